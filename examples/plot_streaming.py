"""
Streaming: the whole framework scan by scan
===========================================

On a vehicle, detections arrive one radar scan at a time, about every 15 ms
(four sensors with a 60 ms cycle each), and a label must be given at once.
:class:`~sklearn_radar.online.OnlinePipeline` runs all four stages on each
scan as it arrives, from the raw detections and the scan's odometry: the
frame transform, the Doppler-density filter counting only past neighbours,
stage 1 over the last ``eps_t`` seconds
(:class:`~sklearn_radar.cluster.ScanStream`) and the stage-2 merges, each
decided as soon as its data are complete.  Objects get ids that persist:
when clusters merge, the older id survives and the newer becomes its alias.
The labels equal the offline pipeline run with ``causal=True``, detection
for detection (see :ref:`user-guide-online`).
"""

# %%
# Build the online pipeline from the offline one
# ----------------------------------------------
# Experiment #13 of the paper: FCS, the filter, stage 1 at experiment #8's
# setting and the continuation merge.  Any pipeline of these steps, or a
# ``params.json`` of ``sklearn-radar reproduce``
# (:meth:`~sklearn_radar.online.OnlinePipeline.from_params`), will do; its
# repr shows the offline pipeline it streams.
import time

import matplotlib.pyplot as plt
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from sklearn.metrics import adjusted_rand_score

from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import tracking_scores
from sklearn_radar.online import OnlinePipeline, iter_scans

scenes = make_scenes(n_sequences=1, duration=15.0, random_state=0)
data = scenes.data
online = OnlinePipeline(experiment_pipeline(13))
print(online)

# %%
# Feed the scans one by one
# -------------------------
# :func:`~sklearn_radar.online.iter_scans` gives the scans of the recorded
# table in arrival order (each timestamp's rows, its sensors together), as
# ``sklearn-radar stream`` replays them.  Each call gets one scan and
# returns, per detection, the stage-1 label, the object id and whether the
# filter kept it, plus the object list.  The time per call is the latency a
# vehicle would see.
timestamp = data["timestamp"].to_numpy()
labels = np.full(len(data), -1)
object_ids = np.full(len(data), -1)
aliases, joins, latency, n_objects = [], [], [], []
for scan in iter_scans(data):
    start = time.perf_counter()
    result = online.update(scan)
    latency.append(time.perf_counter() - start)
    rows = scan.index  # the table has a RangeIndex: the index gives the rows
    labels[rows], object_ids[rows] = result.labels, result.object_ids
    aliases += result.aliases
    joins += result.joins  # stage-2 joins (the accepted pairs at min_samples 1)
    n_objects.append(len(result.objects))
end = online.finish()
aliases += end.aliases
joins += end.joins
latency = (
    np.array(latency[1:]) * 1e3
)  # ms; the first call, which loads the kernels, is left out
print(
    f"{len(n_objects)} scans, {len(data) / len(n_objects):.1f} detections per scan, "
    f"latency median {np.median(latency):.3f} ms, "
    f"99th percentile {np.percentile(latency, 99):.3f} ms; {len(aliases)} aliases"
)

# %%
# The object list
# ---------------
# The last scan's live objects, as a DataFrame (also available as arrays):
# centroid and extent in m, the Eq. 6 velocity estimate in m/s (with
# ``velocity_known`` False where the geometry gives none), age in s and the
# time of the last update in µs.
print(result.objects.to_frame().round(2).to_string(index=False))

# %%
# Same result as the offline causal pipeline
# ------------------------------------------
# Ids differ in value, but the partitions are the same: stage 1 detection
# for detection, and the stage-1 clusters joined by stage 2.
causal = online.causal_pipeline()
offline = causal.fit_predict(data)
offline_stage1 = causal[-1].stage1_labels_
# The merged clusters are the connected components of the graph whose edges are the joins.
n_labels = labels.max() + 1
edges = np.array(joins, dtype=np.int64).reshape(-1, 2)
graph = coo_matrix(
    (np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n_labels, n_labels)
)
component = connected_components(graph, directed=False)[1]
merged = np.where(labels >= 0, component[np.maximum(labels, 0)], -1)
for name, ours, theirs in [
    ("stage 1", labels, offline_stage1),
    ("stage 2", merged, offline),
]:
    clustered = ours >= 0
    same = (
        np.array_equal(ours < 0, theirs < 0)
        and adjusted_rand_score(ours[clustered], theirs[clustered]) == 1.0
    )
    print(f"{name}: same as offline causal: {same}")

# %%
# Tracking quality of the ids
# ---------------------------
# ID switches, MOTA and IDF1 per 0.5 s window on the moving road users
# (:func:`~sklearn_radar.metrics.tracking_scores`), for the ids as the
# stream reported them and after resolving the aliases.
survivor = {merged_id: kept for _, kept, merged_id, _ in aliases}


def resolve(object_id):
    while object_id in survivor:
        object_id = survivor[object_id]
    return object_id


final_ids = np.array([resolve(i) if i >= 0 else -1 for i in object_ids])
for name, ids in [("as reported", object_ids), ("aliases resolved", final_ids)]:
    scores = tracking_scores(scenes.target, ids, times=timestamp * 1e-6)
    print(
        f"{name}: ID switches {scores['id_switches']}, "
        f"MOTA {scores['mota']:.3f}, IDF1 {scores['idf1']:.3f}"
    )

# %%
# Latency against the budget
# --------------------------
# A scan arrives about every 15 ms; the whole pipeline must be much faster.
fig, ax = plt.subplots(figsize=(8, 3.8))
ax.hist(latency, bins=np.logspace(-2, 2, 61), color="C0")
ax.axvline(15.0, c="C3", lw=2, label="budget: 15 ms per scan")
ax.set(
    xscale="log",
    xlabel="time per scan (ms)",
    ylabel="scans",
    title="OnlinePipeline.update latency",
)
ax.legend()
fig.tight_layout()
plt.show()

# %%
# Ids persist over time
# ---------------------
# The whole recording in the fixed frame, coloured by the final object id:
# a road user keeps its colour across stage-1 clusters that stage 2 merged.
# Grey: noise and filtered detections.
clustered = final_ids >= 0
x, y = data["x_seq"].to_numpy(), data["y_seq"].to_numpy()
low = np.percentile(np.c_[x, y][clustered], 1, axis=0) - 10
high = np.percentile(np.c_[x, y][clustered], 99, axis=0) + 10
fig, ax = plt.subplots(figsize=(8, 6))
ax.scatter(x[~clustered], y[~clustered], s=1, c="0.85")
ax.scatter(
    x[clustered], y[clustered], s=3, c=plt.get_cmap("tab20")(final_ids[clustered] % 20)
)
ax.set(
    xlabel="x (m, FCS)",
    ylabel="y (m, FCS)",
    aspect="equal",
    xlim=(low[0], high[0]),
    ylim=(low[1], high[1]),
    title=f"{len(np.unique(final_ids[clustered]))} objects "
    f"over {np.ptp(timestamp) * 1e-6:.0f} s",
)
fig.tight_layout()
plt.show()
