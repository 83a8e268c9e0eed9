"""The tracking step: the run's settings streamed through the online pipeline, their ids scored over time.

Each setting of :data:`~._constants.TRACKED` that the run has (the object experiment when it ran; the learned
grouping's causal model, fitted by the learned step, when it ran; the paper's settings, the run's tuned ones where
their experiments ran, the paper's otherwise) is replayed scan by scan
through :class:`~sklearn_radar.online.OnlinePipeline` on every test sequence, where it lives, with a
:class:`~sklearn_radar.online.Tracker` on its object ids.  The Tracker's few parameters are chosen on the training
half (:data:`TRACKER_GRID`, for MOTA) on the object setting's ids, and every setting streams with them but the learned
grouping, whose Tracker is tuned the same way on its own stream's training-half ids; the baseline tracker
(:class:`._baseline_tracker.NearestCentroidTracker` on SlidingDBSCAN's clusters) is tuned the same way.  The ids
are scored per 0.5 s time window: MOTA and IDF1 (:func:`~sklearn_radar.metrics.tracking_scores`), HOTA, DetA and
AssA (:func:`~sklearn_radar.metrics.hota_scores`) (:ref:`online-tracking`).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np
from sklearn.base import clone

from ..experiments import SKLEARN_BASELINES, baseline_pipeline, experiment_pipeline, get_experiment, paper_params
from ..experiments._baselines import SLIDING_BASELINE
from ..experiments._learned import learned_pipeline
from ..experiments._saved import setting_pipeline
from ..metrics import tracking_scores
from ..metrics._hota import combine_hota_counts, hota_counts
from ..metrics._tracking import _scores
from ..online import OnlinePipeline, Tracker
from ..online._replay import replay
from ..online._scans import scan_order
from ..preprocessing import FrameTransform
from ._baseline_tracker import NearestCentroidTracker
from ._constants import BASELINES, LEARNED, OBJECTS, SCORE_WINDOW_S, TRACKED, TRACKING
from ._context import Outcome
from ._records import JsonRecord, record
from ._tuning import native_params, search_seed, tune

#: The counts of :func:`tracking_scores` that add up over sequences.
_COUNTS = ("id_switches", "misses", "false_positives", "n_objects", "n_matches", "idtp", "idfp", "idfn", "n_windows")

#: The Tracker's parameters tried on the training half, every combination (the others at their defaults).
TRACKER_GRID = {"min_hits": (2, 4, 8), "max_age": (0.3, 1.0), "gate": (3.0, 5.0)}
#: The baseline tracker's, the same confirmation and deletion values and a gate in metres.
BASELINE_GRID = {"gate": (1.0, 2.0, 4.0), "min_hits": (2, 4, 8), "max_age": (0.3, 1.0)}
#: What the trackers' parameters maximise on the training half.
TUNED_FOR = "MOTA"
#: The setting whose ids the Tracker is tuned on, when the run has it: the one meant for objects.
TRACKER_TUNED_ON = OBJECTS
#: The keys of the figure's ids in :attr:`Outcome.tracks`: the ground truth, and ours (the first setting's tracked).
TRUTH, OURS = "truth", "ours"


@record
class TrackingScores(JsonRecord):
    """How well ids follow the moving road users over time, summed over the test sequences.

    A track never crosses sequences, so the identity assignment, and every
    count, is the sum of the sequences'.

    Attributes
    ----------
    window_s : float
        Window length, s.
    mota, idf1 : float
        From the summed counts (:func:`~sklearn_radar.metrics.tracking_scores`); NaN without ground-truth objects.
    id_switches, misses, false_positives, n_objects, n_matches, idtp, idfp, idfn, n_windows : int
    hota, deta, assa : float or None, default=None
        :func:`~sklearn_radar.metrics.hota_scores` over the same windows (sequences combined as TrackEval does).
    """

    window_s: float
    mota: float
    idf1: float
    id_switches: int
    misses: int
    false_positives: int
    n_objects: int
    n_matches: int
    idtp: int
    idfp: int
    idfn: int
    n_windows: int
    hota: float | None = None
    deta: float | None = None
    assa: float | None = None


@record
class TrackingResult(JsonRecord):
    """One setting streamed through :class:`~sklearn_radar.online.OnlinePipeline` on the test half.

    Attributes
    ----------
    number : int or None
        The paper's experiment whose setting streams; None for another (the object experiment, the learned grouping).
    method : str
    setting_source : str
        ``"tuned #13"`` or ``"fixed #1"`` (the run's setting), ``"paper's #13"`` (the experiment did not run),
        ``"tuned for PQ"`` (the object experiment's), ``"causal, fitted on the training half"`` (the learned
        grouping's causal model).
    params : dict
        The setting, as pipeline parameters (stage 1's included for stage 2; the learned model's as set where they
        differ from :func:`~sklearn_radar.experiments._learned.learned_pipeline`'s, the fitted thresholds aside).
    reported : TrackingScores
        The object ids as given with each detection when its scan was labelled.
    final : TrackingScores
        The object ids after every alias (stage-1 meetings, stage-2 merges) resolved to the surviving one.
    tracked : TrackingScores or None, default=None
        The :class:`~sklearn_radar.online.Tracker`'s ids on the reported object ids, as given at each scan.
    n_scans : int
    n_aliases : int
        Merges reported as aliases, summed over the test sequences.
    """

    number: int | None
    method: str
    setting_source: str
    params: dict[str, Any]
    reported: TrackingScores
    final: TrackingScores
    n_scans: int
    n_aliases: int
    tracked: TrackingScores | None = None


@record
class TunedTracker(JsonRecord):
    """A tracker's parameters, chosen on the training half.

    Attributes
    ----------
    params : dict
        The chosen values of its grid (its other parameters at their defaults).
    tuned_on : str
        The setting whose clusters it tracked while tuned (``"objects"``, or the baseline clusterer's name).
    criterion : str
        What the choice maximised (``"MOTA"``), over the training half.
    train_score : float
        Its value for the chosen parameters.
    n_candidates : int
        Settings tried (the grid's combinations).
    """

    params: dict[str, Any]
    tuned_on: str
    criterion: str
    train_score: float
    n_candidates: int


@record
class BaselineTracking(JsonRecord):
    """The baseline tracker on the test half: SlidingDBSCAN's clusters, nearest centroid, Hungarian method.

    Attributes
    ----------
    clusterer : str
        The baseline clusterer's name (:data:`~sklearn_radar.experiments.SKLEARN_BASELINES`).
    clusterer_params : dict
    clusterer_source : str
        Where its setting comes from (tuned for PQ on the training half, here or by the baselines step).
    tracker : TunedTracker
    scores : TrackingScores
    """

    clusterer: str
    clusterer_params: dict[str, Any]
    clusterer_source: str
    tracker: TunedTracker
    scores: TrackingScores


@record
class TrackingStep(JsonRecord):
    """What the tracking step found (``tracking``).

    Attributes
    ----------
    settings : dict of str to TrackingResult
        By setting key (``"objects"``, ``"1"``, ...), in the order of :data:`~._constants.TRACKED`.
    tracker : TunedTracker or None, default=None
        The Tracker's parameters tuned on the object setting's training ids; None when the run has no object
        experiment (the Tracker then runs at its defaults).
    baseline : BaselineTracking or None, default=None
    learned_tracker : TunedTracker or None, default=None
        The learned grouping's Tracker, tuned the same way on its causal model's stream over the training half (the
        half it was fitted on); None when the run does not track the learned grouping.
    """

    settings: dict[str, TrackingResult]
    tracker: TunedTracker | None = None
    baseline: BaselineTracking | None = None
    learned_tracker: TunedTracker | None = None


@dataclasses.dataclass(frozen=True)
class TrackedSetting:
    """A setting the step streams: its pipeline, parameters, where they come from, its experiment and method."""

    pipeline: Any
    params: dict
    source: str
    number: int | None
    method: str


def setting_to_track(key, needed):
    """The :class:`TrackedSetting` of :data:`TRACKED` key ``key``, or None when the run lacks it.

    One branch per kind of setting: the object experiment's (only when it ran), the learned grouping's causal
    model (only when the learned step ran in this run: the fitted model is not read back from a results file), a
    paper experiment's (the run's or the paper's).
    """
    if key == LEARNED:
        result = needed.get(LEARNED)
        model = None if result is None or result.causal is None else result.causal.model
        if model is None:
            return None
        unset = learned_pipeline().get_params()
        params = {
            name: value
            for name, value in model.get_params().items()
            if "__" in name and name != "link__n_jobs" and value != unset[name]
        }
        return TrackedSetting(model, native_params(params), "causal, fitted on the training half", None, LEARNED)
    if key == OBJECTS:
        result = needed.get(OBJECTS)
        if result is None:
            return None
        kept = result.kept
        params = {**kept.stage1_params, **kept.params}
        return TrackedSetting(
            run_setting_pipeline(OBJECTS, kept.params, kept.stage1_params),
            params,
            "tuned for PQ",
            None,
            "objects",
        )
    number = int(key)
    pipeline, params, source = tracked_setting(number, needed.get(key))
    return TrackedSetting(pipeline, params, source, number, get_experiment(number).method)


def tracked_setting(number, result):
    """(pipeline, params, source) of experiment ``number``: the run's setting (``result``) or, if None, the paper's.

    ``source`` says which: ``"tuned #13"`` or ``"fixed #1"`` (the run's), ``"paper's #13"``.
    """
    if result is None:
        return experiment_pipeline(number), paper_params(number), f"paper's #{number}"
    params = {**(result.stage1_params or {}), **result.params}
    return (
        run_setting_pipeline(number, result.params, result.stage1_params),
        params,
        f"{'tuned' if get_experiment(number).tuned else 'fixed'} #{number}",
    )


def run_setting_pipeline(number, params, stage1_params):
    """The pipeline of a setting of experiment ``number`` the run found (as ``params.json`` saves it)."""

    setting = {"experiment": number, "params": params, "stage1_params": stage1_params}
    return setting_pipeline(setting, "results")


def streamable(pipeline):
    """None if :class:`OnlinePipeline` takes ``pipeline``, else why not (e.g. a cluster-level gate)."""
    try:
        OnlinePipeline(pipeline)
    except ValueError as error:
        return str(error)
    return None


def candidates(grid):
    """Every combination of a grid's values, as parameter dicts, in the grid's order."""
    return [dict(zip(grid, values, strict=True)) for values in itertools.product(*grid.values())]


def fixed_frame(data):
    """x, y (m, sequence frame), compensated v_r (m/s), line of sight (rad, sequence frame) and t (s) per detection.

    What :class:`OnlinePipeline` feeds its tracker (``frame="frame"``).
    """
    work = FrameTransform(frame="frame").fit_transform(data)
    los = data["azimuth_sc"] + data["sensor_yaw"] + data["ego_yaw_seq"]
    columns = {name: work[name].to_numpy(dtype=np.float64) for name in ("x", "y", "v_r", "t")}
    return columns | {"los": los.to_numpy(dtype=np.float64), "timestamp": data["timestamp"].to_numpy()}


def run_tracker(tracker, columns, clusters):
    """The ids a fresh ``tracker`` (a Tracker or the baseline's) gives the detections, fed scan by scan."""
    ids = np.full(len(clusters), -1, dtype=np.int64)
    baseline = isinstance(tracker, NearestCentroidTracker)
    x, y, v_r, los, t = (columns[name] for name in ("x", "y", "v_r", "los", "t"))
    for rows in scan_order({"timestamp": columns["timestamp"]}):
        if baseline:
            ids[rows] = tracker.update(x[rows], y[rows], t[rows[0]], clusters[rows])
        else:
            ids[rows] = tracker.update(x[rows], y[rows], v_r[rows], los[rows], t[rows[0]], clusters[rows])
    return ids


def _counts(truth, ids, times, hota=False):
    """The summable counts of ``ids``: :func:`tracking_scores`' and, with ``hota``, :func:`hota_counts`."""
    scores = tracking_scores(truth, ids, times=times, window=SCORE_WINDOW_S)
    found = {count: scores[count] for count in _COUNTS}
    if hota:
        found["hota_counts"] = hota_counts(truth, ids, times, window=SCORE_WINDOW_S)
    return found


def tuning_parts(sequence, objects, sliding, learned=None):
    """One training sequence's counts for every candidate of each tracker: ``{"tracker": [...], "baseline": [...]}``
    (and ``"learned": [...]``).

    ``objects``: the pipeline whose object ids the Tracker follows (None: none); ``sliding``: the
    baseline clusterer's pipeline; ``learned``: the fitted causal learned pipeline, whose Tracker is tuned apart
    (None: none).
    """
    data = sequence.scenes.data
    truth = np.asarray(sequence.scenes.target)
    times = data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    columns = fixed_frame(data)
    found = {}
    for key, pipeline in (("tracker", objects), (LEARNED, learned)):
        if pipeline is not None:  # the ids the pipeline's own Tracker follows
            followed = replay(OnlinePipeline(pipeline), data)["followed"]
            found[key] = [
                _counts(truth, run_tracker(Tracker(**c), columns, followed), times) for c in candidates(TRACKER_GRID)
            ]
    labels = np.asarray(clone(sliding).fit_predict(sequence.X))
    found["baseline"] = [
        _counts(truth, run_tracker(NearestCentroidTracker(**c), columns, labels), times)
        for c in candidates(BASELINE_GRID)
    ]
    return found


def track_sequence(sequence, pipeline, tracker_params, drawn=None):
    """One test sequence streamed with a Tracker: the counts of its reported, final and tracked ids, its scans.

    ``drawn``: the figure's sequence, whose track ids (and true objects) the part keeps.
    """
    data = sequence.scenes.data
    replayed = replay(OnlinePipeline(pipeline, tracker=Tracker(**tracker_params)), data)
    times = data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    truth = np.asarray(sequence.scenes.target)
    found = {"n_scans": len(replayed["latency"]), "n_aliases": len(replayed["aliases"])}
    for name, ids in (
        ("reported", replayed["reported"]),
        ("final", replayed["object_ids"]),
        ("tracked", replayed["track_id"]),
    ):
        found[name] = _counts(truth, ids, times, hota=name != "final")  # the final ids: a reference, not causal
    found["drawn"] = {TRUTH: truth, OURS: replayed["track_id"]} if sequence.id == drawn else None
    return found


def baseline_sequence(sequence, sliding, tracker_params, drawn=None):
    """One test sequence's baseline tracks (SlidingDBSCAN, nearest centroid): their counts (and drawn ids)."""
    data = sequence.scenes.data
    labels = np.asarray(clone(sliding).fit_predict(sequence.X))
    ids = run_tracker(NearestCentroidTracker(**tracker_params), fixed_frame(data), labels)
    times = data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    found = _counts(np.asarray(sequence.scenes.target), ids, times, hota=True)
    found["drawn"] = ids if sequence.id == drawn else None
    return found


def combine_scores(parts):
    """The :class:`TrackingScores` of the summed counts of sequences (and their HOTA, when counted)."""
    total = {count: sum(part[count] for part in parts) for count in _COUNTS}
    hypotheses = total["false_positives"] + total["n_matches"]
    figures = _scores(
        total["n_objects"],
        hypotheses,
        total["n_matches"],
        total["id_switches"],
        total["idtp"],
        total["idfn"],
        total["idfp"],
        total["n_windows"],
    )
    hota = {}
    if all("hota_counts" in part for part in parts):
        found = combine_hota_counts([part["hota_counts"] for part in parts])
        hota = {name: found[name] for name in ("hota", "deta", "assa")}
    return TrackingScores(window_s=SCORE_WINDOW_S, mota=figures["mota"], idf1=figures["idf1"], **total, **hota)


def combine_tracking(setting, parts):
    """The :class:`TrackingResult` of a :class:`TrackedSetting` from its sequences' parts."""
    return TrackingResult(
        number=setting.number,
        method=setting.method,
        setting_source=setting.source,
        params=setting.params,
        reported=combine_scores([part["reported"] for part in parts]),
        final=combine_scores([part["final"] for part in parts]),
        tracked=combine_scores([part["tracked"] for part in parts]),
        n_scans=sum(part["n_scans"] for part in parts),
        n_aliases=sum(part["n_aliases"] for part in parts),
    )


def chosen_tracker(parts, name, grid, tuned_on):
    """The :class:`TunedTracker` of ``grid`` with the best training MOTA over the sequences' ``parts`` (first tie)."""
    options = candidates(grid)
    scores = [combine_scores([part[name][k] for part in parts]).mota for k in range(len(options))]
    scores = [-np.inf if np.isnan(score) else score for score in scores]
    best = int(np.argmax(scores))
    return TunedTracker(
        params=options[best],
        tuned_on=tuned_on,
        criterion=TUNED_FOR,
        train_score=float(scores[best]),
        n_candidates=len(options),
    )


def sliding_setting(env, needed):
    """``(params, source)`` of the baseline clusterer, tuned for PQ on the training half like the object setting.

    The baselines step's setting when it tuned for PQ (``--objective pq``); else one search here, with the run's
    budget.
    """
    baselines = needed.get(BASELINES) or {}
    if env.objective == "pq" and SLIDING_BASELINE in baselines:
        return baselines[SLIDING_BASELINE].params, "the baselines step's, tuned for PQ on the training half"
    pipeline = baseline_pipeline(SLIDING_BASELINE, memory=env.cache)
    space = SKLEARN_BASELINES[SLIDING_BASELINE][1]
    seed = search_seed(env.seed, f"{TRACKING} baseline")
    params, _ = tune(
        dataclasses.replace(env, objective="pq"), TRACKING, pipeline, space, "tracking: baseline clusterer", seed=seed
    )
    return params, "tuned for PQ on the training half by the tracking step"


def run_tracking(env, key, needed):
    """Every setting of :data:`TRACKED` the run has, streamed with the tuned Tracker on the test half; the baseline.

    The Tracker's and the baseline tracker's parameters are chosen on the training half (:data:`TUNED_FOR`);
    the first setting's tracked ids of the drawn test sequence (and its true objects) go to the figure.
    """
    found, lines, settings = {}, [], []
    for name in TRACKED:
        setting = setting_to_track(name, needed)
        if setting is None:
            continue
        refused = streamable(setting.pipeline)
        if refused is not None:
            lines.append(f"    {_name(name)} ({setting.source}) does not stream: {refused}")
            continue
        settings.append((name, setting))
    sliding_params, sliding_source = sliding_setting(env, needed)
    sliding = baseline_pipeline(SLIDING_BASELINE).set_params(**sliding_params)
    lead, learned = dict(settings).get(TRACKER_TUNED_ON), dict(settings).get(LEARNED)
    parts = env.sequences.map(
        tuning_parts,
        env.train,
        None if lead is None else lead.pipeline,
        sliding,
        None if learned is None else learned.pipeline,
        executor=env.executor,
    )
    tracker = None if lead is None else chosen_tracker(parts, "tracker", TRACKER_GRID, TRACKER_TUNED_ON)
    learned_tracker = None if learned is None else chosen_tracker(parts, LEARNED, TRACKER_GRID, LEARNED)
    baseline_tracker = chosen_tracker(parts, "baseline", BASELINE_GRID, SLIDING_BASELINE)
    tracker_params = {} if tracker is None else tracker.params
    drawn = {}
    for name, setting in settings:
        params = learned_tracker.params if name == LEARNED else tracker_params
        parts = env.sequences.map(track_sequence, env.test, setting.pipeline, params, env.drawn, executor=env.executor)
        found[name] = combine_tracking(setting, parts)
        if not drawn:
            drawn = next(part["drawn"] for part in parts if part["drawn"] is not None)
        lines.append(f"    {_name(name)} ({setting.source}): {_said(found[name].tracked)} with the Tracker")
    parts = env.sequences.map(
        baseline_sequence, env.test, sliding, baseline_tracker.params, env.drawn, executor=env.executor
    )
    baseline = BaselineTracking(
        clusterer=SLIDING_BASELINE,
        clusterer_params=sliding_params,
        clusterer_source=sliding_source,
        tracker=baseline_tracker,
        scores=combine_scores(parts),
    )
    lines.append(f"    baseline tracker: {_said(baseline.scores)}")
    result = TrackingStep(settings=found, tracker=tracker, baseline=baseline, learned_tracker=learned_tracker)
    return Outcome(result, "\n".join(lines), tracks=drawn or None)


def _name(key):
    return key if not key.isdigit() else f"#{key}"


def _said(scores):
    return f"MOTA {scores.mota:.3f}, IDF1 {scores.idf1:.3f}, HOTA {scores.hota:.3f}"
