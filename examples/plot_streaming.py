"""
Streaming: clustering scan by scan
==================================

On a vehicle, detections arrive one radar scan at a time, about every 15 ms
(four sensors with a 60 ms cycle each), and a label must be given at once.
:class:`~sklearn_radar.cluster.ScanStream` keeps, per sequence, the
detections of the last ``eps_t`` seconds and labels each new scan against
them, using only the past.  A cluster that continues keeps its id; when two
clusters meet, the older id wins.  The result equals the offline
``RadarDBSCAN(causal=True)`` exactly; :meth:`RadarDBSCAN.partial_fit
<sklearn_radar.RadarDBSCAN.partial_fit>` is the same with DataFrames.
"""

# %%
# Prepare the working columns
# ---------------------------
# The frame transform needs only the scan's own odometry, so it is causal.
# The filter must not look ahead either: ``causal=True`` counts only
# neighbours at or before a detection's time.
import time

import matplotlib.pyplot as plt
import numpy as np
from sklearn.metrics import adjusted_rand_score

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.cluster import ScanStream
from sklearn_radar.datasets import make_scenes

scenes = make_scenes(n_sequences=1, duration=15.0, random_state=0)
X = DopplerDensityFilter(causal=True).fit_transform(FrameTransform(frame="frame").fit_transform(scenes.data))
clusterer = RadarDBSCAN(metric="xyv", eps_xyv=1.04, vr_scale=1.03, min_samples=3.87, alpha_r=0.99, vr_min=1.0)

# %%
# Feed the scans one by one
# -------------------------
# Each call gets one scan as plain arrays and returns its labels (-1: noise).
# The time per call is the latency a vehicle would see.
columns = {name: X[name].to_numpy() for name in ("x", "y", "v_r", "t", "range_sc", "heading")}
keep = X["keep"].to_numpy()
scan_starts = np.flatnonzero(np.r_[True, np.diff(X["timestamp"].to_numpy()) != 0])
scan_ends = np.r_[scan_starts[1:], len(X)]

stream = ScanStream(clusterer)
labels = np.full(len(X), -1, dtype=np.int64)
latency = []
for begin, end in zip(scan_starts, scan_ends, strict=True):
    rows = slice(begin, end)
    start = time.perf_counter()
    labels[rows] = stream.update(
        columns["x"][rows],
        columns["y"][rows],
        columns["v_r"][rows],
        columns["t"][begin],
        keep=keep[rows],
        range_sc=columns["range_sc"][rows],
        heading=columns["heading"][rows],
    )
    latency.append(time.perf_counter() - start)
latency = np.array(latency[1:]) * 1e3  # ms; the first call, which warms up the kernels, is left out
print(
    f"{len(scan_starts)} scans, {len(X) / len(scan_starts):.1f} detections per scan, "
    f"latency median {np.median(latency):.3f} ms, 99th percentile {np.percentile(latency, 99):.3f} ms"
)

# %%
# Same result as the offline causal mode
# --------------------------------------
# Ids may differ in value, but the partition is the same.
offline = clusterer.set_params(causal=True).fit_predict(X)
same_noise = np.array_equal(labels < 0, offline < 0)
clustered = labels >= 0
print(f"same noise: {same_noise}, same clusters: {adjusted_rand_score(labels[clustered], offline[clustered]) == 1.0}")

# %%
# Latency against the budget
# --------------------------
# A scan arrives about every 15 ms; the stream must be much faster than that.
fig, ax = plt.subplots(figsize=(8, 3.8))
ax.hist(latency, bins=np.logspace(-2, 2, 61), color="C0")
ax.axvline(15.0, c="C3", lw=2, label="budget: 15 ms per scan")
ax.set(xscale="log", xlabel="time per scan (ms)", ylabel="scans", title="ScanStream.update latency")
ax.legend()
fig.tight_layout()
plt.show()

# %%
# Ids persist over time
# ---------------------
# The whole recording in the fixed frame, coloured by the id the stream gave:
# a road user keeps its colour for as long as it stays connected within
# 0.25 s windows.  Grey: noise and filtered detections.
clustered = labels >= 0
x, y = X["x"].to_numpy(), X["y"].to_numpy()
low = np.percentile(np.c_[x, y][clustered], 1, axis=0) - 10
high = np.percentile(np.c_[x, y][clustered], 99, axis=0) + 10
fig, ax = plt.subplots(figsize=(8, 6))
ax.scatter(x[~clustered], y[~clustered], s=1, c="0.85")
ax.scatter(x[clustered], y[clustered], s=3, c=plt.get_cmap("tab20")(labels[clustered] % 20))
ax.set(
    xlabel="x (m, FCS)",
    ylabel="y (m, FCS)",
    aspect="equal",
    xlim=(low[0], high[0]),
    ylim=(low[1], high[1]),
    title=f"{labels.max() + 1} stream ids over {columns['t'].max() - columns['t'].min():.0f} s",
)
fig.tight_layout()
plt.show()
