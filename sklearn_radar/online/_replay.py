"""``sklearn-radar stream``: replay a RadarScenes folder scan by scan through the online pipeline."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pandas as pd

from ..datasets import load_radarscenes
from ._objects import ObjectList
from ._pipeline import OnlinePipeline

#: The first line of an object-list CSV this package writes: how a file is recognised as ours.
OBJECTS_HEADER = ",".join(["timestamp", *ObjectList.__dataclass_fields__])


def check_objects_file(out):
    """Refuse to replace ``out`` unless it is absent, empty, or an object list this package wrote.

    Raises
    ------
    FileExistsError
        Naming ``out``.
    """
    problem = _why_not_replaceable(Path(out))
    if problem is not None:
        raise FileExistsError(f"{out} {problem}; it is not replaced: choose another output file")


def _why_not_replaceable(out):
    """None when ``out`` may be replaced (absent, empty, or starting with our header), else why not."""
    if out.is_symlink():
        return "is a symbolic link"
    if not out.is_file() or out.stat().st_size == 0:
        return None
    head = (OBJECTS_HEADER + "\n").encode("ascii")
    with open(out, "rb") as stream:
        ours = stream.read(len(head)) == head
    return None if ours else "exists and is not an object list written by sklearn-radar"


def scan_order(data):
    """Row positions of each scan (one timestamp of one sequence, its sensors together), in timestamp order."""
    timestamp, sequence = data["timestamp"].to_numpy(), data["sequence"].to_numpy()
    order = np.lexsort((sequence, timestamp))
    cut = np.flatnonzero((np.diff(timestamp[order]) != 0) | (np.diff(sequence[order]) != 0)) + 1
    return np.split(order, cut)


def replay(online, data, objects=False):
    """Feed ``data`` to ``online`` scan by scan; per-detection results, latencies and the object lists.

    Returns
    -------
    replayed : dict
        ``labels`` (stage 1), ``reported`` (the object ids as given at each scan), ``object_ids`` (final:
        every alias resolved to its surviving id), ``keep``,
        ``latency`` and ``cpu`` (wall and thread CPU time per scan, s), ``aliases`` and ``objects`` (a
        DataFrame, or None).
    """
    columns = {name: data[name].to_numpy() for name in data.columns if name not in ("uuid", "track_id")}
    n = len(data)
    labels, reported, keep = np.full(n, -1), np.full(n, -1), np.zeros(n, dtype=bool)
    latency, cpu, aliases, frames = [], [], [], []
    for rows in scan_order(data):
        scan = {name: values[rows] for name, values in columns.items()}
        start, start_cpu = time.perf_counter(), time.thread_time()
        result = online.update(scan, objects=objects)
        latency.append(time.perf_counter() - start)
        cpu.append(time.thread_time() - start_cpu)
        labels[rows], reported[rows], keep[rows] = result.labels, result.object_ids, result.keep
        aliases += result.aliases
        if objects and len(result.objects):
            frame = result.objects.to_frame()
            frame.insert(0, "timestamp", int(scan["timestamp"][0]))
            frames.append(frame)
    aliases += online.finish().aliases
    survivor = _survivors(aliases)
    final = np.array([survivor(i) if i >= 0 else -1 for i in reported.tolist()], dtype=np.int64)
    table = pd.concat(frames, ignore_index=True) if frames else None
    return {
        "labels": labels,
        "reported": reported,
        "object_ids": final,
        "keep": keep,
        "latency": np.array(latency),
        "cpu": np.array(cpu),
        "aliases": aliases,
        "objects": table,
    }


def _survivors(aliases):
    """The id each id is an alias of, following chains of aliases."""
    parent = {merged: kept for _, kept, merged, _ in aliases}

    def survivor(object_id):
        while object_id in parent:
            object_id = parent[object_id]
        return object_id

    return survivor


def recording_seconds(data):
    """s of recording: the sum over sequences of last minus first timestamp."""
    span = data.groupby("sequence")["timestamp"].agg(["min", "max"])
    return float((span["max"] - span["min"]).sum()) * 1e-6


def stream_radarscenes(data, params, out, objects=None, experiment=None):
    """Replay a RadarScenes folder through the online pipeline of a saved setting; write devkit predictions.

    The scans of all sequences are fed in timestamp order (the sensors of a
    sequence interleaved, those measuring at the same time together); the
    predictions file holds each detection's final object id (every alias
    resolved to the surviving id), as ``sklearn-radar cluster`` writes
    cluster ids.  Nothing is written before every argument is checked, and
    no file that this package did not write is replaced.

    Parameters
    ----------
    data : str or path-like
        The RadarScenes folder to replay (or its parent).
    params : str or path-like
        The setting: a ``params.json`` of ``sklearn-radar reproduce``.
    out : str or path-like
        Predictions file to write.
    objects : str or path-like, default=None
        Object-list CSV to write (one row per live object per scan); None: none.
    experiment : int, default=None
        Which saved experiment; None: the best.

    Returns
    -------
    summary : dict
        ``experiment``, ``params``, ``n_detections``, ``n_scans``, ``n_objects``, ``n_aliases``,
        ``latency`` and ``cpu`` (wall and thread CPU time per scan, s), ``recording`` (s), ``out`` and
        ``objects``.
    """
    from .._cluster_command import check_predictions_file, load_params, setting_pipeline, write_predictions
    from ..reproduce._io import atomic_write

    setting = load_params(params, experiment)
    online = OnlinePipeline(setting_pipeline(setting, params))
    check_predictions_file(out)
    if objects is not None:
        if Path(objects).resolve() == Path(out).resolve():
            raise ValueError(f"--objects and --out name the same file: {out}")
        check_objects_file(objects)
    scenes = load_radarscenes(data)
    replayed = replay(online, scenes.data, objects=objects is not None)
    write_predictions(scenes.data["uuid"].to_numpy(), replayed["object_ids"], out)
    if objects is not None:
        table = replayed["objects"]
        if table is None:
            table = pd.DataFrame(columns=OBJECTS_HEADER.split(","))

        def write(stream):
            stream.write(table.to_csv(index=False, lineterminator="\n").encode("ascii"))

        atomic_write(Path(objects), write, replaceable=check_objects_file)
    final = replayed["object_ids"]
    return {
        "experiment": setting["experiment"],
        "params": setting["params"],
        "n_detections": len(final),
        "n_scans": len(replayed["latency"]),
        "n_objects": len(np.unique(final[final >= 0])),
        "n_aliases": len(replayed["aliases"]),
        "latency": replayed["latency"],
        "cpu": replayed["cpu"],
        "recording": recording_seconds(scenes.data),
        "out": str(out),
        "objects": None if objects is None else str(objects),
    }
