"""Calibration figures of the simulator's difficulty presets against published numbers.

Run: ``python benchmarks/calibrate_simulator.py [--difficulty realistic] [--seeds 0 1]``.

For each seed it simulates the default ``reproduce`` data (4 sequences x 20 s)
and prints, beside the paper's figures,

* the V1 of the paper's expert setting #1 (CCS, filtered, not tuned) on the
  held-out half, as ``sklearn-radar reproduce --experiments 1`` scores it
  (paper: 67.57 %);
* the share of background the filter removes at the paper's FCS default
  eta=0.10 m/s, d_xy=1.4 m, and its error count (paper: 29.10 %, 0 errors);
* the realism statistics of ``sklearn-radar stats``;

and then issue 32's table over the seeds: instances per minute, annotated
detections per instance and per scan, V1 of #1, the filter's removal and
error windows, each beside its published value with its mean and whether the
mean is on target, and the class mix.  ``--difficulty radarscenes --seeds 0 1
2 3 4`` gives the table of the user guide's "Towards RadarScenes'
statistics"; ``--n-sequences 17 --duration 30`` the data of
``reproduce --full``; ``--effects`` each knob's effect instead: the same
means with each knob in which the preset differs from "realistic" set back
to its realistic value, one at a time (and the box annotator on).

Nothing here tunes a clusterer: the settings are the paper's.
"""

import argparse
import ast
import sys
import time

import numpy as np

from sklearn_radar.datasets import make_scenes, scene_statistics
from sklearn_radar.evaluation import filter_settings_table
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import precluster_target, radar_v_measure
from sklearn_radar.model_selection import sequence_train_test_split


def figures(scenes, seed):
    target = precluster_target(scenes.data, scenes.target)
    X = scenes.data[[c for c in scenes.data.columns if c not in ("uuid", "track_id", "label_id")]]
    _, test = sequence_train_test_split(scenes.groups, random_state=seed)
    labels = experiment_pipeline(1).fit_predict(X.iloc[test])
    v1 = radar_v_measure(target[test], labels, groups=scenes.groups[test])
    table = filter_settings_table(scenes.data, scenes.target)
    fcs = table[(table["frame"] == "frame") & np.isclose(table["vr_threshold"], 0.10) & np.isclose(table["d_xy"], 1.4)]
    summary, _ = scene_statistics(scenes)
    static = scenes.data["label_id"].to_numpy() == 11
    p90 = float(np.quantile(np.abs(scenes.data["vr_compensated"].to_numpy()[static]), 0.9))
    return {
        "instances_per_minute": summary["instances_per_minute"],
        "annotated_per_instance": summary["annotated_per_instance"],
        "annotated_per_scan": summary["annotated_per_scan"],
        "class_mix": {name: 100 * share for name, share in summary["class_mix"].items()},
        "v1_expert_1": 100 * v1,
        "fcs_removed": float(fcs["removal_rate"].iloc[0]),
        "fcs_errors": int(fcs["errors"].iloc[0]),
        "det_per_scan": summary["detections_per_scan"],
        "annotated": 100 * (1 - summary["static_share"]),
        "static_vr_p90": p90,
        "table_ii": table,
    }


#: The targets of issue 32: (key of ``figures``, label, published value, the band the calibration aims at).
TARGETS = (
    ("instances_per_minute", "instances per minute", "at most 31 (RadarScenes)", (24.8, 37.2)),
    ("annotated_per_instance", "annotated detections per instance", "about 530 (RadarScenes)", (424.0, 636.0)),
    ("annotated_per_scan", "annotated detections per scan", "about 4.2 (RadarScenes)", (3.36, 5.04)),
    ("v1_expert_1", "expert #1 V1, %", "67.57 (paper)", (60.0, 75.0)),
    ("fcs_removed", "background removed at FCS 0.10/1.4, %", "29.10 (paper)", (25.0, 35.0)),
    ("fcs_errors", "filter error windows at FCS 0.10/1.4", "0 (paper)", (0.0, 0.0)),
)


def issue_table(results, seeds, difficulty):
    """Issue 32's table: each statistic per seed, their mean, the published value and whether the mean is on target."""
    lines = [
        f"| statistic | published | {difficulty}: seeds {', '.join(map(str, seeds))} | mean | on target |",
        "|---|---|---|---|---|",
    ]
    for key, label, published, (low, high) in TARGETS:
        values = [f[key] for f in results]
        mean = float(np.mean(values))
        shown = ", ".join(f"{v:.1f}" if key != "fcs_errors" else str(v) for v in values)
        lines.append(f"| {label} | {published} | {shown} | {mean:.1f} | {'yes' if low <= mean <= high else 'no'} |")
    classes = sorted({name for f in results for name in f["class_mix"]})
    mix = {name: np.mean([f["class_mix"].get(name, 0.0) for f in results]) for name in classes}
    lines.append(
        "| class mix of annotated detections, % | figures only | - | "
        + ", ".join(f"{name} {share:.1f}" for name, share in mix.items())
        + " | - |"
    )
    return "\n".join(lines)


#: The knob a preset leaves off but whose effect the table shows: a box annotator's labels (0.2 m).
EXTRA_EFFECTS = {"annotation_margin": 0.2}


def knob_effects(difficulty, seeds, n_sequences, duration):
    """Each knob's effect: the means over ``seeds`` with the knob set back to its realistic value, one at a time."""
    from sklearn_radar.datasets._presets import DIFFICULTY_PRESETS

    preset, realistic = DIFFICULTY_PRESETS[difficulty], DIFFICULTY_PRESETS["realistic"]
    changes = {"none": {}}
    changes.update(
        {f"{k} {preset[k]:g} -> {realistic[k]:g}": {k: realistic[k]} for k in preset if preset[k] != realistic[k]}
    )
    changes.update({f"{k} {preset[k]:g} -> {v:g}": {k: v} for k, v in EXTRA_EFFECTS.items() if preset[k] != v})
    keys = [key for key, *_ in TARGETS]
    lines = [
        f"| change ({difficulty}, {n_sequences} x {duration:g} s, seeds {', '.join(map(str, seeds))}) | "
        + " | ".join(label for _, label, *_ in TARGETS)
        + " |",
        "|---" * (len(TARGETS) + 1) + "|",
    ]
    for name, knobs in changes.items():
        rows = [
            figures(make_scenes(n_sequences, duration, random_state=s, difficulty=difficulty, knobs=knobs), s)
            for s in seeds
        ]
        means = [float(np.mean([f[k] for f in rows])) for k in keys]
        lines.append(
            f"| {name} | "
            + " | ".join(
                f"{m:.1f}" if k != "annotated_per_scan" else f"{m:.2f}" for k, m in zip(keys, means, strict=True)
            )
            + " |"
        )
        print(lines[-1], file=sys.stderr, flush=True)
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--difficulty", default="realistic")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--table", action="store_true", help="print the whole Table II")
    parser.add_argument("--ablation", action="store_true", help="each knob of the preset alone on the easy data")
    parser.add_argument("--knobs", default="{}", help="knob overrides, a Python dict literal")
    parser.add_argument(
        "--effects",
        action="store_true",
        help="each knob in which the preset differs from realistic set back to its realistic value, one at a time",
    )
    args = parser.parse_args()
    if args.effects:
        print(knob_effects(args.difficulty, args.seeds, args.n_sequences, args.duration))
        return
    if args.ablation:
        from sklearn_radar.datasets._presets import DIFFICULTY_PRESETS

        groups = {
            "ego-motion": [k for k in DIFFICULTY_PRESETS["easy"] if k.startswith("odometry")],
            "mounting": ["mounting_error"],
            "time_offset": ["time_offset"],
            "multipath": ["multipath", "second_bounce"],
            "clutter": ["rain", "spray", "sidelobes"],
            "traffic": ["traffic", "occlusion"],
            "sensing": ["detection_range", "angular_noise_range", "rcs_fluctuation"],
            "signatures": ["rcs_object_spread", "rcs_aspect", "wheel_micro_doppler"],
        }
        for name, knobs in groups.items():
            values = {k: DIFFICULTY_PRESETS["realistic"][k] for k in knobs}
            for seed in args.seeds:
                scenes = make_scenes(args.n_sequences, args.duration, random_state=seed, knobs=values)
                f = figures(scenes, seed)
                print(
                    f"only {name:<12} seed {seed}: V1 #1 {f['v1_expert_1']:.2f} % | FCS removes "
                    f"{f['fcs_removed']:.2f} %, {f['fcs_errors']} errors | {f['det_per_scan']:.1f} det/scan, "
                    f"{f['annotated']:.1f} % annotated, static |vr_comp| p90 {f['static_vr_p90']:.3f} m/s",
                    flush=True,
                )
        return
    kwargs = (
        {} if args.difficulty == "today" else {"difficulty": args.difficulty, "knobs": ast.literal_eval(args.knobs)}
    )
    results = []
    for seed in args.seeds:
        start = time.perf_counter()
        scenes = make_scenes(args.n_sequences, args.duration, random_state=seed, **kwargs)
        simulated = time.perf_counter() - start
        f = figures(scenes, seed)
        print(
            f"{args.difficulty} seed {seed}: {len(scenes.data)} det ({simulated:.1f} s) | "
            f"V1 #1 {f['v1_expert_1']:.2f} % "
            f"(paper 67.57) | FCS 0.10/1.4 removes {f['fcs_removed']:.2f} % (paper 29.10), {f['fcs_errors']} errors "
            f"| {f['det_per_scan']:.1f} det/scan, {f['annotated']:.1f} % annotated, static |vr_comp| p90 "
            f"{f['static_vr_p90']:.3f} m/s"
        )
        if args.table:
            print(f["table_ii"].to_string())
        results.append(f)
    print(issue_table(results, args.seeds, args.difficulty))


if __name__ == "__main__":
    main()
