"""The data of a reproduce run, one table per sequence: in this process, or on the workers of a dask cluster.

Stages 0-2 never cross sequences, and every figure of a run is combined
from per-sequence summaries (:mod:`sklearn_radar.metrics._parts`, the
statistics' and the filter evaluation's parts).  So the run never needs
the whole data set in one place:

* in one process each sequence is a table of its own, and a step maps a
  function over the sequences it needs;
* on a cluster each sequence is loaded (a RadarScenes folder: by a worker,
  from the folder, which the workers must see at the same path) or placed
  (simulated data) on a worker once, as the result of a task, so that the
  scheduler computes it again when a worker is lost.  A step's function then
  runs where the sequence is and returns its small summary; the command's
  process holds the summaries, the results and at most the one sequence a
  figure draws.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sklearn.utils import Bunch

from ..datasets import load_radarscenes
from ..datasets._radarscenes import _read_sensors_json, _read_sequences_json, _resolve_data_dir
from ..datasets._simulator import _check_knobs, sequence_seeds, simulate_sequences
from ..metrics import precluster_target
from ..model_selection._sequence_search import SearchData, balanced_blocks
from ..model_selection._split import sequence_sides

__all__ = ["RunSequences", "Sequence"]

#: Columns of the detection table that are not measurements (labels, strings): not part of the estimators' input.
LABEL_COLUMNS = ("uuid", "track_id", "label_id")


@dataclass
class Sequence:
    """One sequence of a run.

    Attributes
    ----------
    id : int
        Sequence number (the ``sequence`` column).
    scenes : Bunch
        Its part of the data Bunch (:func:`~sklearn_radar.datasets.make_scenes`
        or :func:`~sklearn_radar.datasets.load_radarscenes`): ``data``,
        ``target`` (annotated instance, -1 for background), ``groups``,
        ``odometry``, ``sensors``, ``sequences``.
    target : ndarray of int
        The pre-clustered target (:func:`~sklearn_radar.metrics.precluster_target`)
        of its detections.
    """

    id: int
    scenes: Bunch
    target: np.ndarray

    @property
    def X(self):
        """The estimators' input: the measured columns (no labels, no strings: cheap to hash for caching)."""
        data = self.scenes.data
        return data[[c for c in data.columns if c not in LABEL_COLUMNS]]

    def __len__(self):
        return len(self.scenes.data)


def as_sequence(number, scenes):
    """:class:`Sequence` of one sequence's Bunch (its target pre-clustered here: where the data is)."""
    return Sequence(id=int(number), scenes=scenes, target=precluster_target(scenes.data, scenes.target))


#: dask priority of a step's per-sequence tasks (:meth:`RunSequences.map`); a search's candidates have 0.
STEP_PRIORITY = 10

#: make_scenes' default number of road users per sequence (low, high), which the run simulates with.
SIMULATED_OBJECTS = (3, 12)

#: Instance ids of a sequence loaded alone start at 0; the run numbers them ``sequence * INSTANCE_STRIDE + id``,
#: unique across sequences as a whole folder's load numbers them (the filter's error windows name objects by id).
INSTANCE_STRIDE = 2**32


def load_sequence(data_dir, number):
    """Load sequence ``number`` of a RadarScenes folder: on a worker of a cluster, the worker reads it."""
    return as_sequence(number, _unique_instances(number, load_radarscenes(data_dir, sequences=int(number))))


def simulate_sequence(number, seed, duration, difficulty):
    """Sequence ``number`` of :func:`~sklearn_radar.datasets.make_scenes` (its seed given), simulated where it runs.

    Its rows are those of the same sequence in ``make_scenes`` with the
    random state that gave ``seed`` (:func:`sequence_seeds`).
    """
    knobs = _check_knobs(difficulty, None)
    description = f"Simulated RadarScenes-layout sequence {number} of {duration:g} s (difficulty {difficulty!r})."
    scenes = simulate_sequences([number], [seed], duration, SIMULATED_OBJECTS, 1.0, knobs, description)
    return as_sequence(number, _unique_instances(number, scenes))


def _unique_instances(number, scenes):
    """``scenes`` (one sequence, instances numbered from 0) with instance ids unique across sequences."""
    target = np.asarray(scenes.target, dtype=np.int64)
    scenes.target = np.where(target >= 0, int(number) * INSTANCE_STRIDE + target, -1)
    return scenes


def _size(sequence):
    return len(sequence)


def _apply(function, sequence, args):
    return function(sequence, *args)


def _search_block(sequences):
    """The training data of a search block: ``(X, pre-clustered target)`` of each sequence."""
    return [(s.X, s.target) for s in sequences]


class RunSequences:
    """Every sequence of a run, where its tasks run.

    Parameters
    ----------
    ids : list of int
        Sequence numbers, increasing.
    sizes : list of int
        Detections per sequence.
    items : list
        :class:`Sequence` per id; on a cluster a dask future of it.
    cluster : Cluster or None, default=None
    n_jobs : int or None, default=None
        A search's tasks at a time in one process (joblib,
        :meth:`search_data`); ignored on a cluster.
    """

    def __init__(self, ids, sizes, items, cluster=None, n_jobs=None):
        self.ids = [int(i) for i in ids]
        self.sizes = [int(n) for n in sizes]
        self.items = dict(zip(self.ids, items, strict=True))
        self.cluster = cluster
        self.n_jobs = n_jobs

    @classmethod
    def simulated(cls, n_sequences, duration, random_state, difficulty="realistic", cluster=None, n_jobs=None):
        """:func:`~sklearn_radar.datasets.make_scenes`'s sequences, each simulated where it lives (on a worker).

        The same detections as ``make_scenes(n_sequences, duration,
        random_state, difficulty=difficulty)``: each sequence has a seed of
        its own, drawn first.
        """
        numbers = list(range(1, n_sequences + 1))
        calls = [
            (number, int(seed), duration, difficulty)
            for number, seed in zip(numbers, sequence_seeds(random_state, n_sequences), strict=True)
        ]
        return cls._made(numbers, simulate_sequence, calls, cluster, n_jobs)

    @classmethod
    def from_folder(cls, path, cluster=None, n_jobs=None):
        """A RadarScenes folder, loaded sequence by sequence: on a cluster by the workers (same path there)."""
        data_dir = _resolve_data_dir(Path(path)).resolve()  # absolute: the workers' working folder may differ
        _read_sensors_json(data_dir / "sensors.json")  # a malformed folder fails here, before any task
        ids = sorted(_read_sequences_json(data_dir / "sequences.json"))  # a ValueError naming it when empty
        return cls._made(ids, load_sequence, [(str(data_dir), number) for number in ids], cluster, n_jobs)

    @classmethod
    def _made(cls, ids, make, calls, cluster, n_jobs):
        """The sequences ``make(*call)``, here or each as a task's result on a worker (computed again if it is lost)."""
        if cluster is None:
            items = [make(*call) for call in calls]
            return cls(ids, [len(s) for s in items], items, None, n_jobs)
        client = cluster.client
        items = [client.submit(make, *call, pure=False) for call in calls]
        sizes = client.gather([client.submit(_size, item, pure=False) for item in items])
        return cls(ids, sizes, items, cluster, n_jobs)

    @property
    def n_detections(self):
        """Detections in all."""
        return sum(self.sizes)

    def size(self, ids):
        """Detections of the sequences ``ids``."""
        sizes = dict(zip(self.ids, self.sizes, strict=True))
        return sum(sizes[i] for i in ids)

    def split(self, random_state=None):
        """Training and test sequence ids: :func:`~sklearn_radar.model_selection.sequence_train_test_split`'s split.

        Raises
        ------
        ValueError
            With fewer than two sequences.
        """
        if len(self.ids) < 2:
            raise ValueError(f"the data must hold at least 2 sequences to split by sequence, got {len(self.ids)}")
        side = sequence_sides(np.asarray(self.sizes), 0.5, random_state)
        ids = np.asarray(self.ids)
        return [int(i) for i in ids[side == 0]], [int(i) for i in ids[side == 1]]

    def map(self, function, ids=None, *args):
        """``function(sequence, *args)`` for each sequence of ``ids`` (None: all), in order, where it lives.

        ``function`` must be a module-level function (the workers import
        it) and should return a small summary.
        """
        ids = self.ids if ids is None else [int(i) for i in ids]
        if self.cluster is None:
            # One after the other: a step's work per sequence is numpy-heavy, and shipping sequences to
            # joblib's processes would cost as much as it saves on 2 cores.
            return [function(self.items[i], *args) for i in ids]
        client = self.cluster.client
        # Ahead of the searches' queued candidates: the run's steps wait for these, one after the other.
        futures = [
            client.submit(_apply, function, self.items[i], args, pure=False, priority=STEP_PRIORITY) for i in ids
        ]
        return client.gather(futures)

    def fetch(self, number):
        """Sequence ``number`` here (from its worker on a cluster), e.g. to draw it."""
        item = self.items[int(number)]
        return item.result() if self.cluster is not None else item

    def search_data(self, ids):
        """The sequences ``ids`` as a search's training data (:class:`._search.SearchData`), where they live.

        On a cluster they are grouped into one block per worker thread,
        balanced in detections, each block built on a worker from its
        sequences.
        """
        ids = sorted(int(i) for i in ids)
        if self.cluster is None:
            return SearchData([_search_block([self.items[i]]) for i in ids], [[i] for i in ids], None, self.n_jobs)
        positions = balanced_blocks([self.size([i]) for i in ids], self.cluster.n_threads)
        client = self.cluster.client
        blocks = [client.submit(_search_block, [self.items[ids[p]] for p in block], pure=False) for block in positions]
        return SearchData(blocks, [[ids[p] for p in block] for block in positions], self.cluster, self.n_jobs)
