"""What a step returns (:class:`Outcome`), and what the figures draw besides ``results.json`` (:class:`RunContext`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class RunContext:
    """The figures' inputs that ``results.json`` does not hold.

    Attributes
    ----------
    sequences : RunSequences
        The data, where the run keeps it (:class:`._sequences.RunSequences`).
    drawn_sequence : int
        The test sequence the figures draw (the first).
    labels : dict of int to ndarray, default={}
        Cluster labels of that sequence, by experiment number.
    tracks : dict of str to ndarray, default={}
        Ids of that sequence's detections from the tracking step: ``"truth"`` (the moving road users) and
        ``"ours"`` (the lead setting's tracks).
    """

    sequences: Any
    drawn_sequence: int
    labels: dict[int, np.ndarray] = field(default_factory=dict)
    tracks: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass(frozen=True)
class Outcome:
    """What a step found: its result (as ``results.json`` holds it) and what the figures draw besides.

    Attributes
    ----------
    result : object
        The step's record (or dict of records), as ``results.json`` holds it.
    summary : str or None
        The line that says it.
    labels : ndarray or None
        An experiment's labels of the test sequence the figures draw.
    models : dict of str to estimator or None
        Fitted models the run saves in its folder, by file name (the classifiers, the learned grouping).
    tracks : dict of str to ndarray or None
        Ids of the drawn test sequence's detections for the tracks figure (:attr:`RunContext.tracks`).
    """

    result: Any
    summary: str | None = None
    labels: np.ndarray | None = None
    models: dict | None = None
    tracks: dict | None = None
