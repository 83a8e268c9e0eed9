"""How well LinkClustering's threshold tuning chooses: the PQ of every setting, out of fold and on the test half.

LinkClustering tunes (objectness threshold, link threshold, min cluster size) on its out-of-fold predictions of the
training half: the setting of the grid (972 of them) with the best PQ.  This script shows what that choice costs on
the test half.  For each preset and seed, on the data and split of ``experiment_learned.py`` (``bench.load``):

* the **out-of-fold surface**: the PQ of every setting on the training half, from the out-of-fold probabilities
  the fit tunes on (captured from the fit, computed by the library's ``tune_surface``);
* the **test surface**: the PQ of every setting on the test half, from the fitted classifiers' probabilities (the
  same function; its value at the fitted setting is checked against ``predict``'s labels);
* the test PQ of the setting each **selection rule** picks from the out-of-fold surface only:

  - ``argmax``: the best setting (what ``fit`` does);
  - ``smoothed``: the best setting of the surface averaged over each setting's neighbours in the grid (a 3 x 3 x 3
    box of grid steps, cut at the grid's ends), which prefers a setting whose neighbours score well too;

  and, as a diagnostic never used to choose, the best test PQ of the grid.

Each (preset, seed) is saved as ``benchmarks/results/threshold_selection/<preset>_seed<seed>.json``; ``--summary``
prints per preset the test PQ of each rule and the paired differences (mean ± 2 SE over seeds).

Run (one core, niced; 2-4 min per preset and seed)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_threshold_selection.py --data radarscenes --seeds 0 1
    python benchmarks/experiment_threshold_selection.py --summary
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.ndimage import uniform_filter
from threadpoolctl import threadpool_limits

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_link_clustering as bench  # noqa: E402
from experiment_learned import _mean_2se  # noqa: E402

from sklearn_radar._validation import read_columns  # noqa: E402
from sklearn_radar.cluster import LinkClustering  # noqa: E402
from sklearn_radar.cluster import _link_clustering as module  # noqa: E402
from sklearn_radar.cluster._link_clustering import (  # noqa: E402
    CANDIDATE_OBJECTNESS,
    LINK_READS,
    _sequences,
)
from sklearn_radar.cluster._link_training import best_of, tune_surface  # noqa: E402
from sklearn_radar.metrics import panoptic_quality  # noqa: E402

RESULTS = HERE / "results" / "threshold_selection"
RULES = ("argmax", "smoothed")


def smoothed(surface):
    """The surface averaged over a 3 x 3 x 3 box of grid steps (``nearest`` at the ends: an end counts twice)."""
    return uniform_filter(surface, size=3, mode="nearest")


def out_of_fold_surface(model, train, y_train):
    """Fit ``model`` and return the out-of-fold surface its tuning saw (captured from the fit)."""
    captured = {}
    tune = module.tune

    def capture(*args, **kwargs):
        captured["surface"] = tune_surface(*args, **kwargs)
        return best_of(captured["surface"], args[4])

    module.tune = capture
    try:
        model.fit(train, y_train)
    finally:
        module.tune = tune
    return captured["surface"]


def test_surface(model, test, y_test):
    """The PQ of every setting of the model's grids on ``test``, from the fitted classifiers' probabilities."""
    _, c = read_columns(model, test, LINK_READS, reset=False)
    sequences = _sequences(c, model.causal)
    grids = model._grids()
    floor = min(CANDIDATE_OBJECTNESS, min(grids[1]))  # the pairs of every objectness threshold, as fit forms them
    objectness, pairs, links = [], [], []
    for s in sequences:
        p, i, j, link = model._probabilities(s, floor)
        objectness.append(p)
        pairs.append((i, j))
        links.append(link)
    return tune_surface(sequences, objectness, pairs, links, grids, c, y_test, model.window)


def run(preset, seed, options):
    """The surfaces and each rule's choice on one preset and seed."""
    (train, y_train), (test, y_test) = bench.load(preset, seed, options.n_sequences, options.duration)
    model = LinkClustering(n_jobs=options.threads)
    start = time.perf_counter()
    with threadpool_limits(options.threads):
        oof = out_of_fold_surface(model, train, y_train)
        fit_s = time.perf_counter() - start
        on_test = test_surface(model, test, y_test)
        labels = model.predict(test)
    grids = model._grids()
    fitted = (model.link_threshold_, model.objectness_threshold_, model.min_cluster_size_)
    pq = panoptic_quality(y_test, labels, times=test["t"].to_numpy(), groups=test["sequence"].to_numpy()).pq
    index = _index(fitted, grids)
    if best_of(oof, grids)[0] != fitted or not math.isclose(on_test[index], pq, abs_tol=1e-9):
        raise RuntimeError(f"{preset} seed {seed}: the surfaces disagree with the fit ({fitted}, PQ {pq})")
    record = {"preset": preset, "seed": seed, "n_sequences": options.n_sequences, "duration": options.duration}
    record["fit_s"] = fit_s
    record["grids"] = [list(map(float, g)) for g in grids]
    record["oof"] = oof.tolist()
    record["test"] = on_test.tolist()
    for rule, surface in (("argmax", oof), ("smoothed", smoothed(oof))):
        setting, _ = best_of(surface, grids)
        record[rule] = {"setting": list(map(float, setting)), "test_pq": float(on_test[_index(setting, grids)])}
    setting, best = best_of(on_test, grids)
    record["test_best"] = {"setting": list(map(float, setting)), "test_pq": best}
    return record


def _index(setting, grids):
    """Index into a surface of the setting ``(link, objectness, size)``."""
    link, gate, size = setting
    link_grid, objectness_grid, size_grid = grids
    return list(objectness_grid).index(gate), list(link_grid).index(link), list(size_grid).index(size)


def summary(directory):
    """Print per preset each rule's test PQ per seed and the paired differences."""
    records = [json.loads(p.read_text(encoding="utf-8")) for p in sorted(directory.glob("*_seed*.json"))]
    presets = dict.fromkeys(r["preset"] for r in records)
    for preset in presets:
        part = sorted((r for r in records if r["preset"] == preset), key=lambda r: r["seed"])
        print(f"\n{preset} ({part[0]['n_sequences']} x {part[0]['duration']:g} s): test PQ of each rule's choice")
        print("seed  argmax  smoothed  test best   argmax setting -> smoothed setting (link, objectness, size)")
        for r in part:
            print(
                f"{r['seed']:>4}  {r['argmax']['test_pq']:.3f}   {r['smoothed']['test_pq']:.3f}     "
                f"{r['test_best']['test_pq']:.3f}     {r['argmax']['setting']} -> {r['smoothed']['setting']}"
            )
        argmax = np.array([r["argmax"]["test_pq"] for r in part])
        print(f"smoothed - argmax:  {_mean_2se([r['smoothed']['test_pq'] for r in part] - argmax)} (mean ± 2 SE)")
        print(f"test best - argmax: {_mean_2se([r['test_best']['test_pq'] for r in part] - argmax)} (diagnostic)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    presets = ["easy", "realistic", "radarscenes"]
    parser.add_argument("--data", nargs="+", default=presets, choices=presets)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--n-sequences", type=int, default=8)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--results", type=Path, default=RESULTS)
    parser.add_argument("--summary", action="store_true", help="only print the tables of the saved results")
    options = parser.parse_args(argv)
    if not options.summary:
        options.results.mkdir(parents=True, exist_ok=True)
        for preset in options.data:
            for seed in options.seeds:
                record = run(preset, seed, options)
                path = options.results / f"{preset}_seed{seed}.json"
                path.write_text(json.dumps(record), encoding="utf-8")
                print(f"{preset} seed {seed}: {record['argmax']} {record['smoothed']} {record['test_best']}")
    summary(options.results)


if __name__ == "__main__":
    main()
