"""What the figures of a reproduce run draw besides ``results.json``: one test sequence and the labels of it."""

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
    """

    sequences: Any
    drawn_sequence: int
    labels: dict[int, np.ndarray] = field(default_factory=dict)
