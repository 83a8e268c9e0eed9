"""Fixtures of the datasets tests."""

import pytest

from sklearn_radar.datasets._radarscenes_writer import write_radarscenes

from ._radarscenes_data import make_test_bunch


@pytest.fixture
def written(tmp_path):
    """A written copy of the test bunch: (data folder, bunch)."""
    bunch = make_test_bunch()
    return write_radarscenes(bunch, tmp_path / "data"), bunch
