"""The tracking step: settings of the run streamed through the online pipeline, their object ids scored over time.

Each setting of :data:`~._constants.TRACKED` (the run's tuned one where its experiment ran, the paper's otherwise)
is replayed scan by scan through :class:`~sklearn_radar.online.OnlinePipeline` on every test sequence, where it
lives, and :func:`~sklearn_radar.metrics.tracking_scores` scores the ids per 0.5 s time window (:ref:`online-speed`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..experiments import experiment_pipeline, get_experiment, paper_params
from ..experiments._saved import setting_pipeline
from ..metrics import tracking_scores
from ..metrics._tracking import _scores
from ..online import OnlinePipeline
from ..online._replay import replay
from ._constants import SCORE_WINDOW_S
from ._records import JsonRecord, record

#: The counts of :func:`tracking_scores` that add up over sequences.
_COUNTS = ("id_switches", "misses", "false_positives", "n_objects", "n_matches", "idtp", "idfp", "idfn", "n_windows")


@record
class TrackingScores(JsonRecord):
    """How well object ids follow the moving road users over time (:func:`~sklearn_radar.metrics.tracking_scores`).

    Summed over the test sequences (a track never crosses sequences, so the
    identity assignment, and every count, is the sum of the sequences').

    Attributes
    ----------
    window_s : float
        Window length, s.
    mota, idf1 : float
        From the summed counts; NaN without ground-truth objects.
    id_switches, misses, false_positives, n_objects, n_matches, idtp, idfp, idfn, n_windows : int
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


@record
class TrackingResult(JsonRecord):
    """One setting streamed through :class:`~sklearn_radar.online.OnlinePipeline` on the test half (``tracking``).

    Attributes
    ----------
    number : int
        The experiment whose setting streams.
    method : str
    setting_source : str
        ``"tuned #13"`` or ``"fixed #1"`` (the run's setting), ``"paper's #13"`` (the experiment did not run).
    params : dict
        The setting, as pipeline parameters (stage 1's included for stage 2).
    reported : TrackingScores
        The ids as given with each detection when its scan was labelled.
    final : TrackingScores
        The ids after every alias (stage-1 meetings, stage-2 merges) resolved to the surviving one.
    n_scans : int
    n_aliases : int
        Merges reported as aliases, summed over the test sequences.
    """

    number: int
    method: str
    setting_source: str
    params: dict[str, Any]
    reported: TrackingScores
    final: TrackingScores
    n_scans: int
    n_aliases: int


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


def track_sequence(sequence, pipeline):
    """One test sequence streamed: the counts of its reported and its final ids, its scans and aliases."""
    data = sequence.scenes.data
    replayed = replay(OnlinePipeline(pipeline), data)
    times = data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    truth = np.asarray(sequence.scenes.target)
    found = {"n_scans": len(replayed["latency"]), "n_aliases": len(replayed["aliases"])}
    for name, ids in (("reported", replayed["reported"]), ("final", replayed["object_ids"])):
        scores = tracking_scores(truth, ids, times=times, window=SCORE_WINDOW_S)
        found[name] = {count: scores[count] for count in _COUNTS}
    return found


def combine_tracking(number, params, source, parts):
    """The :class:`TrackingResult` of a setting from its sequences' parts (their counts summed)."""

    def scores(name):
        total = {count: sum(part[name][count] for part in parts) for count in _COUNTS}
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
        return TrackingScores(window_s=SCORE_WINDOW_S, **{name: figures[name] for name in ("mota", "idf1")}, **total)

    return TrackingResult(
        number=number,
        method=get_experiment(number).method,
        setting_source=source,
        params=params,
        reported=scores("reported"),
        final=scores("final"),
        n_scans=sum(part["n_scans"] for part in parts),
        n_aliases=sum(part["n_aliases"] for part in parts),
    )
