"""Fixtures shared by several test modules."""

import pytest

from sklearn_radar.datasets import make_scenes, write_radarscenes


@pytest.fixture(scope="session")
def tiny_folder(tmp_path_factory):
    """A tiny simulated RadarScenes folder (4 sequences of 4 s), written once per session; tests only read it."""
    path = tmp_path_factory.mktemp("data") / "tiny"
    write_radarscenes(make_scenes(n_sequences=4, duration=4.0, random_state=3), path)
    return path
