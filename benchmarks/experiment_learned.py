"""LinkClustering against the object experiment and the best PQ-tuned baseline over seeds (issue 42's offline goal).

For each preset and seed, on the same data and split: ``make_scenes`` (``--n-sequences`` x ``--duration`` s),
``sequence_train_test_split(random_state=seed)``, target ``metrics.precluster_target``, test half scored with
``metrics.panoptic_quality`` and ``metrics.instance_errors`` (0.5 s windows, the times and sequences of the front's
output), three methods:

* ``learned``: :class:`~sklearn_radar.cluster.LinkClustering` with its defaults, fitted on the training half through
  the front (``FrameTransform(frame="frame")``, ``DopplerDensityFilter()``), as ``bench_link_clustering.py`` loads it;
* ``objects``: the object experiment, tuned for PQ by ``ablation_object_level.py``'s ``run_one`` (Bayesian search,
  ``--n-iter`` iterations, folds by sequence);
* ``baseline``: of the ablation's per-sequence scikit-learn baselines (``SequenceDBSCAN``, ``SequenceHDBSCAN``,
  ``SequenceHDBSCAN narrow``), each tuned the same way, the one with the best cross-validated PQ on the training
  half (never chosen on the test half).

Fit seconds are ``fit`` of LinkClustering (classifiers, out-of-fold tuning) and the whole search of the others
(their search includes scoring the test half once); predict ms per scan (one sensor's cycle) is the test half's
labelling with the front excluded, batch-amortised.  Each (preset, seed) is saved as
``benchmarks/results/learned_<preset>_seed<seed>.json`` as soon as it is done; ``--summary`` reads every saved file,
prints per preset the test PQ per method, the paired differences ``learned - objects`` and
``learned - max(objects, baseline)`` (mean ± 2 SE over seeds), and the error anatomy (sums over seeds), and writes
``benchmarks/results/learned_rows.csv`` (one row per preset, seed and method).

``--method learned_causal`` runs the causal learned grouping alone on the same data and split:
``LinkClustering(causal=True)`` with the main job's causal boosting iterations fitted on the training half through a
front whose filter is causal too (``--max-links``, ``--max-leaf-nodes`` and ``--max-depth`` set its
``max_links_per_detection``, ``max_leaf_nodes`` and ``max_depth``; by default every pair, 31 leaves and any depth,
where the main job's model has 16 links and depth 6: ``--max-links 16 --max-depth 6`` is it), the test half labelled
by its ``predict`` (what ``OnlinePipeline`` streams), saved as ``learned_causal_<preset>_seed<seed>.json``;
``--summary`` then sets it beside the saved offline rows of the same seeds.  The object experiment's saved rows hold
its stage-2 setting only (not its stage 1), so its causal score is
not recomputed here: the main job's learned section has it, with the sliding-window baseline.

Run (one core, niced; several minutes per preset and seed on a busy 2-core machine)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_learned.py --data easy realistic radarscenes --seeds 0 1 2
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_learned.py --method learned_causal --data realistic
    python benchmarks/experiment_learned.py --summary
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import ablation_object_level as ablation  # noqa: E402
import bench_link_clustering as bench  # noqa: E402

from sklearn_radar.cluster import LinkClustering  # noqa: E402
from sklearn_radar.metrics import instance_errors, panoptic_quality  # noqa: E402
from sklearn_radar.metrics._errors import FALSE_CAUSES, MISSED_CAUSES  # noqa: E402
from sklearn_radar.reproduce._learned import LEARNED_CAUSAL_PARAMS  # noqa: E402

RESULTS = HERE / "results"
METHODS = ("learned", "objects", "baseline")


def _scores(name, labels, y_test, times, groups):
    pq = panoptic_quality(y_test, labels, times=times, groups=groups)
    errors = instance_errors(y_test, labels, times=times, groups=groups)
    return {"method": name, "pq": pq.pq, "recall": pq.recall, "precision": pq.precision, "errors": errors}


def run(preset, seed, options):
    """The three methods' records on one preset and seed."""
    (train, y_train), (test, y_test) = bench.load(preset, seed, options.n_sequences, options.duration)
    times, groups = test["t"].to_numpy(), test["sequence"].to_numpy()
    n_scans = test.groupby(["sequence", "sensor_id", "timestamp"]).ngroups
    learned = _learned_record("learned", LinkClustering(n_jobs=options.threads), train, y_train, test, y_test, options)
    wanted = ("objects (stage 1)", "objects", *ablation.BASELINES)
    chosen = [v for v in ablation.variants() if v.name in wanted]
    args = argparse.Namespace(
        n_sequences=options.n_sequences,
        duration=options.duration,
        n_iter=options.n_iter,
        cv_folds=3,
        keep_labels=True,
    )
    with threadpool_limits(options.threads):
        found = ablation.run_one(preset, seed, chosen, args)
    best = max(ablation.BASELINES, key=lambda name: found[name]["cv_pq"])  # chosen on the training half only
    records = [learned]
    for method, name in (("objects", "objects"), ("baseline", best)):
        record = found[name]
        if len(record["test_labels"]) != len(y_test):
            raise RuntimeError(f"{name}: {len(record['test_labels'])} test labels for {len(y_test)} detections")
        scored = _scores(method, record["test_labels"], y_test, times, groups)
        if not math.isclose(scored["pq"], record["pq"], abs_tol=1e-9):  # the same rows in the same order
            raise RuntimeError(f"{name}: PQ {scored['pq']} from the kept labels, {record['pq']} in the ablation")
        seconds = record["seconds"] + (found["objects (stage 1)"]["seconds"] if name == "objects" else 0.0)
        scored.update(
            variant=name,
            cv_pq=record["cv_pq"],
            fit_s=seconds,
            predict_ms_per_scan=1e3 * record["predict_s"] / n_scans,
            params=record["params"],
        )
        records.append(scored)
    for record in records:
        record.update(preset=preset, seed=seed, n_sequences=options.n_sequences, duration=options.duration)
    return records


def run_causal(preset, seed, options):
    """The causal learned grouping's record on one preset and seed (the split of :func:`run`)."""
    (train, y_train), (test, y_test) = bench.load(preset, seed, options.n_sequences, options.duration, causal=True)
    model = LinkClustering(
        causal=True,
        max_iter=LEARNED_CAUSAL_PARAMS["link__max_iter"],
        max_links_per_detection=options.max_links,
        max_leaf_nodes=options.max_leaf_nodes,
        max_depth=options.max_depth,
        n_jobs=options.threads,
    )
    record = _learned_record("learned_causal", model, train, y_train, test, y_test, options)
    record.update(preset=preset, seed=seed, n_sequences=options.n_sequences, duration=options.duration)
    return [record]


def _learned_record(method, model, train, y_train, test, y_test, options):
    """Fit ``model`` (a LinkClustering) on the training half, label the test half: its scores, times and thresholds."""
    times, groups = test["t"].to_numpy(), test["sequence"].to_numpy()
    n_scans = test.groupby(["sequence", "sensor_id", "timestamp"]).ngroups
    start = time.perf_counter()
    with threadpool_limits(options.threads):
        model.fit(train, y_train)
        fit_s = time.perf_counter() - start
        start = time.perf_counter()
        labels = model.predict(test)
        predict_s = time.perf_counter() - start
    record = _scores(method, labels, y_test, times, groups)
    record.update(
        variant="LinkClustering(causal=True)" if model.causal else "LinkClustering",
        cv_pq=model.cv_score_,
        fit_s=fit_s,
        predict_ms_per_scan=1e3 * predict_s / n_scans,
        params={
            "link_threshold": model.link_threshold_,
            "objectness_threshold": model.objectness_threshold_,
            "min_cluster_size": model.min_cluster_size_,
        },
    )
    return record


def causal_summary(directory):
    """The causal learned grouping beside the offline rows of the same presets and seeds."""
    records = []
    for path in sorted(directory.glob("learned_causal_*_seed*.json")):
        records.extend(json.loads(path.read_text(encoding="utf-8")))
    if not records:
        return
    causal = pd.DataFrame([_flat(r) for r in records])
    for preset, part in causal.groupby("preset", sort=False):
        rows = []
        for seed in sorted(part.seed):
            offline = directory / f"learned_{preset}_seed{seed}.json"
            saved = (
                {r["method"]: r for r in json.loads(offline.read_text(encoding="utf-8"))} if offline.exists() else {}
            )
            own = part[part.seed == seed].iloc[0]
            rows.append(
                {
                    "seed": seed,
                    "learned_causal": own.pq,
                    **{method: saved[method]["pq"] for method in METHODS if method in saved},
                    "missed_causal": own.missed,
                    "missed_learned": saved["learned"]["errors"]["missed"] if "learned" in saved else np.nan,
                }
            )
        table = pd.DataFrame(rows).set_index("seed")
        print(f"\n{preset}: the causal learned grouping (test PQ) beside the offline rows of the same seeds")
        print(table.round(3).to_string())
        if "learned" in table:
            print(
                f"learned_causal - learned (offline): {_mean_2se(table.learned_causal - table.learned)} (mean ± 2 SE)"
            )


def _flat(record):
    row = {key: value for key, value in record.items() if key not in ("errors", "params")}
    row.update(record["errors"])
    row["params"] = json.dumps(record["params"])
    return row


def _mean_2se(values):
    values = np.asarray(values, dtype=np.float64)
    se = values.std(ddof=1) / math.sqrt(len(values)) if len(values) > 1 else float("nan")
    return f"{values.mean():+.3f} ± {2 * se:.3f}"


def summary(directory):
    """Print the tables of every saved (preset, seed) and write the rows as CSV; returns the DataFrame."""
    records = []
    for path in sorted(directory.glob("learned_*_seed*.json")):
        if not path.name.startswith("learned_causal_"):
            records.extend(json.loads(path.read_text(encoding="utf-8")))
    if not records:
        print(f"no results in {directory}")
        return None
    rows = pd.DataFrame([_flat(r) for r in records])
    rows.to_csv(directory / "learned_rows.csv", index=False)
    for preset, part in rows.groupby("preset", sort=False):
        pq = part.pivot(index="seed", columns="method", values="pq")[list(METHODS)]
        seeds = ", ".join(str(s) for s in pq.index)
        print(f"\n{preset}: seeds {seeds} ({len(pq)}), test PQ")
        print(pq.round(3).to_string())
        baseline = part[part.method == "baseline"].set_index("seed")["variant"]
        print("best baseline by cv PQ: " + ", ".join(f"seed {s}: {v}" for s, v in baseline.items()))
        print(f"learned - objects:                 {_mean_2se(pq.learned - pq.objects)} (mean ± 2 SE)")
        best = np.maximum(pq.objects, pq.baseline)
        print(f"learned - max(objects, baseline):  {_mean_2se(pq.learned - best)} (mean ± 2 SE)")
        columns = ["pq", "recall", "precision", "n_true", "matched", "missed", *MISSED_CAUSES]
        columns += ["n_pred", "false", *FALSE_CAUSES, "median_size_missed", "fit_s", "predict_ms_per_scan"]
        means = ("pq", "recall", "precision", "fit_s", "predict_ms_per_scan")
        sums = part.groupby("method")[columns].agg({c: "mean" if c in means else "sum" for c in columns})
        sums["median_size_missed"] = part.groupby("method")["median_size_missed"].median()
        print("error anatomy on the test halves (counts summed over seeds; PQ, times: means):")
        print(sums.loc[list(METHODS)].round(3).T.to_string())
        missed = sums["missed"]
        print(f"missed segments, learned against objects: {missed['learned'] / missed['objects'] - 1:+.1%}")
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    presets = ["easy", "realistic", "radarscenes"]
    parser.add_argument("--data", nargs="+", default=presets, choices=presets)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--n-iter", type=int, default=20, help="search iterations of the object experiment, baselines")
    parser.add_argument("--threads", type=int, default=1, help="threads of the classifiers and the searches")
    parser.add_argument("--results", type=Path, default=RESULTS, help="folder of the saved rows")
    parser.add_argument("--summary", action="store_true", help="only print the tables of the saved rows")
    parser.add_argument(
        "--method",
        choices=["offline", "learned_causal"],
        default="offline",
        help="the three offline methods, or the causal learned grouping alone",
    )
    parser.add_argument(
        "--max-links",
        type=lambda text: None if text == "none" else int(text),
        default=None,
        help="max_links_per_detection of the causal learned grouping ('none', the default: every pair)",
    )
    parser.add_argument(
        "--max-leaf-nodes", type=int, default=31, help="max_leaf_nodes of the causal learned grouping's classifiers"
    )
    parser.add_argument(
        "--max-depth",
        type=lambda text: None if text == "none" else int(text),
        default=None,
        help="max_depth of the causal learned grouping's classifiers ('none', the default: as the leaves allow)",
    )
    options = parser.parse_args(argv)
    if not options.summary:
        options.results.mkdir(parents=True, exist_ok=True)
        for preset in options.data:
            for seed in options.seeds:
                print(f"{preset} seed {seed}: {options.n_sequences} x {options.duration:g} s", flush=True)
                records = (run_causal if options.method == "learned_causal" else run)(preset, seed, options)
                for r in records:
                    print(
                        f"  {r['method']:<9} {r['variant']:<24} test PQ {r['pq']:.3f} (cv {r['cv_pq']:.3f}) "
                        f"missed {r['errors']['missed']} false {r['errors']['false']} fit {r['fit_s']:.0f} s "
                        f"predict {r['predict_ms_per_scan']:.2f} ms/scan",
                        flush=True,
                    )
                stem = "learned_causal" if options.method == "learned_causal" else "learned"
                path = options.results / f"{stem}_{preset}_seed{seed}.json"
                path.write_text(json.dumps(records, indent=1, default=float), encoding="utf-8")
    summary(options.results)
    causal_summary(options.results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
