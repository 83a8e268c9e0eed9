"""Statistics of a detection data set, to judge at a glance whether it is realistic."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from sklearn.utils._param_validation import validate_params

from .._schema import LABELS

#: Range bins (m) of :func:`scene_statistics`.
RANGE_BINS = (0.0, 10.0, 25.0, 50.0, 100.0)

#: Figures of the RadarScenes data set derived from its published numbers (radar-scenes.com, "Statistics":
#: about 4 million annotated detections, > 7,500 unique road users, > 4 h of 4 sensors with a cycle of about
#: 60 ms, i.e. about 960,000 scans).  Upper bounds where the published number is a lower bound ("> 4 h").
#: Total detections per scan and the class mix are published only as figures, not as numbers.
RADARSCENES_PUBLISHED = {
    "annotated_per_scan": 4.2,  # 4e6 / (4 h * 3600 s/h * 4 sensors / 0.060 s)
    "instances_per_minute": 31.0,  # 7,500 / (4 h * 60 min/h)
    "annotated_per_instance": 530.0,  # 4e6 / 7,500
}


@validate_params({"bunch": [dict], "range_bins": ["array-like"]}, prefer_skip_nested_validation=True)
def scene_statistics(bunch, range_bins=RANGE_BINS):
    """Summary figures of a data Bunch (simulated or loaded).

    Parameters
    ----------
    bunch : Bunch or dict
        As returned by :func:`make_scenes` or :func:`load_radarscenes`;
        needs ``data`` and ``target``.
    range_bins : array-like of float, default=(0, 10, 25, 50, 100)
        Increasing edges of the range bins, m.

    Returns
    -------
    summary : dict
        ``n_detections``, ``n_sequences``, ``duration_s`` (summed over
        sequences), ``detections_per_second``, ``scans``,
        ``detections_per_scan``, ``static_share`` (share of detections with
        target -1), ``annotated_per_scan`` (detections of road users per
        scan), ``instances`` (number of distinct targets),
        ``objects_per_sequence`` (mean), ``instances_per_minute``,
        ``annotated_per_instance`` and ``class_mix`` (share of the annotated
        detections per class name).  :data:`RADARSCENES_PUBLISHED` holds the
        RadarScenes figures of the same names.
    per_object_scan : DataFrame
        Mean number of detections of one object in one scan in which it is
        detected, by class (rows) and range bin of the object's median range
        in that scan (columns).  A count is missing where no object of that
        class was seen in that bin.

    See Also
    --------
    format_statistics : the figures as text.

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes, scene_statistics
    >>> summary, table = scene_statistics(make_scenes(n_sequences=1, duration=2.0, random_state=0))
    >>> summary["n_sequences"]
    1
    """
    # The whole data set as one part: one implementation of the figures for it and for merged parts.
    return combine_statistics([statistics_parts(bunch, range_bins)])


@validate_params({"summary": [dict], "table": [pd.DataFrame]}, prefer_skip_nested_validation=True)
def format_statistics(summary, table) -> str:
    """Human-readable text of :func:`scene_statistics` output.

    Parameters
    ----------
    summary : dict
        The first value :func:`scene_statistics` returns.
    table : DataFrame
        The second value :func:`scene_statistics` returns, detections per
        object per scan by class and range bin.

    Returns
    -------
    text : str
        One line per summary figure, with the RadarScenes figure
        (:data:`RADARSCENES_PUBLISHED`) beside it where one is published,
        then the table with two decimals ("-" where no object of the class
        was seen in the range, with a line that says so).

    Examples
    --------
    >>> from sklearn_radar.datasets import format_statistics, make_scenes, scene_statistics
    >>> text = format_statistics(*scene_statistics(make_scenes(n_sequences=1, duration=2.0, random_state=0)))
    >>> text.splitlines()[1]
    'sequences             1 (2.0 s in all)'
    """
    published = RADARSCENES_PUBLISHED
    lines = [
        f"detections            {summary['n_detections']}",
        f"sequences             {summary['n_sequences']} ({summary['duration_s']:.1f} s in all)",
        f"detections per second {summary['detections_per_second']:.0f}",
        f"detections per scan   {summary['detections_per_scan']:.1f} ({summary['scans']} scans)",
        f"static share          {100 * summary['static_share']:.1f} %",
        f"object instances      {summary['instances']} ({summary['objects_per_sequence']:.1f} per sequence)",
    ]
    if "annotated_per_scan" in summary:  # a summary read back from an older results.json lacks these
        mix = ", ".join(f"{name} {100 * share:.0f} %" for name, share in summary["class_mix"].items())
        lines += [
            f"annotated per scan    {summary['annotated_per_scan']:.1f} "
            f"(RadarScenes about {published['annotated_per_scan']:.1f})",
            f"instances per minute  {summary['instances_per_minute']:.1f} "
            f"(RadarScenes at most {published['instances_per_minute']:.0f})",
            f"annotated per instance {summary['annotated_per_instance']:.0f} "
            f"(RadarScenes about {published['annotated_per_instance']:.0f})",
            f"class mix (annotated) {mix or 'none'}",
        ]
    lines += [
        "detections per object per scan (when detected), by range bin in m:",
        table.round(2).to_string(na_rep="-"),
    ]
    if table.isna().to_numpy().any():
        lines.append("(-: no object of that class in that range)")
    return "\n".join(lines)


# ----------------------------------------------------------------------------
# Mergeable per-sequence summaries (the data never has to fit in one process)
# ----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StatisticsPart:
    """What :func:`scene_statistics` needs of one sequence (or of a block of whole sequences).

    Built by :func:`statistics_parts` where the sequence lives and merged by
    :func:`combine_statistics`.  Its size grows with the number of sequences
    it covers and with the number of classes times range bins, never with
    the number of detections or objects.

    Attributes
    ----------
    n_detections : int
        Rows of the part.
    n_static, n_annotated : int
        Rows with target -1 (background) and with target >= 0 (objects).
    instances : int
        Distinct object ids (target >= 0) of the part.
    sequences : DataFrame
        One row per sequence (index ``sequence``), columns ``first`` and
        ``last`` (timestamp, µs), ``scans`` (distinct timestamps) and
        ``objects`` (distinct object ids, 0 when it has none).
    classes : Series of int
        Annotated detections per class name (:data:`LABELS`), the counts of
        ``value_counts``.
    object_scans : DataFrame
        One row per (``label_id``, ``range_bin``) pair seen, with ``count``
        (sum over the (object, scan) pairs of their detections) and
        ``n`` (number of (object, scan) pairs); ``range_bin`` is NaN for an
        object whose median range lies outside the bins.
    range_bins : CategoricalDtype
        The range bins (intervals, m) the part was computed with, the
        dtype of ``pd.cut`` with the given edges.
    """

    n_detections: int
    n_static: int
    n_annotated: int
    instances: int
    sequences: pd.DataFrame
    classes: pd.Series
    object_scans: pd.DataFrame
    range_bins: pd.CategoricalDtype


def _object_scans(data, target, range_bins):
    """(object, scan) pairs of the objects: detections, median range (m), class, range bin; and the object rows."""
    is_object = target >= 0
    objects = data.loc[is_object, ["sequence", "timestamp", "range_sc", "label_id"]].assign(instance=target[is_object])
    per_scan = objects.groupby(["instance", "timestamp"]).agg(
        count=("range_sc", "size"), range=("range_sc", "median"), label_id=("label_id", "first")
    )
    per_scan["class"] = per_scan["label_id"].map(LABELS)
    per_scan["range_bin"] = pd.cut(per_scan["range"], list(range_bins))
    return objects, per_scan


@validate_params({"bunch": [dict], "range_bins": ["array-like"]}, prefer_skip_nested_validation=True)
def statistics_parts(bunch, range_bins=RANGE_BINS) -> StatisticsPart:
    """Summary of one sequence (or several whole ones) that :func:`combine_statistics` merges.

    Parameters
    ----------
    bunch : Bunch or dict
        The ``data`` (with ``sequence``, ``timestamp`` in µs, ``range_sc``
        in m and ``label_id``) and ``target`` of whole sequences, as
        :func:`make_scenes` or :func:`load_radarscenes` return them.
    range_bins : array-like of float, default=(0, 10, 25, 50, 100)
        Increasing edges of the range bins, m; every part of one data set
        needs the same.

    Returns
    -------
    part : StatisticsPart
        Small and picklable: a few counts, one row per sequence and one per
        (class, range bin) seen.

    See Also
    --------
    combine_statistics : merges the parts into :func:`scene_statistics`'s result.

    Notes
    -----
    Nothing of :func:`scene_statistics` needs per-object arrays across
    parts: the only median, the range of an object in one scan, is taken
    over that object's detections of that scan, which lie in one sequence,
    so it is computed here; the table then averages the detection counts
    of the (object, scan) pairs per (class, range bin) cell, which the sums
    and numbers of pairs per cell give exactly.  A part's size therefore
    grows with the number of its sequences (4 integers each) and of the
    (class, range bin) cells seen (at most one per label id times the bins plus
    one for "outside"), not with detections, scans or objects.  Objects
    are assumed not to span parts (see :func:`combine_statistics`).
    """
    data, target = bunch["data"], np.asarray(bunch["target"])
    if len(target) != len(data):
        raise ValueError(f"bunch: target has {len(target)} values for {len(data)} rows of data")
    if "sequence" not in data.columns:
        raise ValueError("bunch: data has no column 'sequence'")
    objects, per_scan = _object_scans(data, target, range_bins)
    by_sequence = data.groupby("sequence")["timestamp"]
    sequences = pd.DataFrame({"first": by_sequence.min(), "last": by_sequence.max(), "scans": by_sequence.nunique()})
    sequences["objects"] = objects.groupby("sequence")["instance"].nunique().reindex(sequences.index, fill_value=0)
    codes = per_scan["range_bin"].cat.codes.to_numpy()  # -1: outside the bins
    object_scans = (
        pd.DataFrame({"label_id": per_scan["label_id"].to_numpy(), "code": codes, "count": per_scan["count"]})
        .groupby(["label_id", "code"])["count"]
        .agg(count="sum", n="size")
        .reset_index()
    )
    is_object = target >= 0
    return StatisticsPart(
        n_detections=len(data),
        n_static=int(np.count_nonzero(target == -1)),
        n_annotated=int(np.count_nonzero(is_object)),
        instances=len(np.unique(target[is_object])),
        sequences=sequences,
        classes=objects["label_id"].map(LABELS).value_counts(),
        object_scans=object_scans,
        range_bins=per_scan["range_bin"].dtype,
    )


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_statistics(parts):
    """Merge :func:`statistics_parts` of whole sequences into :func:`scene_statistics`'s result.

    The result equals ``scene_statistics`` of the concatenated sequences:
    counts exactly, the floats bit for bit (they are computed from the same
    integer counts in the same order), and the table with the same index,
    columns and dtypes.  Objects never span parts: each part's object ids
    are its own (as :func:`load_radarscenes` and :func:`make_scenes` number
    them uniquely across sequences, and as a sequence loaded alone numbers
    them from 0), so ``instances`` is the sum over the parts.

    Parameters
    ----------
    parts : list of StatisticsPart
        One per sequence (or block of whole sequences), in any order; no
        sequence in two parts, all with the same range bins.

    Returns
    -------
    summary : dict
        As :func:`scene_statistics` returns it.
    per_object_scan : DataFrame
        Mean detections of one object per scan in which it is detected, by
        class and range bin (m), as :func:`scene_statistics` returns it.

    Raises
    ------
    ValueError
        If ``parts`` is empty, holds something else than parts, a sequence
        lies in two parts, or the parts' range bins differ.
    """
    parts = list(parts)
    if not parts:
        raise ValueError("parts must not be empty: give one statistics_parts(...) per sequence")
    if not all(isinstance(part, StatisticsPart) for part in parts):
        kinds = sorted({type(part).__name__ for part in parts if not isinstance(part, StatisticsPart)})
        raise ValueError(f"parts must hold statistics_parts(...) results, got {kinds}")
    dtype = parts[0].range_bins
    if any(part.range_bins != dtype for part in parts):
        raise ValueError("parts: computed with different range_bins; give every part the same edges")
    sequences = pd.concat([part.sequences for part in parts]).sort_index(kind="stable")
    if sequences.index.has_duplicates:
        repeated = sorted(set(sequences.index[sequences.index.duplicated()].tolist()))
        raise ValueError(f"parts: sequence(s) {repeated} lie in more than one part; split the data by sequence")

    n_detections = sum(part.n_detections for part in parts)
    n_annotated = sum(part.n_annotated for part in parts)
    n_static = sum(part.n_static for part in parts)
    n_instances = sum(part.instances for part in parts)
    duration = float(((sequences["last"] - sequences["first"]) * 1e-6).sum())
    scans = int(sequences["scans"].sum())
    per_sequence = sequences.loc[sequences["objects"] > 0, "objects"]
    classes = pd.concat([part.classes for part in parts])
    classes = classes.groupby(level=0).sum() if len(classes) else classes
    mix = (classes / classes.sum()).sort_index()
    summary = {
        "n_detections": n_detections,
        "n_sequences": len(sequences),
        "duration_s": duration,
        "detections_per_second": n_detections / duration if duration > 0 else float("nan"),
        "scans": scans,
        "detections_per_scan": n_detections / max(scans, 1),
        "static_share": n_static / n_detections if n_detections else float("nan"),
        "annotated_per_scan": n_annotated / max(scans, 1),
        "instances": n_instances,
        "objects_per_sequence": float(per_sequence.mean()) if n_annotated else 0.0,
        "instances_per_minute": 60 * n_instances / duration if duration > 0 else float("nan"),
        "annotated_per_instance": n_annotated / n_instances if n_instances else float("nan"),
        "class_mix": {str(name): float(share) for name, share in mix.items()},
    }

    # The table is a mean per (class, range bin) cell: the parts' sums and counts give it exactly.  One row per
    # cell with that mean, pivoted as scene_statistics pivots its (object, scan) rows, gives the same layout.
    cells = pd.concat([part.object_scans for part in parts]).groupby(["label_id", "code"], as_index=False).sum()
    per_scan = pd.DataFrame(
        {
            "count": cells["count"].to_numpy(dtype=np.float64) / cells["n"].to_numpy(dtype=np.float64),
            "label_id": cells["label_id"].to_numpy(),
        }
    )
    per_scan["class"] = per_scan["label_id"].map(LABELS)
    per_scan["range_bin"] = pd.Categorical.from_codes(cells["code"].to_numpy(), dtype=dtype)
    table = per_scan.pivot_table(index="class", columns="range_bin", values="count", aggfunc="mean", observed=False)
    return summary, table
