"""
Quick start: the whole pipeline on simulated data
=================================================

Simulate two recordings, run the framework of Scheiner et al. (2019) as one
scikit-learn :class:`~sklearn.pipeline.Pipeline` (frame transform, Doppler-density
filter, radar DBSCAN, cluster merging), score it with the radar V-measure and
look at the result next to the ground truth.
"""

# %%
# Data
# ----
# :func:`~sklearn_radar.datasets.make_scenes` returns a
# :class:`~sklearn.utils.Bunch`: ``data`` is the detection table (one row per
# detection, RadarScenes columns), ``target`` the ground-truth instance per
# detection (-1 for static background) and ``groups`` the sequence number.
import matplotlib.pyplot as plt
import numpy as np
from sklearn.pipeline import make_pipeline

from sklearn_radar import (
    ClusterMerger,
    DopplerDensityFilter,
    FrameTransform,
    RadarDBSCAN,
)
from sklearn_radar.datasets import make_scenes
from sklearn_radar.metrics import (
    precluster_target,
    radar_homogeneity_completeness_v_measure,
)

scenes = make_scenes(n_sequences=2, duration=20.0, random_state=0)
print(
    f"{len(scenes.data)} detections, "
    f"{np.unique(scenes.target[scenes.target >= 0]).size} road users, "
    f"{100 * np.mean(scenes.target == -1):.0f} % background"
)

# %%
# Pipeline
# --------
# Stage 1 uses the paper's best setting (experiment #8: Eq. 5 with a
# range-adaptive minimum of points, Eq. 2); stage 2 the cluster continuation
# (#13), which is :class:`~sklearn_radar.ClusterMerger`'s default.
stage1 = RadarDBSCAN(
    metric="xyv",
    eps_xyv=1.04,
    vr_scale=1.03,
    min_samples=3.87,
    alpha_r=0.99,
    vr_min=1.0,
)
model = make_pipeline(
    FrameTransform(frame="frame"), DopplerDensityFilter(), ClusterMerger(stage1=stage1)
)
labels = model.fit_predict(scenes.data)
print(
    f"{labels.max() + 1} clusters, "
    f"{100 * np.mean(labels == -1):.0f} % of the detections are noise"
)

# %%
# Score
# -----
# The paper optimises towards the ground truth *pre-clustered* per object
# (:func:`~sklearn_radar.metrics.precluster_target`) and scores with a
# V-measure whose completeness ignores background detections.
target = precluster_target(scenes.data, scenes.target)
for name, predicted in (("stage 1", model[-1].stage1_labels_), ("stage 1 + 2", labels)):
    h, c, v = radar_homogeneity_completeness_v_measure(
        target, predicted, groups=scenes.groups
    )
    print(f"{name:<12} homogeneity {h:.3f}  completeness {c:.3f}  V-measure {v:.3f}")

# %%
# Look at one time window
# -----------------------
# Half a second of the first recording in the fixed frame (FCS, columns
# ``x`` and ``y`` written by :class:`~sklearn_radar.FrameTransform`).  The
# colours of the two panels are independent: what matters is whether each
# road user is one colour on the right as on the left.
Xt = model[:-1].transform(scenes.data)
t = Xt["t"].to_numpy()
first = scenes.groups == scenes.groups[0]
start = t[first].min() + 6.0
now = first & (t >= start) & (t < start + 0.5)
palette = plt.get_cmap("tab20")
# Frame the road users of the window and the ego car (black triangle).
ego_x, ego_y = (
    Xt["ego_x_seq"].to_numpy()[now].mean(),
    Xt["ego_y_seq"].to_numpy()[now].mean(),
)
users = now & (scenes.target >= 0)
centre_x = (Xt["x"].to_numpy()[users].mean() + ego_x) / 2
centre_y = (Xt["y"].to_numpy()[users].mean() + ego_y) / 2
limits = dict(xlim=(centre_x - 45, centre_x + 45), ylim=(centre_y - 45, centre_y + 45))


def draw(ax, ids, title):
    ids = ids[now]
    x, y = Xt["x"].to_numpy()[now], Xt["y"].to_numpy()[now]
    grey = ids < 0
    ax.scatter(x[grey], y[grey], s=3, c="0.8", label="background / noise")
    ax.scatter(x[~grey], y[~grey], s=10, c=palette(ids[~grey] % 20))
    ax.plot(ego_x, ego_y, "k^", ms=9)
    ax.set(
        title=title, xlabel="x (m, FCS)", ylabel="y (m, FCS)", aspect="equal", **limits
    )


fig, axes = plt.subplots(1, 2, figsize=(12, 5.5), sharex=True, sharey=True)
draw(axes[0], scenes.target, "ground truth (instances)")
draw(axes[1], labels, "pipeline clusters")
axes[0].legend(loc="lower left", markerscale=3)
fig.tight_layout()
plt.show()

# %%
# The processing chain, stage by stage
# ------------------------------------
# The same window after each stage: all detections, what the filter of
# Eq. (1) keeps, the stage-1 clusters and the merged clusters.
stages = [
    ("raw detections", np.full(len(Xt), -1), None),
    ("after the Doppler-density filter", np.full(len(Xt), -1), Xt["keep"].to_numpy()),
    ("stage 1: RadarDBSCAN", model[-1].stage1_labels_, None),
    ("stage 2: ClusterMerger", labels, None),
]
fig, axes = plt.subplots(1, 4, figsize=(16, 4.6), sharex=True, sharey=True)
x, y = Xt["x"].to_numpy()[now], Xt["y"].to_numpy()[now]
for ax, (title, ids, keep) in zip(axes, stages, strict=True):
    ids = ids[now]
    if keep is not None:
        keep = keep[now]
        ax.scatter(x[~keep], y[~keep], s=3, c="0.85")
        ax.scatter(x[keep], y[keep], s=6, c="k")
    else:
        grey = ids < 0
        ax.scatter(
            x[grey], y[grey], s=3, c="0.6" if title.startswith("raw") else "0.85"
        )
        ax.scatter(x[~grey], y[~grey], s=8, c=palette(ids[~grey] % 20))
    ax.plot(ego_x, ego_y, "k^", ms=7)
    ax.set(title=title, xlabel="x (m)", aspect="equal", **limits)
axes[0].set_ylabel("y (m)")
fig.tight_layout()
plt.show()
