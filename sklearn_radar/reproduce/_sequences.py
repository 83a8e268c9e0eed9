"""The data of a reproduce run, one table per sequence, made and kept where the run's executor runs its tasks.

A step's function runs where each sequence is and returns a small summary (:ref:`contributing-runner`); a
RadarScenes folder must be at the same path on a cluster's workers.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sklearn.utils import Bunch

from .._executor import LocalExecutor
from ..datasets import load_radarscenes
from ..datasets._presets import _check_knobs
from ..datasets._radarscenes_reader import _read_sensors_json, _read_sequences_json, _resolve_data_dir
from ..datasets._simulator import sequence_seeds, simulate_sequences
from ..metrics import precluster_target
from ..model_selection._sequence_search import SearchData
from ..model_selection._split import sequence_sides

#: Columns of the detection table that are not measurements (labels, strings): not part of the estimators' input.
LABEL_COLUMNS = ("uuid", "track_id", "label_id")


@dataclass
class Sequence:
    """One sequence of a run: its ``id``, its part of the data Bunch (``scenes``) and its pre-clustered ``target``."""

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


#: make_scenes' default number of road users per sequence (low, high), which the run simulates with.
SIMULATED_OBJECTS = (3, 12)

#: Instance ids of a sequence loaded alone start at 0; the run numbers them ``sequence * INSTANCE_STRIDE + id``,
#: unique across sequences as a whole folder's load numbers them (the filter's error windows name objects by id).
INSTANCE_STRIDE = 2**32


def load_sequence(data_dir, number):
    """Load sequence ``number`` of a RadarScenes folder: on a worker of a cluster, the worker reads it."""
    return as_sequence(number, _unique_instances(number, load_radarscenes(data_dir, sequences=int(number))))


def simulate_sequence(number, seed, duration, difficulty):
    """Sequence ``number`` of :func:`~sklearn_radar.datasets.make_scenes` with its ``seed``, simulated where it runs."""
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


def _search_block(*sequences):
    """The training data of a search block: ``(X, pre-clustered target)`` of each sequence."""
    return [(s.X, s.target) for s in sequences]


class RunSequences:
    """Every sequence of a run (``ids``, ``sizes`` in detections), the executor's handle of each where it keeps them."""

    def __init__(self, ids, sizes, items, executor):
        self.ids = [int(i) for i in ids]
        self.sizes = [int(n) for n in sizes]
        self.items = dict(zip(self.ids, items, strict=True))
        self.executor = executor

    @classmethod
    def simulated(cls, n_sequences, duration, random_state, difficulty="realistic", executor=None):
        """:func:`~sklearn_radar.datasets.make_scenes`'s detections, each sequence simulated where it lives."""
        numbers = list(range(1, n_sequences + 1))
        calls = [
            (number, int(seed), duration, difficulty)
            for number, seed in zip(numbers, sequence_seeds(random_state, n_sequences), strict=True)
        ]
        return cls._made(numbers, simulate_sequence, calls, executor)

    @classmethod
    def from_folder(cls, path, executor=None):
        """A RadarScenes folder, loaded sequence by sequence where they live (on a cluster: same path there)."""
        data_dir = _resolve_data_dir(Path(path)).resolve()  # absolute: the workers' working folder may differ
        _read_sensors_json(data_dir / "sensors.json")  # a malformed folder fails here, before any task
        ids = sorted(_read_sequences_json(data_dir / "sequences.json"))  # a ValueError naming it when empty
        return cls._made(ids, load_sequence, [(str(data_dir), number) for number in ids], executor)

    @classmethod
    def _made(cls, ids, make, calls, executor):
        executor = executor or LocalExecutor()
        items = [executor.place(make, *call) for call in calls]
        sizes = executor.gather([executor.submit(_size, item) for item in items])
        return cls(ids, sizes, items, executor)

    @property
    def n_detections(self):
        """Detections in all."""
        return sum(self.sizes)

    def size(self, ids):
        """Detections of the sequences ``ids``."""
        sizes = dict(zip(self.ids, self.sizes, strict=True))
        return sum(sizes[i] for i in ids)

    def split(self, random_state=None):
        """Training and test ids by :func:`~sklearn_radar.model_selection.sequence_train_test_split`'s rule."""
        if len(self.ids) < 2:
            raise ValueError(f"the data must hold at least 2 sequences to split by sequence, got {len(self.ids)}")
        side = sequence_sides(np.asarray(self.sizes), 0.5, random_state)
        ids = np.asarray(self.ids)
        return [int(i) for i in ids[side == 0]], [int(i) for i in ids[side == 1]]

    def map(self, function, ids=None, *args, executor=None):
        """Module-level ``function(sequence, *args)`` of each sequence of ``ids`` (None: all), in order, where it is."""
        executor = executor or self.executor
        ids = self.ids if ids is None else [int(i) for i in ids]
        return executor.gather([executor.submit(_apply, function, self.items[i], args) for i in ids])

    def fetch(self, number):
        """Sequence ``number`` here (from its worker on a cluster), e.g. to draw it."""
        return self.executor.fetch(self.items[int(number)])

    def search_data(self, ids, executor=None):
        """The sequences ``ids`` as a search's ``SearchData``, in the executor's blocks, each built where it lives."""
        executor = executor or self.executor
        ids = sorted(int(i) for i in ids)
        positions = executor.blocks([self.size([i]) for i in ids])
        blocks = [self.executor.place(_search_block, *[self.items[ids[p]] for p in block]) for block in positions]
        return SearchData(blocks, [[ids[p] for p in block] for block in positions], executor)
