"""What the simulator records besides measurements: labels by box, RadarScenes track ids and detection ids.

Read more in the :ref:`User Guide <simulator-knobs>`.
"""

from __future__ import annotations

import numpy as np

from .._schema import STATIC_LABEL
from ._scenario import ROAD_USER_CLASSES

NEW_TRACK_GAP = 0.5  # s, RadarScenes: a new track id after longer absence


def _box_annotation(truth, measured, users, sensor, margin):
    """The labels of an annotator who marks each road user, scan by scan, by its box enlarged by ``margin`` (m).

    A label follows where a detection was *measured*, not what reflected it:
    an own detection measured beyond the box becomes background, and a
    background detection measured inside the box joins the object.  Only
    scans in which the object has a detection of its own are marked, and
    never while it stands.  Read more in the :ref:`User Guide <simulator-knobs>`.
    """
    scan = truth["scan"]
    angle = measured["azimuth_sc"].astype(float) + sensor["boresight"][scan]
    r = measured["range_sc"].astype(float)
    px, py = sensor["x"][scan] + r * np.cos(angle), sensor["y"][scan] + r * np.sin(angle)
    label, obj = truth["label"].copy(), truth["object"].copy()
    n_scans = len(sensor["t"])
    for index, user in enumerate(users):
        own = truth["object"] == index
        if not own.any():
            continue
        marked = (np.bincount(scan[own], minlength=n_scans) > 0) & ~user.standing(sensor["t"])
        cx, cy, _, _, heading, _ = user.kinematics(sensor["t"])
        c, s = np.cos(heading[scan]), np.sin(heading[scan])
        dx, dy = px - cx[scan], py - cy[scan]
        inside = (
            marked[scan]
            & (np.abs(c * dx + s * dy) <= user.length / 2 + margin)
            & (np.abs(-s * dx + c * dy) <= user.width / 2 + margin)
        )
        leave, join = own & ~inside, inside & (truth["object"] == -1)
        label[leave], obj[leave] = STATIC_LABEL, -1
        label[join], obj[join] = ROAD_USER_CLASSES[user.kind]["label"], index
    return {**truth, "label": label, "object": obj}


def _track_ids(obj, t, sequence):
    """RadarScenes-style track ids: a new id after more than 0.5 s without detection."""
    track = np.full(len(obj), "", dtype=object)
    for index in np.unique(obj[obj >= 0]):
        rows = np.flatnonzero(obj == index)
        rows = rows[np.argsort(t[rows], kind="stable")]
        segment = np.concatenate([[0], np.cumsum(np.diff(t[rows]) > NEW_TRACK_GAP)])
        track[rows] = [f"{sequence:08x}{index:08x}{k:016x}" for k in segment]
    return track


_HEX = np.frombuffer(b"0123456789abcdef", dtype=np.uint8)


def _uuids(n, rng):
    """``n`` random 32-character hexadecimal detection ids, deterministic for ``rng``."""
    words = rng.integers(0, 2**32, size=(n, 4), dtype=np.uint64)
    shifts = np.arange(28, -1, -4, dtype=np.uint64)
    nibbles = (words[:, :, None] >> shifts) & np.uint64(0xF)
    chars = _HEX[nibbles.reshape(n, 32)]
    return np.ascontiguousarray(chars).view("S32").ravel()
