"""
Cluster merging: velocity estimate (Eq. 6) and cluster continuation
===================================================================

Stage 1 forms small, certain clusters; an object that vanishes for a moment
or is seen by two sensors may end up as several of them.
:class:`~sklearn_radar.ClusterMerger` runs a second DBSCAN over the stage-1
clusters with one of two neighbourhood criteria:

* ``mode="velocity"``, Eq. (6): the clusters are close (``d_min < eps_d``),
  and their full 2-D velocities, estimated from Doppler and line of sight,
  agree in direction (``eps_phi``) and magnitude (``eps_v``);
* ``mode="continuation"``: each cluster's track of centres is continued
  with its velocity; the continued centres meet (``d_pred,min < eps_d``) and
  the velocities agree (``eps_v``).

Both are *causal*: a pair is decided with the data available at
``tau = min(end of B, start of B + eps_t2)``.  This example draws that rule,
estimates one cluster's velocity, and compares both modes at the paper's
settings (#12 and #13) on stage 1 at the paper's best setting (#8).
"""

# %%
# When a pair is decided
# ----------------------
# Cluster A is older; cluster B starts at ``s_B``.  The pair (A, B) is decided
# at ``tau = min(end of B, s_B + eps_t2)`` using only detections up to
# ``tau``: real time forbids waiting for the future.  A gap between A's last
# detection before ``s_B`` and ``s_B`` must be below ``eps_t2``.
import tempfile

import matplotlib.pyplot as plt
import numpy as np

from sklearn_radar import (
    ClusterMerger,
    DopplerDensityFilter,
    FrameTransform,
    RadarDBSCAN,
)
from sklearn_radar.cluster import estimate_velocity
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import get_experiment
from sklearn_radar.metrics import (
    precluster_target,
    radar_homogeneity_completeness_v_measure,
)

eps_t2 = 0.35
a_start, a_end, s_b, b_end = 0.0, 0.9, 1.05, 1.9
tau = min(b_end, s_b + eps_t2)
fig, ax = plt.subplots(figsize=(9, 3.8))
ax.axvspan(s_b - eps_t2, tau, color="0.9")
ax.text(
    s_b - eps_t2 + 0.01,
    5.1,
    "Eq. (6): A and B\nwithin [s_B - eps_t2, tau]",
    va="top",
    fontsize=9,
)
ax.broken_barh([(a_start, a_end - a_start)], (2.6, 0.8), color="C0")
ax.broken_barh([(s_b, tau - s_b)], (1.1, 0.8), color="C1")
ax.broken_barh([(tau, b_end - tau)], (1.1, 0.8), color="C1", alpha=0.3)
ax.text(
    (tau + b_end) / 2, 1.5, "after tau: not used", ha="center", va="center", fontsize=9
)
ax.axvline(s_b, c="k", ls="--")
ax.text(s_b - 0.01, 0.15, "s_B", ha="right")
ax.axvline(tau, c="C3", lw=2)
ax.text(tau + 0.02, 0.15, "decision at tau", color="C3")
ax.annotate("", (s_b, 0.65), (s_b + eps_t2, 0.65), arrowprops=dict(arrowstyle="<->"))
ax.text(s_b + eps_t2 / 2, 0.75, "eps_t2", ha="center")
ax.annotate("", (a_end, 2.3), (s_b, 2.3), arrowprops=dict(arrowstyle="<->"))
ax.text(a_end - 0.02, 2.3, "gap < eps_t2", ha="right", va="center", fontsize=9)
ax.set(
    yticks=[1.5, 3.0],
    yticklabels=["cluster B", "cluster A"],
    xlabel="time (s)",
    ylim=(0, 5.2),
    xlim=(-0.05, 2.0),
    title="Causal decision (continuation uses all of A up to tau)",
)
fig.tight_layout()
plt.show()

# %%
# Stage 1, then both merging modes
# --------------------------------
# ``ClusterMerger(memory=...)`` caches the stage-1 labels, so stage 1 runs
# once for both modes.  ``merges_`` lists the pairs that met the criterion.
scenes = make_scenes(n_sequences=2, duration=20.0, random_state=0)
X = DopplerDensityFilter().fit_transform(
    FrameTransform(frame="frame").fit_transform(scenes.data)
)
target = precluster_target(X, scenes.target)
stage1 = RadarDBSCAN(**get_experiment(8).params)

models = {}
with tempfile.TemporaryDirectory() as cache:
    for number in (12, 13):
        params = get_experiment(number).params
        models[params["mode"]] = ClusterMerger(
            **params, stage1=stage1, memory=cache
        ).fit(X)

rows = [("stage 1 (#8)", models["velocity"].stage1_labels_, 0)]
rows += [
    (f"{mode} (#{12 if mode == 'velocity' else 13})", m.labels_, len(m.merges_))
    for mode, m in models.items()
]
for name, labels, n_merges in rows:
    h, c, v = radar_homogeneity_completeness_v_measure(
        target, labels, groups=scenes.groups
    )
    print(
        f"{name:<20} homogeneity {h:.4f}  completeness {c:.4f}  V {v:.4f}  "
        f"merges {n_merges}"
    )

# %%
# The velocity of a cluster
# -------------------------
# A rigid object moving with velocity ``(v_x, v_y)`` gives each detection the
# compensated radial velocity ``v_r = v_x cos(theta) + v_y sin(theta)``, with
# ``theta`` the line of sight.  :func:`~sklearn_radar.cluster.estimate_velocity`
# fits this with RANSAC over pairs of detections and least squares (Kellner
# et al. 2013).  Here: the largest stage-1 cluster within one ``eps_t2``
# window of 0.35 s (as Eq. 6 uses it), its detections against their line of
# sight (FCS, ``azimuth_sc + sensor_yaw + heading``), and the fitted curve.
stage1_labels = models["velocity"].stage1_labels_
largest = np.bincount(stage1_labels[stage1_labels >= 0]).argmax()
t_all = X["t"].to_numpy()
middle = np.median(t_all[stage1_labels == largest])
rows_of = (stage1_labels == largest) & (t_all >= middle) & (t_all < middle + eps_t2)
theta = (X["azimuth_sc"] + X["sensor_yaw"] + X["heading"]).to_numpy()[rows_of]
v_r = X["v_r"].to_numpy()[rows_of]
vx, vy, n_inliers = estimate_velocity(v_r, theta)
print(
    f"cluster {largest}, 0.35 s: {rows_of.sum()} detections, "
    f"velocity ({vx:.2f}, {vy:.2f}) m/s, speed {np.hypot(vx, vy):.2f} m/s, "
    f"{n_inliers} inliers"
)
grid = np.linspace(theta.min() - 0.05, theta.max() + 0.05, 100)
fig, ax = plt.subplots(figsize=(8, 4))
ax.scatter(np.rad2deg(theta), v_r, s=12, label="detections")
ax.plot(
    np.rad2deg(grid),
    vx * np.cos(grid) + vy * np.sin(grid),
    c="C3",
    label="v_x cos(theta) + v_y sin(theta)",
)
ax.set(
    xlabel="line of sight theta (deg, FCS)",
    ylabel="compensated v_r (m/s)",
    title=f"Velocity estimate of one cluster: |v| = {np.hypot(vx, vy):.2f} m/s",
)
ax.legend()
fig.tight_layout()
plt.show()

# %%
# A merge, seen over time
# -----------------------
# The pair with the most detections among those that cluster continuation
# merged: the two stage-1 clusters (left, two colours) become one (right).
# The vertical axis is the position along the road user's direction of
# travel.
merges = models["continuation"].merges_
sizes = [np.isin(stage1_labels, [a, b]).sum() for _, a, b in merges]
sequence, a, b = merges[int(np.argmax(sizes))]
pair = np.isin(stage1_labels, [a, b])
xy = X.loc[pair, ["x", "y"]].to_numpy()
direction = np.linalg.svd(xy - xy.mean(axis=0), full_matrices=False)[2][0]
along = (xy - xy.mean(axis=0)) @ direction
t = X["t"].to_numpy()[pair] - X["t"].to_numpy()[pair].min()
fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
for ax, labels, title in (
    (axes[0], stage1_labels, "stage 1"),
    (axes[1], models["continuation"].labels_, "after merging"),
):
    ids = labels[pair]
    for k, cluster in enumerate(np.unique(ids)):
        ax.scatter(
            t[ids == cluster],
            along[ids == cluster],
            s=10,
            c=f"C{k}",
            label=f"cluster {cluster}",
        )
    ax.axvline(t[stage1_labels[pair] == b].min(), c="k", ls=":", lw=0.8)
    ax.set(title=title, xlabel="time (s)")
    ax.legend()
axes[0].set_ylabel("position along the track (m)")
fig.tight_layout()
plt.show()
