"""Each search of a reproduce run draws from its own seed stream (``_steps.search_seed``)."""

import io
import json
import os
import subprocess
import sys

import numpy as np

from sklearn_radar.experiments import SKLEARN_BASELINES, get_experiment, search_space
from sklearn_radar.reproduce import _steps, reproduce
from sklearn_radar.reproduce._constants import NUMBERS
from sklearn_radar.reproduce._steps import search_seed

KEYS = [str(n) for n in NUMBERS if get_experiment(n).tuned] + list(SKLEARN_BASELINES)


def test_a_search_seed_is_numpys_seed_sequence_of_the_run_seed_and_the_experiment():
    # The documented formula, written out: SeedSequence(run seed, spawn_key=(experiment number,)).
    for run_seed in (0, 1, 2**32 - 1):
        expected = np.random.SeedSequence(run_seed, spawn_key=(3,)).generate_state(1, dtype=np.uint32)[0]
        assert search_seed(run_seed, "3") == int(expected)
    seeds = [search_seed(run_seed, key) for run_seed in range(3) for key in KEYS]
    assert len(set(seeds)) == len(seeds)  # every search of three repeats has its own stream
    assert all(isinstance(s, int) and 0 <= s < 2**32 for s in seeds)


def test_a_search_seed_is_the_same_in_every_process_whatever_pythons_hash_seed():
    code = (
        "import json; from sklearn_radar.reproduce._steps import search_seed; "
        f"print(json.dumps([search_seed(7, key) for key in {KEYS!r}]))"
    )
    here = [search_seed(7, key) for key in KEYS]
    for hash_seed in ("0", "12345"):
        env = {**os.environ, "PYTHONHASHSEED": hash_seed}
        printed = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
        assert json.loads(printed.stdout) == here


def test_two_experiments_with_equal_spaces_draw_different_first_candidates(tiny_folder, tmp_path, monkeypatch):
    assert search_space(3) == search_space(5)  # the box criterion in FCS, filtered: the same four dimensions
    searched = []
    original = _steps._search

    def spy(executor, blocks, ids, estimator, space, folds, start_from, options, callback):
        found = original(executor, blocks, ids, estimator, space, folds, start_from, options, callback)
        searched.append((options["random_state"], found[0].candidates[0]))  # (SearchResult, start score)
        return found

    monkeypatch.setattr(_steps, "_search", spy)
    reproduce(tiny_folder, tmp_path / "out", n_iter=2, experiments="3,5", stream=io.StringIO())
    (seed3, first3), (seed5, first5) = searched
    assert (seed3, seed5) == (search_seed(0, "3"), search_seed(0, "5"))
    assert first3 != first5
