"""Benchmark of the classifier stage against stage 1: does classifying the clusters cost more than finding them?

Run: ``python benchmarks/bench_classifier.py [--n-sequences 8] [--duration 30] [--repeat 7] [--profile]
[--accuracy] [--signatures]``.

Data: the realistic simulator preset, ``--n-sequences`` sequences of ``--duration`` s for training and as
many others (the next seed) for testing, through experiment #8's frame transform and Doppler-density
filter.  Stage 1 is #8's RadarDBSCAN.  Printed, each the best of ``--repeat`` runs (wall time, and the CPU
time of the whole process, which counts every thread of the classifier's OpenMP pool):

* stage 1: ``RadarDBSCAN.fit_predict`` on the test data;
* the classifier stage on the test data given stage 1's labels: ``ClusterClassifier.predict_instances`` with a
  clusterer that hands back the precomputed labels, i.e. reading the columns, the cluster features (per
  0.5 s window), the wrapped classifier's ``predict_proba`` and the per-detection result;
* ``predict_instances`` with #8's stage 1 inside, the whole call a user makes;
* ``fit`` on the training data given stage 1's labels (features, matching, fitting the classifier), against
  stage 1 on the training data;

and the ratios to stage 1.  The issue's goal: the classifier stage (features + predict) costs at most stage 1.

``--profile`` prints cProfile's top entries of the classifier stage.  ``--accuracy`` measures what cheaper
settings of the default HistGradientBoostingClassifier cost in macro-F1 (3 seeds; segment-level F1 on the
matched targets and point-wise F1 against every detection's class, both over the five road-user classes)
and in prediction time: the measurement behind the default ``max_iter=30``.  ``--signatures`` prints what
the simulated classes hold: per class, the median and quartiles of the main features of the annotated road
users themselves (each object's detections per 0.5 s window, i.e. perfect clustering), and the macro-F1 of the
default classifier trained on such segments of one seed and tested on another's (both presets).
"""

import argparse
import cProfile
import pstats
import time

import numpy as np
from sklearn.base import BaseEstimator, ClusterMixin


class Precomputed(ClusterMixin, BaseEstimator):
    """A clusterer that returns given labels, so that a timing of ClusterClassifier leaves the clustering out."""

    def __init__(self, labels=None):
        self.labels = labels

    def fit(self, X, y=None):
        self.labels_ = np.asarray(self.labels)
        return self


def best_of(function, repeat):
    """(wall s, process CPU s) of the fastest of ``repeat`` calls, and the last result."""
    best_wall, best_cpu, result = np.inf, np.inf, None
    for _ in range(repeat):
        cpu, wall = time.process_time(), time.perf_counter()
        result = function()
        best_wall = min(best_wall, time.perf_counter() - wall)
        best_cpu = min(best_cpu, time.process_time() - cpu)
    return best_wall, best_cpu, result


def prepared(seed, n_sequences, duration):
    """#8's working detections of one simulated data set, their classes and #8's stage 1."""
    from sklearn_radar.classification import road_user_class
    from sklearn_radar.datasets import make_scenes
    from sklearn_radar.experiments import experiment_pipeline

    scenes = make_scenes(n_sequences=n_sequences, duration=duration, random_state=seed)
    pipeline = experiment_pipeline(8)
    return pipeline[:-1].fit_transform(scenes.data), road_user_class(scenes.data["label_id"]), pipeline[-1]


def timing(args):
    from sklearn_radar.classification import ClusterClassifier

    train, y_train, stage1 = prepared(args.seed, args.n_sequences, args.duration)
    test, _, _ = prepared(args.seed + 1, args.n_sequences, args.duration)
    stage1.fit_predict(test.iloc[:2000])  # compile (or load) the kernels before timing
    print(
        f"data: {args.n_sequences} sequences x {args.duration:g} s each for training and testing; "
        f"test {len(test)} detections, {int(test['keep'].sum())} kept by the filter"
    )

    fit_wall, fit_cpu, train_labels = best_of(lambda: stage1.fit_predict(train), args.repeat)
    wall1, cpu1, test_labels = best_of(lambda: stage1.fit_predict(test), args.repeat)
    print(f"stage 1 clusters: {test_labels.max() + 1} on {int((test_labels >= 0).sum())} test detections")

    model = ClusterClassifier(Precomputed(train_labels)).fit(train, y_train)
    clf_fit_wall, clf_fit_cpu, _ = best_of(
        lambda: ClusterClassifier(Precomputed(train_labels)).fit(train, y_train), args.repeat
    )
    model.set_params(clusterer=Precomputed(test_labels))
    wall2, cpu2, result = best_of(lambda: model.predict_instances(test), args.repeat)
    whole = ClusterClassifier(stage1).fit(train, y_train)
    wall3, cpu3, whole_result = best_of(lambda: whole.predict_instances(test), args.repeat)
    assert result.equals(whole_result), "the precomputed labels must give the same result"
    n_segments = int(np.unique(result["instance"][result["instance"] >= 0]).size)
    print(f"classified: {n_segments} road users on {int((result['class'] >= 0).sum())} detections\n")

    print(f"{'':58s} {'wall s':>8s} {'ratio':>6s} {'CPU s':>8s} {'ratio':>6s}")
    rows = [
        ("stage 1 (RadarDBSCAN #8 fit_predict), test", wall1, cpu1, wall1, cpu1),
        ("classifier stage (features + predict), test", wall2, cpu2, wall1, cpu1),
        ("predict_instances with stage 1 inside, test", wall3, cpu3, wall1, cpu1),
        ("stage 1 (RadarDBSCAN #8 fit_predict), training", fit_wall, fit_cpu, fit_wall, fit_cpu),
        ("classifier fit (features + matching + fit), training", clf_fit_wall, clf_fit_cpu, fit_wall, fit_cpu),
    ]
    for name, wall, cpu, ref_wall, ref_cpu in rows:
        print(f"{name:58s} {wall:8.4f} {wall / ref_wall:6.2f} {cpu:8.4f} {cpu / ref_cpu:6.2f}")
    print(
        f"\nclassifier stage / stage 1: {wall2 / wall1:.2f} (wall), {cpu2 / cpu1:.2f} (CPU); "
        f"goal: at most 1 -> {'met' if wall2 <= wall1 else 'NOT met'} (wall)"
    )
    if args.profile:
        profile = cProfile.Profile()
        profile.enable()
        for _ in range(args.repeat):
            model.predict_instances(test)
        profile.disable()
        pstats.Stats(profile).sort_stats("tottime").print_stats(15)


def accuracy(args):
    """Macro-F1 and prediction time of cheaper settings of the default classifier."""
    from sklearn.ensemble import HistGradientBoostingClassifier
    from sklearn.metrics import f1_score

    from sklearn_radar import instance_target
    from sklearn_radar.classification._features import segment_features, window_index
    from sklearn_radar.classification._targets import segment_targets

    def segments(seed):
        X, y, stage1 = prepared(seed, args.n_sequences, args.duration)
        labels = stage1.fit_predict(X)
        c = {name: X[name].to_numpy(dtype=np.float64) if name in X.columns else None for name in COLUMNS}
        windows = window_index(c["t"], c["sequence"], 0.5)
        table, rows = segment_features(c, labels, windows)
        instances = instance_target(X["track_id"], X["sequence"])
        targets = segment_targets(y, instances, c["sequence"], windows, rows, len(table))
        return table.iloc[:, 3:], targets, rows, y

    settings = {
        "max_iter=100 (scikit-learn's default)": {},
        "max_iter=50": {"max_iter": 50},
        "max_iter=30, no early stopping (the default here)": {"max_iter": 30, "early_stopping": False},
        "max_iter=20, learning_rate=0.25": {"max_iter": 20, "learning_rate": 0.25},
        "early_stopping=True": {"early_stopping": True},
    }
    labels = [0, 1, 2, 3, 4]
    scores = {name: [] for name in settings}
    for seed in (1, 2, 3):
        train_features, train_targets, _, _ = segments(seed)
        test_features, test_targets, rows, y = segments(seed + 100)
        for name, params in settings.items():
            model = HistGradientBoostingClassifier(random_state=0, **params).fit(train_features, train_targets)
            wall, _, predicted = best_of(lambda model=model, X=test_features: model.predict(X), 3)
            per_detection = np.where(rows >= 0, predicted[np.maximum(rows, 0)], -1)
            scores[name].append(
                (
                    f1_score(test_targets, predicted, labels=labels, average="macro"),
                    f1_score(y, per_detection, labels=labels, average="macro"),
                    wall,
                    model.n_iter_,
                )
            )
    print(f"\n{'setting':40s} {'segment F1':>14s} {'point-wise F1':>14s} {'predict ms':>10s} {'n_iter':>6s}")
    for name, values in scores.items():
        v = np.array(values)
        print(
            f"{name:40s} {v[:, 0].mean():.3f} ± {v[:, 0].std():.3f} {v[:, 1].mean():.3f} ± {v[:, 1].std():.3f} "
            f"{1000 * v[:, 2].mean():10.1f} {v[:, 3].mean():6.0f}"
        )
    print("(mean ± standard deviation over 3 seeds; #8's clusters; 0.5 s segments)")


def signatures(args):
    """Per-class features of the annotated road users (perfect clustering) and how well they separate."""
    import pandas as pd
    from sklearn.metrics import f1_score

    from sklearn_radar import FrameTransform
    from sklearn_radar.classification import ROAD_USER_CLASSES, cluster_features, road_user_class
    from sklearn_radar.classification._wrapped import default_classifier
    from sklearn_radar.datasets import make_scenes

    def true_segments(seed, difficulty):
        scenes = make_scenes(n_sequences=args.n_sequences, duration=args.duration, random_state=seed,
                             difficulty=difficulty)  # fmt: skip
        X = FrameTransform().fit_transform(scenes.data)
        y = road_user_class(scenes.data["label_id"])
        table, rows = cluster_features(X, scenes.target, window=0.5, return_rows=True)
        classes = np.full(len(table), -9)
        classes[rows[rows >= 0]] = y[rows >= 0]
        return table.iloc[:, 3:], classes

    features = ["n_detections", "extent_along", "extent_across", "vr_std", "speed_residual", "rcs_mean", "n_sensors"]
    for difficulty in ("realistic", "easy"):
        train, train_classes = true_segments(args.seed + 3, difficulty)
        test, test_classes = true_segments(args.seed + 4, difficulty)
        grouped = train.groupby(pd.Series(train_classes).map(ROAD_USER_CLASSES))[features]
        median, low, high = grouped.median(), grouped.quantile(0.25), grouped.quantile(0.75)
        print(f"\n{difficulty} preset, annotated road users per 0.5 s window: median [quartiles]")
        print(
            (
                median.round(2).astype(str) + " [" + low.round(2).astype(str) + ", " + high.round(2).astype(str) + "]"
            ).T.to_string()
        )
        predicted = default_classifier().fit(train, train_classes).predict(test)
        f1 = f1_score(test_classes, predicted, labels=list(ROAD_USER_CLASSES), average=None)
        print(f"default classifier on these segments, another seed: F1 {np.round(f1, 3)}, macro {f1.mean():.3f}")


COLUMNS = ("x", "y", "v_r", "t", "sequence", "heading", "range_sc", "azimuth_sc", "sensor_yaw", "rcs", "sensor_id")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-sequences", type=int, default=8)
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--accuracy", action="store_true", help="also measure cheaper classifier settings")
    parser.add_argument("--signatures", action="store_true", help="also print what the simulated classes hold")
    args = parser.parse_args()
    timing(args)
    if args.accuracy:
        accuracy(args)
    if args.signatures:
        signatures(args)


if __name__ == "__main__":
    main()
