"""``results.json`` of real runs (``reproduce._results``) read and written back byte for byte, old layouts.

The byte-for-byte references are real runs' files in ``tests/data``, written
by the hand-written methods the converter replaced: the default run's
(``results_default_run.json``), a ``--full`` run's as saved after its
experiment #6 (``results_full_run_partial.json``: 100 iterations, no wall
time yet), and one of the first typed layout (``results_3bcbd36_layout.json``:
the default run without the keys added since commit 3bcbd36, which that
commit's reader reads and writes back unchanged).
"""

import json
from pathlib import Path

import pytest

from sklearn_radar.reproduce._budget import Budget
from sklearn_radar.reproduce._experiment_records import SearchRecord
from sklearn_radar.reproduce._results import FigureRecord, RunMeta, RunResults

DATA = Path(__file__).parents[1] / "data"
DEFAULT_RUN = DATA / "results_default_run.json"
OLD_LAYOUT = DATA / "results_3bcbd36_layout.json"
FULL_RUN_PARTIAL = DATA / "results_full_run_partial.json"

# ----------------------------------------------------------------------------- files of real runs


@pytest.mark.parametrize("path", [DEFAULT_RUN, FULL_RUN_PARTIAL], ids=lambda path: path.stem)
def test_a_real_runs_file_is_written_back_byte_for_byte(path):
    text = path.read_text()
    results = RunResults.read(path)
    assert json.dumps(results.to_json_dict(), indent=1) == text
    assert isinstance(results.experiments[2].search, SearchRecord) and results.experiments[1].search is None
    assert results.filter.windows.n_windows == json.loads(text)["filter"]["windows"]["n_windows"]


def test_a_file_of_the_first_typed_layout_loads_and_gains_only_the_default_objective():
    document = json.loads(OLD_LAYOUT.read_text())
    results = RunResults.read(OLD_LAYOUT)
    assert results.statistics is None and results.filter.windows is None and results.meta.repeats == 1
    assert all(r.instance_test is None and r.n_merges_test is None for r in results.experiments.values())
    written = results.to_json_dict()
    assert written["meta"].pop("objective") == "v1"
    assert written == document
    # The old file is the default run's file without the newer keys: every value it has is the same.
    current = RunResults.read(DEFAULT_RUN)
    assert {n: r.v1_test for n, r in current.experiments.items()} == results.v1_test()
    assert current.filter.table_ii == results.filter.table_ii


def test_keys_that_were_absent_stay_absent():
    document = RunResults.read(DEFAULT_RUN).to_json_dict()
    baseline = next(iter(document["baselines"].values()))
    assert "cv_start_from" not in baseline and "repeats" not in document["meta"]
    assert "stage1_params" not in document["experiments"]["2"] and "figures" not in document
    assert "n_sequences" not in document["meta"]["budget"] and "duration" not in document["meta"]["budget"]
    budget = Budget.default().to_json_dict()
    assert list(budget) == ["label", "n_iter", "n_initial_points", "cv_folds"]
    assert FigureRecord(drawn={"scene": "a.png"}, missing="no matplotlib").to_json_dict() == {
        "scene": "a.png",
        "missing": "no matplotlib",
    }


def test_repeats_are_absent_for_one_and_written_otherwise():
    meta = RunResults.read(DEFAULT_RUN).meta
    assert "repeats" not in meta.to_json_dict()
    meta.repeats = 3
    assert list(meta.to_json_dict())[-2:] == ["repeats", "wall_time_s"]
    assert RunMeta.from_json_dict(meta.to_json_dict()).repeats == 3
