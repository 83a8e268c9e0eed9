"""Object-level ablation (issue #27): which of the framework's choices cost panoptic quality?

Every variant below changes one factor of a reference framework setting and is tuned for per-frame PQ
with the same budget, on the training half of simulated sequences, with folds grouped by sequence; its
best setting is then scored on the test half (PQ and the paper's V1).  The per-sequence scikit-learn
baselines are tuned the same way, over search spaces widened until no tuned setting should stop at a
bound; the framework's variants keep the paper's ranges (#8's, ``experiments.search_space(8)``).  A setting
that stops at an end of its search range (not at a limit of the parameter itself, such as alpha_r = 1) is
flagged with ``@bound`` and listed in the table's last column.

The reference ``F0`` is the paper's best stage 1 (#8): FCS, the Doppler-density filter at its chosen
setting (0.10 m/s, 1.4 m), the joint x-y-v_r distance (Eq. 5), N_min(r) (Eq. 2), a core-only Doppler
gate ``vr_min`` and eps_t fixed at 0.25 s.  The factors (one at a time against F0):

* ``wide``: #8's space with N_min,50 up to 20 (not 8) and vr_min up to 3 m/s (not 1.5), where F0 stops;
* ``eps_t``: eps_t tuned in [0.05, 2] s instead of fixed at 0.25 s;
* ``point_gate``: a Doppler gate on every detection (|v_r| <= gate is noise before clustering, as the
  per-sequence baseline does) instead of the core-only gate;
* ``no_filter`` / ``gate_only``: no Doppler-density filter; no filter but the point gate;
* ``box`` / ``xy``: the box (Eq. 3) or Euclidean x-y (Eq. 4) criterion instead of Eq. 5;
* ``fixed_nmin``: alpha_r = 0 (fixed N_min) instead of Eq. 2;
* ``merge_cont`` / ``merge_vel``: stage 2 (continuation / Eq. 6 velocity merging) on F0's tuned stage 1;
* ``merge_vel+min_size``: ``merge_vel`` with every merged cluster of fewer than a tuned number of detections
  made noise (ClusterMerger's ``min_cluster_size``, as HDBSCAN's); its causal form counts a cluster's detections
  up to each one's time (``causal=True``, a track confirmation rule), on ``F0 causal``, F0 with every stage causal;
* ``combined``: eps_t tuned and the point gate together, with the cluster-level gate;
* ``SequenceHDBSCAN narrow`` / ``SlidingDBSCAN narrow``: the baselines over their ranges before they were
  widened (the best baseline is the better of both forms);
* ``objects`` / ``objects causal``: the object experiment (``experiments.object_pipeline``: #12 on #8 with a
  tuned ``min_cluster_size``) as ``reproduce`` runs it, offline and causally (tuned causally).

Run (the issue's scale: 5 seeds, every data set, 6 x 20 s; hours on 2 cores), or the user guide's tables (per
preset, in parallel processes, about 40 minutes each on 2 cores; ``--from-logs`` joins their output)::

    python benchmarks/ablation_object_level.py --seeds 0 1 2 3 4 --n-iter 40
    python benchmarks/ablation_object_level.py --data realistic --n-sequences 4 --n-iter 20 \
        --variants F0 SequenceDBSCAN SequenceHDBSCAN SlidingDBSCAN --only
    python benchmarks/ablation_object_level.py --data realistic --n-sequences 4 --n-iter 20 \
        --variants objects "objects causal" "SequenceHDBSCAN narrow" "SlidingDBSCAN narrow" --only
    python benchmarks/ablation_object_level.py --data realistic --n-sequences 4 --n-iter 20 \
        --variants wide eps_t point_gate no_filter gate_only box xy fixed_nmin merge_cont merge_vel --only

``--variants`` picks a subset (``--only``: without F0 and the baselines), ``--quick`` runs a small smoke
configuration, ``--from-logs`` prints the tables from the output of earlier runs (for example of seeds or
variants run in parallel processes).  The table gives, per preset,
each variant's mean test PQ and V1 over the seeds with the standard error, and its mean paired PQ
difference to F0 and to the best per-sequence baseline with the standard error of that difference.

The search loop is the main job's (``sklearn_radar.model_selection._sequence_search``: skopt's ask and tell, one
task per training sequence); its public form is :class:`~sklearn_radar.model_selection.SequenceSearchCV`.
"""

from __future__ import annotations

import argparse
import ast
import json
import math
import re
import sys
import time
from dataclasses import dataclass, field

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin, clone
from sklearn.pipeline import Pipeline

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar._skopt import Integer, Real
from sklearn_radar.cluster import SequenceDBSCAN, SequenceHDBSCAN, SlidingDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import SKLEARN_BASELINES, SLIDING_BASELINE, object_pipeline, object_search_space
from sklearn_radar.metrics import precluster_target
from sklearn_radar.metrics._parts import combine_parts, sequence_parts
from sklearn_radar.model_selection import sequence_train_test_split
from sklearn_radar.model_selection._bounds import bounds_reached
from sklearn_radar.model_selection._sequence_search import SearchData, bayes_search, sized_sequence_folds


class PointDopplerGate(TransformerMixin, BaseEstimator):
    """Marks every detection with ``|v_r| <= gate`` (m/s) as not kept: the per-sequence baseline's gate."""

    def __init__(self, gate=0.4):
        self.gate = gate

    def fit(self, X, y=None):
        return self

    def transform(self, X):
        keep = np.abs(X["v_r"].to_numpy()) > self.gate
        if "keep" in X.columns:
            keep &= X["keep"].to_numpy() != 0
        return X.assign(keep=keep)


#: The reference setting's search space (#8's, as in experiments.search_space(8)).
def _f0_space():
    return {
        "cluster__eps_xyv": Real(0.2, 3.0, name="cluster__eps_xyv"),
        "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
        "cluster__min_samples": Real(1.5, 8.0, name="cluster__min_samples"),
        "cluster__alpha_r": Real(0.0, 1.0, name="cluster__alpha_r"),
        "cluster__vr_min": Real(0.0, 1.5, name="cluster__vr_min"),
    }


#: Simulated data sets: (difficulty preset, knobs).  "radarscenes" has RadarScenes' published traffic statistics
#: (about 31 instances per minute and 460-510 annotated detections per instance, against about 94 and 234 for the
#: realistic preset), fewer and longer-lived road users, where issue #27 saw the baselines' lead on real data.
DATA_SETS = {
    "realistic": ("realistic", None),
    "easy": ("easy", None),
    "radarscenes": ("radarscenes", None),
}


@dataclass
class Variant:
    """A pipeline to tune: its fixed stage 0 (frame, filter), the searched part and its space."""

    name: str
    stage0: Pipeline
    searched: object
    space: dict
    after: str | None = None  # stage 2 on the tuned stage 1 of this variant
    fixed: dict = field(default_factory=dict)
    merged: object = None  # stage1 params -> the searched stage 2 (default: F0's cluster under a ClusterMerger)


def _stage0(filtered=True, causal=False):
    steps = [("frame", FrameTransform(frame="frame"))]
    if filtered:
        steps.append(("filter", DopplerDensityFilter(causal=causal)))
    return Pipeline(steps)


def _cluster(**params):
    base = {"metric": "xyv", "eps_t": 0.25, "alpha_r": 0.99, "min_samples": 3.87, "vr_min": 1.0}
    base.update(params)
    return Pipeline([("cluster", RadarDBSCAN(**base))])


def _gated(**params):
    return Pipeline([("gate", PointDopplerGate()), ("cluster", RadarDBSCAN(**{"metric": "xyv", **params}))])


def _with(space, **dimensions):
    space = dict(space)
    for key, dimension in dimensions.items():
        if dimension is None:
            space.pop(key, None)
        else:
            space[key] = dimension
    return space


_EPS_T = Real(0.05, 2.0, prior="log-uniform", name="cluster__eps_t")
_GATE = Real(0.0, 1.5, name="gate__gate")


def variants():
    """Every variant, in table order."""
    f0 = _f0_space()
    box = {
        "cluster__eps_xy": Real(0.2, 3.0, name="cluster__eps_xy"),
        "cluster__eps_vr": Real(0.5, 20.0, prior="log-uniform", name="cluster__eps_vr"),
    }
    no_xyv = {"cluster__eps_xyv": None, "cluster__vr_scale": None}
    gate_space = _with(f0, gate__gate=_GATE, cluster__vr_min=None)
    merge = {
        "merge__eps_d": Real(0.2, 3.0, name="merge__eps_d"),
        "merge__eps_v": Real(0.2, 6.0, name="merge__eps_v"),
        "merge__eps_t2": Real(0.1, 1.0, name="merge__eps_t2"),
        "merge__min_samples": Integer(1, 3, name="merge__min_samples"),
    }
    velocity = {**merge, "merge__eps_phi": Real(0.05, 1.5, name="merge__eps_phi")}
    min_size = {**velocity, "merge__min_cluster_size": object_search_space(2)["merge__min_cluster_size"]}
    sequence_dbscan, sequence_hdbscan, sliding = (SKLEARN_BASELINES[name][1] for name in _BASELINE_NAMES)
    vr_gate = Real(0.0, 1.5, name="cluster__cluster_vr_min")
    return [
        Variant("F0", _stage0(), _cluster(), f0),
        Variant(
            "wide",
            _stage0(),
            _cluster(),
            _with(
                f0,
                cluster__min_samples=Real(1.5, 20.0, name="cluster__min_samples"),
                cluster__vr_min=Real(0.0, 3.0, name="cluster__vr_min"),
            ),
        ),
        Variant("eps_t", _stage0(), _cluster(), _with(f0, cluster__eps_t=_EPS_T)),
        Variant("point_gate", _stage0(), _gated(eps_t=0.25, vr_min=-np.inf), gate_space),
        Variant("no_filter", _stage0(False), _cluster(), f0),
        Variant("gate_only", _stage0(False), _gated(eps_t=0.25, vr_min=-np.inf), gate_space),
        Variant("box", _stage0(), _cluster(metric="box"), _with(f0, **no_xyv, **box)),
        Variant(
            "xy",
            _stage0(),
            _cluster(metric="xy"),
            _with(f0, **no_xyv, **{**box, "cluster__eps_xy": Real(0.2, 3.0, name="cluster__eps_xy")}),
        ),
        Variant(
            "fixed_nmin",
            _stage0(),
            _cluster(alpha_r=0.0, min_samples=3),
            _with(f0, cluster__alpha_r=None, cluster__min_samples=Integer(2, 8, name="cluster__min_samples")),
        ),
        Variant("merge_cont", _stage0(), None, merge, after="F0", fixed={"mode": "continuation"}),
        Variant(
            "merge_vel",
            _stage0(),
            None,
            velocity,
            after="F0",
            fixed={"mode": "velocity"},
        ),
        Variant(
            "combined",
            _stage0(),
            _gated(eps_t=0.25, vr_min=-np.inf),
            _with(gate_space, cluster__eps_t=_EPS_T, cluster__cluster_vr_min=vr_gate),
        ),
        Variant("merge_vel+min_size", _stage0(), None, min_size, after="F0", fixed={"mode": "velocity"}),
        Variant("F0 causal", _stage0(causal=True), _cluster(causal=True), f0),
        Variant(
            "merge_vel+min_size causal",
            _stage0(causal=True),
            None,
            min_size,
            after="F0 causal",
            fixed={"mode": "velocity", "causal_min_size": True},
        ),
        *_object_variants("objects", causal=False),
        *_object_variants("objects causal", causal=True),
        Variant("SequenceDBSCAN", _stage0(), Pipeline([("cluster", SequenceDBSCAN())]), sequence_dbscan),
        Variant("SequenceHDBSCAN", _stage0(), Pipeline([("cluster", SequenceHDBSCAN())]), sequence_hdbscan),
        Variant("SlidingDBSCAN", _stage0(causal=True), Pipeline([("cluster", SlidingDBSCAN())]), sliding),
        Variant(
            "SequenceHDBSCAN narrow",
            _stage0(),
            Pipeline([("cluster", SequenceHDBSCAN())]),
            {**sequence_hdbscan, **_NARROW_SCALES},
        ),
        Variant(
            "SlidingDBSCAN narrow",
            _stage0(causal=True),
            Pipeline([("cluster", SlidingDBSCAN())]),
            {**sliding, **_NARROW_SCALES, "cluster__min_samples": _NARROW_MIN_SAMPLES},
        ),
    ]


#: The baselines' ranges before they were widened (vr_scale from 0.05, t_scale from 0.1 m/s, vr_min to 3 m/s,
#: min_samples from 2): a check that the wider ranges do not tune worse within 20 iterations (the best baseline is
#: the better of both forms).
_NARROW_SCALES = {
    "cluster__vr_scale": Real(0.05, 50.0, prior="log-uniform", name="cluster__vr_scale"),
    "cluster__t_scale": Real(0.1, 100.0, prior="log-uniform", name="cluster__t_scale"),
    "cluster__vr_min": Real(0.1, 3.0, name="cluster__vr_min"),
}
_NARROW_MIN_SAMPLES = Integer(2, 40, prior="log-uniform", name="cluster__min_samples")


#: The baselines' search spaces are reproduce's (``experiments.SKLEARN_BASELINES``, widened where a tuned setting
#: stopped at a bound): per-sequence DBSCAN, per-sequence HDBSCAN, DBSCAN over a sliding past window.
_BASELINE_NAMES = (
    "sklearn DBSCAN per sequence (x, y, v_r, t) with Doppler gate",
    "sklearn HDBSCAN per sequence (x, y, v_r, t) with Doppler gate",
    SLIDING_BASELINE,
)


def _object_variants(name, causal):
    """The object experiment (``experiments.object_pipeline``): its stage-1 search, then stage 2 on it."""
    stage1 = object_pipeline(1, causal=causal)

    def merged(stage1_params):
        return object_pipeline(2, stage1_params=stage1_params, causal=causal)[1:]

    return [
        Variant(f"{name} (stage 1)", stage1[:1], stage1[1:], object_search_space(1)),
        Variant(name, stage1[:1], None, object_search_space(2), after=f"{name} (stage 1)", merged=merged),
    ]


BASELINES = ("SequenceDBSCAN", "SequenceHDBSCAN", "SequenceHDBSCAN narrow")
#: The causal ones: their best is what the causal variants are compared with.
CAUSAL_BASELINES = ("SlidingDBSCAN", "SlidingDBSCAN narrow")
#: Variants that decide from the past only (compared with the causal baselines).
CAUSAL = (
    "objects causal (stage 1)",
    "objects causal",
    "F0 causal",
    "merge_vel+min_size causal",
    *CAUSAL_BASELINES,
)


def _merger(variant, stage1_params):
    """Stage 2 on the tuned stage 1, with the variant's fixed merger parameters (causal_min_size: causal stage 1)."""
    stage1 = clone(_cluster(causal=variant.fixed.get("causal_min_size", False))).set_params(**stage1_params)[-1]
    return Pipeline([("merge", ClusterMerger(stage1=stage1, **variant.fixed))])


def _test_scores(searched, test_sequences):
    """Test PQ and V1 of a fitted-per-sequence estimator (each test sequence clustered on its own)."""
    scores = {}
    for objective in ("pq", "v1"):
        parts = [sequence_parts(clone(searched), X, y, objective) for X, y in test_sequences]
        scores[objective] = combine_parts(objective, parts)
    return scores


def run_one(preset, seed, chosen, options):
    """Tune and test every chosen variant on one simulated data set; returns {variant: record}.

    With ``options.keep_labels`` each record also holds ``test_labels`` (the tuned setting's labels of the test
    sequences, fitted per sequence on the output of the variant's stage 0, concatenated in sequence order) and
    ``predict_s`` (their seconds, stage 0 excluded); otherwise both are None.
    """
    difficulty, knobs = DATA_SETS[preset]
    scenes = make_scenes(
        n_sequences=options.n_sequences,
        duration=options.duration,
        difficulty=difficulty,
        knobs=knobs,
        random_state=seed,
    )
    X, groups = scenes.data, scenes.groups
    target = precluster_target(X, scenes.target)
    train_rows, test_rows = sequence_train_test_split(groups, test_size=0.5, random_state=seed)
    train_ids = np.unique(groups[train_rows])
    sizes = [int(np.sum(groups == s)) for s in train_ids]
    folds = sized_sequence_folds(train_ids, sizes, min(options.cv_folds, len(train_ids)))
    raw = SearchData.place(X.iloc[train_rows], target[train_rows], groups[train_rows])
    test_raw = [(X.iloc[r], target[r]) for r in _rows_per_sequence(groups, test_rows)]
    found, prepared = {}, {}
    for variant in chosen:
        start = time.perf_counter()
        key = repr(variant.stage0)
        if key not in prepared:
            prepared[key] = raw.prepare(variant.stage0)
        data = prepared[key]
        searched = variant.searched
        if variant.after is not None:
            base = found[variant.after]
            searched = variant.merged(base["params"]) if variant.merged else _merger(variant, base["params"])
        result = bayes_search(
            searched,
            variant.space,
            data,
            folds,
            objective="pq",
            n_iter=options.n_iter,
            n_initial_points=max(1, round(0.3 * options.n_iter)),
            random_state=seed,
        )
        fitted = clone(searched).set_params(**result.best_params)
        test = [(clone(variant.stage0).fit_transform(Xs), ys) for Xs, ys in test_raw]
        scores = _test_scores(fitted, test)
        labels, predict_s = None, None
        if getattr(options, "keep_labels", False):  # the test labels again, for an error anatomy
            predict_start = time.perf_counter()
            labels = np.concatenate([np.asarray(clone(fitted).fit_predict(Xs)) for Xs, _ in test])
            predict_s = time.perf_counter() - predict_start
        found[variant.name] = {
            "params": result.best_params,
            "cv_pq": result.best_score,
            "pq": scores["pq"],
            "v1": scores["v1"],
            "bounds": bounds_reached(result.best_params, variant.space),
            "seconds": time.perf_counter() - start,
            "test_labels": labels,
            "predict_s": predict_s,
        }
        record = found[variant.name]
        print(
            f"  {preset} seed {seed} {variant.name:<26} test PQ {record['pq']:.3f} V1 {record['v1']:.3f} "
            f"(cv PQ {record['cv_pq']:.3f}, {record['seconds']:.0f} s)"
            + (f" @bound {record['bounds']}" if record["bounds"] else "")
            + f" params {json.dumps(record['params'])}",
            flush=True,
        )
    return found


_LINE = re.compile(
    r"^  (?P<preset>\S+) seed (?P<seed>\d+) (?P<name>.+?)\s+test PQ (?P<pq>[\d.]+) V1 (?P<v1>[\d.]+) "
    r"\(cv PQ (?P<cv>[\d.]+), \d+ s\)(?: @bound (?P<bounds>\[.*?\]))?(?: params (?P<params>\{.*\}))?$"
)


def read_logs(paths):
    """``{preset: {seed: {variant: record}}}`` from the per-variant lines of earlier runs' output (``--from-logs``).

    Runs of the same seed split over several processes combine; the settings are those printed in the lines.
    """
    runs = {}
    for path in paths:
        for line in open(path, encoding="utf-8"):
            match = _LINE.match(line.rstrip("\n"))
            if match is None:
                continue
            record = {
                "pq": float(match["pq"]),
                "v1": float(match["v1"]),
                "cv_pq": float(match["cv"]),
                "bounds": ast.literal_eval(match["bounds"]) if match["bounds"] else [],
                "params": json.loads(match["params"]) if match["params"] else {},
            }
            runs.setdefault(match["preset"], {}).setdefault(int(match["seed"]), {})[match["name"]] = record
    return runs


def _rows_per_sequence(groups, rows):
    return [rows[groups[rows] == s] for s in np.unique(groups[rows])]


def _mean_se(values):
    values = np.asarray(values, dtype=np.float64)
    if len(values) < 2:
        return float(values.mean()), float("nan")
    return float(values.mean()), float(values.std(ddof=1) / math.sqrt(len(values)))


def _table(preset, runs, names):
    """One preset's table: mean ± se of test PQ and V1, and paired PQ differences to F0 and the best baseline.

    A causal variant (:data:`CAUSAL`) is set beside the best causal baseline, every other one beside the best
    offline baseline: a car can only use the causal figure.
    """

    def best_of(candidates):
        present = [b for b in candidates if b in names]
        return max(present, key=lambda b: np.mean([r[b]["pq"] for r in runs])) if present else None

    best = {False: best_of(BASELINES), True: best_of(CAUSAL_BASELINES)}
    lines = [
        f"\n{preset}: {len(runs)} seed(s); best per-sequence baseline: {best[False]}; best causal one: {best[True]}",
        f"{'variant':<26} {'test PQ':>15} {'test V1':>15} {'PQ - F0':>15} {'PQ - baseline':>15}  at a bound",
    ]
    for name in names:
        pq = [r[name]["pq"] for r in runs]
        v1 = [r[name]["v1"] for r in runs]
        cells = [_fmt(_mean_se(pq)), _fmt(_mean_se(v1))]
        for reference in ("F0", best[name in CAUSAL]):
            if reference is None or reference not in names or reference == name:
                cells.append(f"{'-':>15}")
            else:
                cells.append(_fmt(_mean_se([r[name]["pq"] - r[reference]["pq"] for r in runs]), signed=True))
        bound_hits = sorted({hit for r in runs for hit in r[name]["bounds"]})
        lines.append(f"{name:<26} " + " ".join(cells) + f"  {', '.join(bound_hits) or '-'}")
    lines.append("settings of each seed:")
    for name in names:
        for k, run in enumerate(runs):
            params = ", ".join(f"{key.split('__')[-1]}={_short(v)}" for key, v in sorted(run[name]["params"].items()))
            lines.append(f"  {name if k == 0 else '':<26} {params}")
    return "\n".join(lines)


def _short(value):
    return f"{value:.3g}" if isinstance(value, float) else str(value)


def _fmt(mean_se, signed=False):
    mean, se = mean_se
    text = f"{mean:+.3f}" if signed else f"{mean:.3f}"
    return f"{text} ± {se:.3f}".rjust(15) if not math.isnan(se) else text.rjust(15)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--data", nargs="+", default=list(DATA_SETS), choices=list(DATA_SETS), dest="presets")
    parser.add_argument("--n-sequences", type=int, default=6)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--n-iter", type=int, default=40)
    parser.add_argument("--cv-folds", type=int, default=3)
    parser.add_argument("--variants", nargs="+", help="subset of the variants (F0 and the baselines are added)")
    parser.add_argument(
        "--only", action="store_true", help="run only --variants (and the stage 1 they need), not F0 and the baselines"
    )
    parser.add_argument("--quick", action="store_true", help="1 seed, 1 preset, 4 x 10 s, 6 iterations")
    parser.add_argument("--from-logs", nargs="+", metavar="FILE", help="print the tables of earlier runs' output")
    options = parser.parse_args(argv)
    if options.from_logs:
        for preset, by_seed in read_logs(options.from_logs).items():
            names = [v.name for v in variants() if all(v.name in run for run in by_seed.values())]
            print(_table(preset, [by_seed[seed] for seed in sorted(by_seed)], names))
        return 0
    if options.quick:
        options.seeds, options.presets = options.seeds[:1], options.presets[:1]
        options.n_sequences, options.duration, options.n_iter = 4, 10.0, 6
    every = variants()
    known = [v.name for v in every]
    if options.only and not options.variants:
        parser.error("--only needs --variants")
    wanted = set(options.variants or known)
    if not options.only:
        wanted |= {"F0", *BASELINES}
        if wanted & set(CAUSAL):
            wanted |= set(CAUSAL_BASELINES)
    needed = {v.after for v in every if v.name in wanted and v.after} - wanted  # stage 2 needs its stage 1
    while needed:
        wanted |= needed
        needed = {v.after for v in every if v.name in needed and v.after} - wanted
    unknown = wanted - set(known)
    if unknown:
        parser.error(f"unknown variant(s) {sorted(unknown)}; known: {known}")
    chosen = [v for v in every if v.name in wanted]
    names = [v.name for v in chosen]
    print(
        f"object-level ablation: {len(options.seeds)} seed(s) x {options.presets}, "
        f"{options.n_sequences} x {options.duration:g} s, {options.n_iter} iterations per search, PQ objective",
        flush=True,
    )
    tables = []
    for preset in options.presets:
        runs = [run_one(preset, seed, chosen, options) for seed in options.seeds]
        tables.append(_table(preset, runs, names))
    print("\n".join(tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
