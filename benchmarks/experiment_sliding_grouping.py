"""The learned grouping re-formed at every scan from its recent links (issue #44): a prototype beside the causal one.

The causal agglomeration of ``LinkClustering(causal=True)`` accumulates the link evidence between two clusters over
their whole lives, and a merge is for good: two road users whose clusters once merged stay one while either is seen
(the largest kind of the stream's misses, ``docs/user_guide/online.rst``, "Limiting a cluster's extent").  This
prototype keeps the fitted model's causal links and changes only how they become clusters: at every scan time
``now``, the detections above the objectness threshold of the last ``--length`` s are clustered afresh by the
offline mean-link agglomeration (``_agglomeration.mean_link_merges``) of the candidate pairs among them, and each
cluster takes the id that most of its detections had at the previous time (the Hungarian method on the counts; a
cluster left over gets a new id).  A wrong merge thus ends as soon as the recent links no longer join the two, and
the new scan's detections are labelled with their cluster's id (causal: nothing after ``now`` is used).

Only the clusters that the new scan can change are formed again: two clusters merge only while their mean link
exceeds the threshold, so only if some pair between them does, and the clustering splits over the components of the
pairs above the threshold.  The components that hold a new detection, and those that share an id with them, are
clustered; the others keep their ids.  The time of that step per scan is printed (a Python prototype: what a
compiled version in the library would have to beat is the 1 ms of the whole pipeline).

Per preset and seed: the data of ``experiment_tracking_errors.py`` (``make_scenes``, the same split,
``--extra-training`` as there), the main job's causal model fitted on the training half with the pre-clustered target,
and its causal links on both halves.  Two forms of ids from the same links: ``causal``, the causal agglomeration scan
by scan (``_causal_agglomeration.step``: the ids ``OnlinePipeline`` reports, up to their numbers; ``--check-stream``
replays the stream to check it), a cluster confirmed when it has ``min_cluster_size`` detections; and ``sliding``, a
cluster confirmed when its id has had that many.  Each form is given the same choice: the link threshold and
``min_cluster_size`` that ``fit`` tuned, and every pair of ``--thresholds`` x ``--sizes``; the pair with the best
training MOTA of the Tracker at its defaults on the confirmed ids is kept, then the Tracker is tuned on them
(``experiment_tracking.tuned_tracker``: the defaults and ``--n-settings`` random settings, best training MOTA) and
scored on the test half's.  The reported ids' missed object-frames (0.5 s window and moving road user, matched when
one id covers it with IoU > 0.5) are counted by kind: ``merge`` (the id covering most of the road user also holds
others, IoU <= 0.5), ``fragment`` (no id covers half of it) and ``unclustered`` (no id on it).

Run (2-3 minutes per preset and seed on one core; records ``benchmarks/results/sliding_grouping/``)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_sliding_grouping.py --data realistic radarscenes \\
        --seeds 0 1 2 3 4 --save benchmarks/results/sliding_grouping
    python benchmarks/experiment_sliding_grouping.py --summary --save benchmarks/results/sliding_grouping
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from sklearn.metrics import adjusted_rand_score

sys.path.insert(0, str(Path(__file__).parent))

from experiment_tracking import (
    LABEL_COLUMNS,
    LEARNED_CAUSAL,
    TRACKER_SPACE,
    _mean_se,
    fixed_frame,
    scores,
    track,
    tuned_tracker,
)
from experiment_tracking_errors import _windows, data_arguments, labelled_model, parsed, records

from sklearn_radar._validation import read_columns
from sklearn_radar.cluster import _link_clustering
from sklearn_radar.cluster._agglomeration import mean_link_merges, roots_at
from sklearn_radar.cluster._causal_agglomeration import new_state, step
from sklearn_radar.metrics import tracking_scores
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay
from sklearn_radar.reproduce._learned import LEARNED_CAUSAL_PARAMS, LEARNED_PARAMS

FORMS = ("causal", "sliding")
#: The learned grouping whose links see both sides of each detection, with the causal model's capacity and filter
#: (``reproduce/_learned.py``: LEARNED_PARAMS, the window, LEARNED_CAUSAL_PARAMS's trees and the causal Doppler-density
#: filter; every candidate pair, as ``causal=False`` requires).
OFFLINE = {
    **LEARNED_PARAMS,
    **{k: v for k, v in LEARNED_CAUSAL_PARAMS.items() if k != "link__max_links_per_detection"},
    "link__window": 0.5,
    "filter__causal": True,
}
MISS_KINDS = ("merge", "fragment", "unclustered")


def fitted(preset, seed, options, causal=True, check_stream=False):
    """Per half, per sequence: fixed-frame columns, truth and the model's causal links (``t``, ``x``, ``y`` of the kept
    detections in the estimator's order, ``node``, pairs ``i``, ``j``, ``p``, and ``rows``: their rows of the
    sequence); the fitted link threshold, ``min_cluster_size`` and pair window.

    ``causal=False``: a model that sees both sides of each detection instead (``OFFLINE``), its links (of features
    that see 0.15 s past each detection, :data:`~sklearn_radar.cluster._link_features.LOCAL_WINDOW`) and its labels
    (``offline``).  ``check_stream``: replay ``OnlinePipeline`` on each sequence and check that :func:`causal_ids`
    gives its reported ids (causal links only).
    """
    labelled, model = labelled_model(preset, seed, options, params=LEARNED_CAUSAL if causal else OFFLINE)
    link = model[-1]
    halves = {"train": [], "test": []}
    for frame, truth, half in labelled:
        groups = frame["sequence"].to_numpy()
        for sequence in np.unique(groups):
            data = frame[groups == sequence].reset_index(drop=True)
            part = fixed_frame(data)
            part.update(sequence=np.full(len(data), sequence), truth=truth[groups == sequence])
            working = model[:-1].transform(data.drop(columns=list(LABEL_COLUMNS)))
            _, columns = read_columns(link, working, _link_clustering.LINK_READS, reset=False)
            (kept,) = _link_clustering._sequences(columns, causal=causal)
            objectness, i, j, p = link._probabilities(kept, link.objectness_threshold_)
            d = kept.detections
            node = objectness > link.objectness_threshold_
            part["links"] = {"rows": kept.rows, "t": d.t, "x": d.x, "y": d.y, "node": node, "i": i, "j": j, "p": p}
            if not causal:
                part["offline"] = model.predict(data.drop(columns=list(LABEL_COLUMNS)))
            elif check_stream:  # the causal ids computed here are the stream's reported ids
                reported = replay(OnlinePipeline(model), data)["reported"]
                mine, _ = causal_ids(part["links"], len(data), link.link_threshold_, link.pair_window)
                if adjusted_rand_score(reported, mine) != 1.0:
                    raise AssertionError(
                        f"{preset} seed {seed} sequence {sequence}: causal ids differ from the stream's"
                    )
            halves[half].append(part)
    return halves, {
        "link_threshold": float(link.link_threshold_),
        "min_cluster_size": int(link.min_cluster_size_),
        "pair_window": float(link.pair_window),
    }


def scans(links):
    """Per scan time with a detection above the objectness threshold: the time, the bounds ``start``, ``end`` of its
    detections in ``links`` (sorted by time) and those of them above the threshold."""
    t, node = links["t"], links["node"]
    times, first = np.unique(t, return_index=True)
    ends = np.r_[first[1:], len(t)]
    for now, start, end in zip(times, first, ends, strict=True):
        new = np.arange(start, end)
        new = new[node[new]]
        if len(new):
            yield now, start, end, new


def causal_ids(links, n_rows, threshold, window):
    """Id of each row at its scan time by the causal agglomeration (-1 for noise), and its cluster's size then: what
    ``OnlinePipeline`` reports (the cluster's oldest node, renumbered there), from ``_causal_agglomeration.step``."""
    i, j, p = links["i"], links["j"], links["p"]
    n = len(links["t"])
    state = new_state()
    ids, sizes = np.full(n, -1, dtype=np.int64), np.zeros(n, dtype=np.int64)
    for now, start, end, new in scans(links):
        pairs = slice(*np.searchsorted(j, [start, end]))  # the pairs end at their j, in the order of j
        clusters, counts, _, _ = step(state, now, new, i[pairs], j[pairs], p[pairs], window, threshold)
        ids[new], sizes[new] = clusters, counts
    out, size = np.full(n_rows, -1, dtype=np.int64), np.zeros(n_rows, dtype=np.int64)
    out[links["rows"]], size[links["rows"]] = ids, sizes
    return out, size


def sliding_ids(links, n_rows, threshold, length, lag=0.0):
    """Id of each row by the sliding re-clustering (-1 for noise), and the step's seconds per scan.

    A row's id is the one its cluster has at the last step within ``lag`` s of its scan time (0: at its scan).
    """
    t, node, i, j, p = links["t"], links["node"], links["i"], links["j"], links["p"]
    n = len(t)
    late, early = np.maximum(t[i], t[j]), np.minimum(t[i], t[j])
    previous = np.full(n, -1, dtype=np.int64)  # each detection's id at the last time its cluster was formed
    out = np.full(n, -1, dtype=np.int64)
    seconds = []
    next_id = 0
    oldest = 0
    by_late = np.argsort(late, kind="stable")  # pairs by their later end: those up to now are a prefix
    late_sorted = late[by_late]
    for now, _, end, new in scans(links):
        start = time.perf_counter()
        while t[oldest] <= now - length:
            oldest += 1
        window = np.arange(oldest, end)
        window = window[node[window]]
        pairs = by_late[: np.searchsorted(late_sorted, now, side="right")]
        pairs = pairs[early[pairs] > now - length]
        local = np.full(n, -1, dtype=np.int64)
        local[window] = np.arange(len(window))
        a, b, q = local[i[pairs]], local[j[pairs]], p[pairs]
        inside = (a >= 0) & (b >= 0)
        a, b, q = a[inside], b[inside], q[inside]
        strong = q > threshold
        graph = coo_matrix((np.ones(strong.sum()), (a[strong], b[strong])), shape=(len(window), len(window)))
        _, component = connected_components(graph, directed=False)
        # the components of the new detections, and those sharing an id with them
        touched = np.isin(component, component[local[new]])
        ids = previous[window]
        shared = np.isin(ids, ids[touched & (ids >= 0)]) & (ids >= 0)
        touched |= np.isin(component, component[shared])
        members = np.flatnonzero(touched)
        renumber = np.full(len(window), -1, dtype=np.int64)
        renumber[members] = np.arange(len(members))
        ra, rb = renumber[a], renumber[b]
        keep = (ra >= 0) & (rb >= 0)
        child, survivor, link = mean_link_merges(len(members), ra[keep], rb[keep], q[keep], threshold)
        roots = roots_at(len(members), child, survivor, link, threshold)
        clusters, of_member = np.unique(roots, return_inverse=True)
        before = ids[members]
        given = np.full(len(clusters), -1, dtype=np.int64)
        had = before >= 0
        if had.any():
            old, of_old = np.unique(before[had], return_inverse=True)
            overlap = np.zeros((len(clusters), len(old)))
            np.add.at(overlap, (of_member[had], of_old), 1.0)
            rows, cols = linear_sum_assignment(-overlap)
            matched = overlap[rows, cols] > 0
            given[rows[matched]] = old[cols[matched]]
        for c in np.flatnonzero(given < 0):
            given[c] = next_id
            next_id += 1
        previous[window[members]] = given[of_member]
        recent = new if lag == 0 else window[t[window] >= now - lag]
        out[recent] = previous[recent]
        seconds.append(time.perf_counter() - start)
    ids = np.full(n_rows, -1, dtype=np.int64)
    ids[links["rows"]] = out
    return ids, seconds


def confirmed_of(ids, t, min_size, lag=0.0):
    """The ids of the rows whose id has ``min_size`` detections up to ``lag`` s after their scan, -1 otherwise."""
    order = np.lexsort((np.arange(len(t)), t))
    seen, confirmed = {}, np.full(len(t), -1, dtype=np.int64)
    times = t[order]
    bounds = np.flatnonzero(np.r_[True, times[1:] != times[:-1], True])
    counted = 0  # the scans whose ids are counted in seen
    for a, b in itertools.pairwise(bounds):
        while counted < len(bounds) - 1 and times[bounds[counted]] <= times[a] + lag:
            scan = order[bounds[counted] : bounds[counted + 1]]
            for g in ids[scan][ids[scan] >= 0].tolist():
                seen[g] = seen.get(g, 0) + 1
            counted += 1
        for r in order[a:b][ids[order[a:b]] >= 0].tolist():
            if seen[ids[r]] >= min_size:
                confirmed[r] = ids[r]
    return confirmed


def miss_kinds(part, ids):
    """The reported ids' missed object-frames of one sequence by kind (:data:`MISS_KINDS`), and all object-frames."""
    window, truth = _windows(part), part["truth"]
    counts = dict.fromkeys((*MISS_KINDS, "object_frames"), 0)
    for road_user in np.unique(truth[truth >= 0]):
        own = truth == road_user
        for w in np.unique(window[own]):
            inside, here = own & (window == w), window == w
            counts["object_frames"] += 1
            best, kind = 0.0, "unclustered"
            for k in np.unique(ids[inside & (ids >= 0)]):
                predicted = here & (ids == k)
                iou = (inside & predicted).sum() / (inside | predicted).sum()
                if iou > best:
                    best = iou
                    kind = "merge" if (inside & predicted).sum() * 2 > inside.sum() else "fragment"
            if best <= 0.5:
                counts[kind] += 1
    return counts


def pair_grid(model, options):
    """(link threshold, ``min_cluster_size``) pairs to choose from: the fitted one first, then ``--thresholds`` x
    ``--sizes``."""
    grid = [(model["link_threshold"], model["min_cluster_size"])]
    return grid + [(value, size) for value in options.thresholds for size in options.sizes if (value, size) != grid[0]]


def chosen_and_scored(train, test, grid, labelled, options, seed):
    """One form's record: the (link threshold, ``min_cluster_size``) of ``grid`` with the best training MOTA of the
    Tracker at its defaults, the Tracker then tuned on the training half, its test scores and the misses by kind.

    ``labelled(part, threshold, min_cluster_size)`` sets the part's ``ids`` and ``confirmed`` ids.
    """
    truth = np.concatenate([p["truth"] for p in train])
    times = np.concatenate([p["t"] for p in train])
    groups = np.concatenate([p["sequence"] for p in train])
    best = None
    for value, size in grid:
        for part in (*train, *test):
            labelled(part, value, size)
        ids = track(train, Tracker, lambda p: p["confirmed"])
        mota = tracking_scores(truth, ids, times=times, groups=groups, window=0.5)["mota"]
        if best is None or mota > best["default_tracker_mota"]:
            best = {"threshold": value, "min_cluster_size": size, "default_tracker_mota": mota}
            best["parts"] = [(p["ids"], p["confirmed"]) for p in (*train, *test)]
    for part, (ids, confirmed) in zip((*train, *test), best.pop("parts"), strict=True):
        part["ids"], part["confirmed"] = ids, confirmed
    mota, setting = tuned_tracker(train, Tracker, lambda p: p["confirmed"], TRACKER_SPACE, options.n_settings, seed)
    tested = scores(test, track(test, lambda s=setting: Tracker(**s), lambda p: p["confirmed"]))
    misses = Counter()
    for part in test:
        misses.update(miss_kinds(part, part["ids"]))  # (update keeps the kinds counted 0)
    return {**best, "train_mota": mota, "setting": setting, "scores": tested, "misses": dict(misses)}


def measure(preset, seed, options):
    """Both forms' chosen thresholds, tracked test scores and reported miss kinds, for one data set."""
    start = time.perf_counter()
    halves, model = fitted(preset, seed, options, check_stream=options.check_stream)
    record = {"model": model}
    train, test = halves["train"], halves["test"]
    grid = pair_grid(model, options)
    seconds = []
    for form in FORMS:

        def labelled(part, value, size, form=form):
            if form == "causal":
                part["ids"], at_time = causal_ids(part["links"], len(part["t"]), value, model["pair_window"])
                part["confirmed"] = np.where(at_time >= size, part["ids"], -1)
            else:
                part["ids"], spent = sliding_ids(part["links"], len(part["t"]), value, options.length)
                part["confirmed"] = confirmed_of(part["ids"], part["t"], size)
                seconds.extend(spent)

        record[form] = chosen_and_scored(train, test, grid, labelled, options, seed)
    record["step_us"] = {"p50": float(np.median(seconds) * 1e6), "p99": float(np.percentile(seconds, 99) * 1e6)}
    record["seconds"] = time.perf_counter() - start
    c, s = record["causal"], record["sliding"]
    print(
        f"{preset} seed {seed}: MOTA causal {c['scores']['mota']:.3f} ({c['threshold']}/{c['min_cluster_size']}) -> "
        f"sliding {s['scores']['mota']:.3f} ({s['threshold']}/{s['min_cluster_size']}); IDF1 "
        f"{c['scores']['idf1']:.3f} -> {s['scores']['idf1']:.3f} ({record['seconds']:.0f} s)",
        flush=True,
    )
    return record


def table(preset, runs):
    """Per form: test scores and the reported ids' misses by kind (shares of the object-frames), mean ± SE over
    seeds; the paired differences sliding - causal (± 2 SE)."""
    seeds = sorted(runs)
    lines = [f"\n{preset}: {len(seeds)} seed(s), test half; mean ± standard error"]
    header = ("MOTA", "IDF1", "HOTA", *(f"missed: {k}" for k in MISS_KINDS))
    lines.append(f"{'':<8} " + " ".join(f"{h:>20}" for h in header))
    values = {}
    for form in FORMS:
        cells = []
        for key in header:
            column = []
            for seed in seeds:
                row = runs[seed][form]
                if key.startswith("missed"):
                    column.append(row["misses"][key.split(": ")[1]] / row["misses"]["object_frames"])
                else:
                    column.append(row["scores"][key.lower()])
            values[form, key] = np.array(column)
            mean, se = _mean_se(column)
            cells.append(f"{mean:.3f} ± {se:.3f}")
        lines.append(f"{form:<8} " + " ".join(f"{c:>20}" for c in cells))
    cells = []
    for key in header:
        mean, se = _mean_se(values["sliding", key] - values["causal", key])
        cells.append(f"{mean:+.3f} ± {2 * se:.3f}")
    lines.append(f"{'diff.':<8} " + " ".join(f"{c:>20}" for c in cells) + "   (sliding - causal, ± 2 SE)")
    for form in FORMS:
        chosen = ", ".join(
            f"{runs[s][form]['threshold']}/{runs[s][form]['min_cluster_size']}"
            f" (fit: {runs[s]['model']['link_threshold']}/{runs[s]['model']['min_cluster_size']})"
            for s in seeds
        )
        lines.append(f"{form}: link threshold / min_cluster_size chosen per seed: {chosen}")
    p50 = np.median([runs[s]["step_us"]["p50"] for s in seeds])
    p99 = np.median([runs[s]["step_us"]["p99"] for s in seeds])
    lines.append(f"sliding step (Python prototype), per scan with new detections: p50 {p50:.0f} us, p99 {p99:.0f} us")
    return "\n".join(lines)


def _record_path(folder, preset, seed):
    return Path(folder) / f"sliding_{preset}_{seed}.json"


def choice_arguments(parser):
    """The arguments of the sliding re-clustering's window and of the choice of :func:`pair_grid`."""
    parser.add_argument("--length", type=float, default=0.5, help="s of links the sliding re-clustering sees")
    parser.add_argument("--thresholds", type=float, nargs="+", default=[0.5, 0.6, 0.7])
    parser.add_argument("--sizes", type=int, nargs="+", default=[3, 6], help="min_cluster_size values tried")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    data_arguments(parser)
    choice_arguments(parser)
    parser.add_argument(
        "--check-stream", action="store_true", help="check the causal ids against OnlinePipeline's (slower)"
    )
    options = parsed(parser, argv)
    for preset in options.presets:
        runs = records(options, preset, measure, _record_path)
        if runs:
            print(table(preset, runs), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
