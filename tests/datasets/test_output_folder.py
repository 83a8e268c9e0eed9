"""Tests of write_radarscenes' output folder: what it refuses to replace, and atomic replacement."""

import pytest

from sklearn_radar.datasets._radarscenes_reader import load_radarscenes
from sklearn_radar.datasets._radarscenes_writer import write_radarscenes

from ._radarscenes_data import assert_bunch_equal, failing_on_second_call, make_test_bunch, subset


def test_existing_folder_is_kept_without_overwrite(written):
    root, _ = written
    before = sorted(p.relative_to(root) for p in root.rglob("*"))
    with pytest.raises(FileExistsError, match="overwrite"):
        write_radarscenes(subset(make_test_bunch(), [2]), root)
    assert sorted(p.relative_to(root) for p in root.rglob("*")) == before


def test_overwrite_replaces_existing_folder(written):
    root, _ = written
    expected = subset(make_test_bunch(), [2])
    write_radarscenes(expected, root, overwrite=True)
    assert_bunch_equal(load_radarscenes(root), expected)
    assert not (root / "sequence_5").exists()
    assert [p.name for p in root.parent.iterdir()] == ["data"]


def test_failed_overwrite_keeps_old_content(written, monkeypatch):
    root, bunch = written
    failing_on_second_call(monkeypatch)
    with pytest.raises(OSError, match="simulated"):
        write_radarscenes(make_test_bunch(seed=1), root, overwrite=True)
    assert_bunch_equal(load_radarscenes(root), bunch)
    assert [p.name for p in root.parent.iterdir()] == ["data"]


def test_writing_onto_a_file_says_it_is_a_file(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("mine")
    with pytest.raises(FileExistsError, match="is a file"):
        write_radarscenes(make_test_bunch(), afile)
    assert afile.read_text() == "mine"
