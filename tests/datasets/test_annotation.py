"""Tests of what the simulator records besides measurements: box labels, track ids and detection ids."""

import numpy as np

from sklearn_radar._schema import STATIC_LABEL
from sklearn_radar.datasets._annotation import _box_annotation, _track_ids, _uuids
from sklearn_radar.datasets._scenario import RoadUser

from .test_radarscenes_preset import _straight_road


def test_track_id_changes_after_more_than_half_a_second_of_absence():
    t = np.array([0.0, 0.06, 0.7, 0.76, 1.2, 0.3])
    obj = np.array([0, 0, 0, 0, 0, -1])
    track = _track_ids(obj, t, sequence=1)
    assert track[0] == track[1] != track[2] == track[3] == track[4]
    assert track[5] == ""


def test_uuids_are_hexadecimal_and_deterministic():
    a = _uuids(5, np.random.default_rng(1))
    b = _uuids(5, np.random.default_rng(1))
    np.testing.assert_array_equal(a, b)
    assert all(len(u) == 32 and int(u, 16) >= 0 for u in a)


def test_box_annotation_labels_what_is_measured_inside_the_enlarged_box():
    # A standing-still 4 m x 2 m car centred at (20, 0), heading 0; one sensor at the origin looking along x.
    road = _straight_road()
    user = RoadUser(kind="car", length=4.0, width=2.0, road=road, s0=20.0, speed=0.0, d0=0.0)
    sensor = {"x": np.zeros(1), "y": np.zeros(1), "boresight": np.zeros(1), "t": np.zeros(1)}
    points = np.array([[21.0, 0.0], [20.0, 1.3], [18.1, 0.5], [25.0, 0.0]])  # own, own, background, background
    truth = {
        "scan": np.zeros(4, dtype=int),
        "label": np.array([0, 0, STATIC_LABEL, STATIC_LABEL]),
        "object": np.array([0, 0, -1, -1]),
    }
    measured = {
        "range_sc": np.hypot(points[:, 0], points[:, 1]).astype(np.float32),
        "azimuth_sc": np.arctan2(points[:, 1], points[:, 0]).astype(np.float32),
    }
    labelled = _box_annotation(truth, measured, [user], sensor, margin=0.2)
    # Half width 1 + 0.2 = 1.2 < 1.3: the second leaves; half length 2 + 0.2 = 2.2 > 1.9: the third joins.
    np.testing.assert_array_equal(labelled["object"], [0, -1, 0, -1])
    np.testing.assert_array_equal(labelled["label"], [0, STATIC_LABEL, 0, STATIC_LABEL])
    wider = _box_annotation(truth, measured, [user], sensor, margin=0.35)
    np.testing.assert_array_equal(wider["object"], [0, 0, 0, -1])
