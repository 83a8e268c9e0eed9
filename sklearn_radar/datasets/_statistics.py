"""Statistics of a detection data set, to judge at a glance whether it is realistic."""

from __future__ import annotations

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
    data, target = bunch.data, np.asarray(bunch.target)
    spans = data.groupby("sequence")["timestamp"].agg(["min", "max"])
    duration = float(((spans["max"] - spans["min"]) * 1e-6).sum())
    scans = data.groupby(["sequence", "timestamp"]).ngroups
    is_object = target >= 0
    objects = data.loc[is_object, ["sequence", "timestamp", "range_sc", "label_id"]].assign(instance=target[is_object])
    per_scan = objects.groupby(["instance", "timestamp"]).agg(
        count=("range_sc", "size"), range=("range_sc", "median"), label_id=("label_id", "first")
    )
    per_scan["class"] = per_scan["label_id"].map(LABELS)
    per_scan["range_bin"] = pd.cut(per_scan["range"], list(range_bins))
    table = per_scan.pivot_table(index="class", columns="range_bin", values="count", aggfunc="mean", observed=False)
    per_sequence = objects.groupby("sequence")["instance"].nunique()
    n_instances = len(np.unique(target[is_object]))
    mix = objects["label_id"].map(LABELS).value_counts(normalize=True).sort_index()
    summary = {
        "n_detections": len(data),
        "n_sequences": int(data["sequence"].nunique()),
        "duration_s": duration,
        "detections_per_second": len(data) / duration if duration > 0 else float("nan"),
        "scans": int(scans),
        "detections_per_scan": len(data) / max(scans, 1),
        "static_share": float(np.mean(target == -1)) if len(target) else float("nan"),
        "annotated_per_scan": int(is_object.sum()) / max(scans, 1),
        "instances": n_instances,
        "objects_per_sequence": float(per_sequence.mean()) if len(objects) else 0.0,
        "instances_per_minute": 60 * n_instances / duration if duration > 0 else float("nan"),
        "annotated_per_instance": int(is_object.sum()) / n_instances if n_instances else float("nan"),
        "class_mix": {str(name): float(share) for name, share in mix.items()},
    }
    return summary, table


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
        then the table with two decimals.

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
    lines += ["detections per object per scan (when detected), by range bin in m:", table.round(2).to_string()]
    return "\n".join(lines)
