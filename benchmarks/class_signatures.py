"""What each simulated road-user class looks like to a classifier: the class signatures of the simulator.

Run: ``python benchmarks/class_signatures.py [--seeds 0 1 2] [--n-sequences 4] [--duration 20]
[--difficulty realistic] [--knobs "{...}"] [--before]``.

For each class of the simulator (by ``label_id``) it prints, over the annotated road users of the data of
``--seeds`` (default: the default ``reproduce`` data, 4 sequences of 20 s, seeds 0-2), with perfect clustering
(each object's own detections):

* ``objects``: the number of objects (instances);
* ``RCS``: the mean over objects of each object's mean RCS (dBsm), and ``between``: the standard deviation
  of the per-object mean RCS between the objects of the class (dB); ``within``: the median over objects
  of the RCS standard deviation of one object's detections (dB);
* ``along`` / ``across``: the median extent of a 0.5 s window of an object along and across its principal
  axes (m; :func:`~sklearn_radar.classification.cluster_features`);
* ``vr_std``: the median standard deviation of the compensated Doppler in a 0.5 s window (m/s);
* ``sensors``: the mean number of sensors that see a 0.5 s window, and ``life``: the mean number of
  sensors that see the object over its whole life.  Both are set by the mounting, not the class: the four
  sensors (yaw -85, -25, 25, 85 deg, +-60 deg each) see almost every direction with exactly two of them.

``--before`` also prints the same table with the class-signature knobs of issue 31
(:data:`SIGNATURE_KNOBS`) turned off, i.e. the realistic preset as it was before them.  Nothing here tunes
anything: it only measures.
"""

import argparse
import ast

import numpy as np
import pandas as pd

from sklearn_radar import FrameTransform
from sklearn_radar.classification import cluster_features
from sklearn_radar.datasets import make_scenes
from sklearn_radar.datasets._scenario import ROAD_USER_CLASSES

#: The knobs that give the classes their signatures (issue 31 item 6), and their "off" values.
SIGNATURE_KNOBS = {"rcs_object_spread": 0.0, "rcs_aspect": 0.0, "wheel_micro_doppler": 0.0}

CLASS_NAMES = {params["label"]: name for name, params in ROAD_USER_CLASSES.items()}


def object_table(scenes):
    """One row per annotated object: class, per-object RCS figures, per-frame medians, sensors."""
    X = FrameTransform().fit_transform(scenes.data)
    target = np.asarray(scenes.target)
    road_user = target >= 0
    data = scenes.data[road_user]
    rcs = data["rcs"].to_numpy(dtype=float)
    objects = pd.DataFrame({"object": target[road_user], "rcs": rcs, "label": data["label_id"].to_numpy()})
    objects["sensor"] = data["sensor_id"].to_numpy()
    per_object = objects.groupby("object").agg(
        label=("label", "first"), rcs_mean=("rcs", "mean"), rcs_within=("rcs", "std"), life=("sensor", "nunique")
    )
    frames = cluster_features(X, target, window=0.5)
    frames = frames[frames["n_detections"] >= 2]
    per_frame = frames.groupby("cluster").agg(
        along=("extent_along", "median"),
        across=("extent_across", "median"),
        vr_std=("vr_std", "median"),
        sensors=("n_sensors", "mean"),
    )
    return per_object.join(per_frame, how="left")


def class_table(tables):
    """Per class: the figures of the module docstring, over the objects of all ``tables``."""
    objects = pd.concat(tables, ignore_index=True)
    grouped = objects.groupby(objects["label"].map(CLASS_NAMES))
    table = pd.DataFrame(
        {
            "objects": grouped.size(),
            "RCS": grouped["rcs_mean"].mean(),
            "between": grouped["rcs_mean"].std(),
            "within": grouped["rcs_within"].median(),
            "along": grouped["along"].median(),
            "across": grouped["across"].median(),
            "vr_std": grouped["vr_std"].median(),
            "sensors": grouped["sensors"].mean(),
            "life": grouped["life"].mean(),
        }
    )
    order = [name for name in ROAD_USER_CLASSES if name in table.index]
    return table.loc[order]


def signatures(args, knobs):
    tables = []
    for seed in args.seeds:
        scenes = make_scenes(
            args.n_sequences, args.duration, random_state=seed, difficulty=args.difficulty, knobs=knobs or None
        )
        tables.append(object_table(scenes))
    return class_table(tables)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--difficulty", default="realistic")
    parser.add_argument("--knobs", default="{}", help="knob overrides, a Python dict literal")
    parser.add_argument("--before", action="store_true", help="also print the table with the signature knobs off")
    args = parser.parse_args()
    knobs = ast.literal_eval(args.knobs)
    runs = {"with the knobs given": knobs}
    if args.before:
        runs = {"before (signature knobs off)": {**knobs, **SIGNATURE_KNOBS}, "after (the preset)": knobs}
    pd.set_option("display.width", 160)
    for title, values in runs.items():
        print(f"\n{args.difficulty} preset, {title}, seeds {args.seeds}, {args.n_sequences} x {args.duration:g} s:")
        print(signatures(args, values).round(2).to_string())
    print("(RCS, between, within: dBsm / dB; along, across: m; vr_std: m/s; sensors per 0.5 s window and per life)")


if __name__ == "__main__":
    main()
