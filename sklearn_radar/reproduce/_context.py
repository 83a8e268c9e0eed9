"""What a reproduce run keeps beside its results: where the data is, the split, labels and intermediate tables."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(slots=True, kw_only=True)
class RunContext:
    """The in-memory state of a run that ``results.json`` does not hold; the figures are drawn from it.

    Every field is declared here: a step that needs to hand something to a
    later step or to a figure adds a field, it does not invent a key.

    Attributes
    ----------
    sequences : RunSequences
        The data, one table per sequence, where the run's tasks run
        (:class:`._sequences.RunSequences`: here, or on the cluster's
        workers).
    train, test : list of int
        The training and the test sequences.
    cache : str or None, default=None
        Pipeline cache folder of the run.
    labels : dict of int to ndarray, default={}
        Cluster labels of the test sequence the figures draw (the first),
        by experiment number.
    filter_grids : dict of str to Bunch or None, default=None
        :func:`~sklearn_radar.evaluation.filter_grid` per coordinate system
        (``"frame"``, ``"car"``), once the filter evaluation ran.
    best_stage1 : dict or None, default=None
        The tuned setting (``cluster__`` parameters) of the best stage-1
        method, #8 (:data:`~sklearn_radar.reproduce._constants.BEST_STAGE1`),
        once it ran: #10, #11, the stage-2 experiments and the filter effect
        reuse it.
    best_stage1_repeats : list of dict or None, default=None
        The same for each repeat of a run with several (``meta.repeats``):
        repeat ``k`` of #10, #11 and stage 2 builds on repeat ``k`` of #8.
    search_data : SearchData or None, default=None
        The training half per sequence, placed where the searches' tasks
        run (:mod:`._search`), once the first search ran.
    prepared : dict, default={}
        The same with stage 0 applied, by stage 0's hash: searches with the
        same stage 0 (repeats, experiments on the same input) share it.
    pending : dict, default={}
        Searches started ahead on a dask cluster, by step (and baseline):
        ``{repeat: concurrent future}``.
    """

    sequences: Any
    train: list[int]
    test: list[int]
    cache: str | None = None
    labels: dict[int, np.ndarray] = field(default_factory=dict)
    filter_grids: dict[str, Any] | None = None
    best_stage1: dict[str, Any] | None = None
    best_stage1_repeats: list[dict[str, Any]] | None = None
    search_data: Any = None
    prepared: dict[str, Any] = field(default_factory=dict)
    pending: dict[Any, Any] = field(default_factory=dict)

    @property
    def drawn_sequence(self):
        """The test sequence the figures draw (the first), and whose labels :attr:`labels` keeps."""
        return self.test[0]


__all__ = ["RunContext"]
