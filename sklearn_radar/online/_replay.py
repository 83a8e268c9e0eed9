"""Replay a detection table scan by scan through an online pipeline: labels, object ids, latencies."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from .._labels import drop_small_clusters
from ._scans import scan_order
from ._tracker import followed_ids


def replay(online, data, objects=False):
    """Feed ``data`` to ``online`` scan by scan; per-detection results, latencies and the object lists.

    Returns
    -------
    replayed : dict
        ``labels`` (stage 1), ``reported`` (the object ids as given at each scan), ``confirmed`` (as given at
        each scan), ``followed`` (the ids a tracker of the pipeline follows at each scan), ``object_ids``
        (final: every alias resolved to its surviving id, and with stage 2's ``min_cluster_size`` the causal
        confirmation rule applied to them, as the causal pipeline does; with the learned grouping, the detections
        confirmed when they came), ``keep``, ``latency`` and ``cpu`` (wall and thread CPU time per scan, s),
        ``aliases``, ``objects`` (a DataFrame, or None) and ``track_id`` (the tracker's id of each detection as
        given at its scan; None without a tracker).
    """
    columns = {name: data[name].to_numpy() for name in data.columns if name not in ("uuid", "track_id")}
    n = len(data)
    labels, reported, keep = np.full(n, -1), np.full(n, -1), np.zeros(n, dtype=bool)
    confirmed = np.zeros(n, dtype=bool)
    track_id = None if online.tracker is None else np.full(n, -1, dtype=np.int64)
    latency, cpu, aliases, scan_objects = [], [], [], []
    for rows in scan_order(data):
        scan = {name: values[rows] for name, values in columns.items()}
        start, start_cpu = time.perf_counter(), time.thread_time()
        result = online.update(scan, objects=objects)
        latency.append(time.perf_counter() - start)
        cpu.append(time.thread_time() - start_cpu)
        labels[rows], reported[rows], keep[rows] = result.labels, result.object_ids, result.keep
        confirmed[rows] = result.confirmed
        if track_id is not None:
            track_id[rows] = result.track_id
        aliases += result.aliases
        if objects and len(result.objects):
            listed = result.objects.to_frame()
            listed.insert(0, "timestamp", int(scan["timestamp"][0]))
            scan_objects.append(listed)
    aliases += online.finish().aliases
    survivor = _survivors(aliases)
    final = np.array([survivor(i) if i >= 0 else -1 for i in reported.tolist()], dtype=np.int64)
    if online.learned:  # the learned grouping confirms at each detection's time: its confirmed flag
        final = np.where(confirmed, final, -1)
    else:
        final = drop_small_clusters(final, online.min_cluster_size, data["timestamp"].to_numpy())
    table = pd.concat(scan_objects, ignore_index=True) if scan_objects else None
    return {
        "labels": labels,
        "reported": reported,
        "confirmed": confirmed,
        "followed": followed_ids(reported, confirmed, online.learned),
        "object_ids": final,
        "keep": keep,
        "latency": np.array(latency),
        "cpu": np.array(cpu),
        "aliases": aliases,
        "objects": table,
        "track_id": track_id,
    }


def _survivors(aliases):
    """The id each id is an alias of, following chains of aliases."""
    parent = {merged: kept for _, kept, merged, _ in aliases}

    def survivor(object_id):
        while object_id in parent:
            object_id = parent[object_id]
        return object_id

    return survivor
