"""
The three stage-1 neighbourhood criteria side by side
=====================================================

:class:`~sklearn_radar.RadarDBSCAN` is DBSCAN over position, Doppler and time
with one of three neighbourhood criteria, all limited to ``|dt| <= eps_t``
(0.25 s):

* ``metric="box"``, Eq. (3): ``|dx| < eps_xy`` and ``|dy| < eps_xy`` and
  ``|dv_r| < eps_vr`` (the box is aligned with the car);
* ``metric="xy"``, Eq. (4): ``sqrt(dx^2 + dy^2) < eps_xy`` and
  ``|dv_r| < eps_vr``;
* ``metric="xyv"``, Eq. (5): ``sqrt(dx^2 + dy^2 + dv_r^2 / vr_scale^2) < eps_xyv``.

This example draws the three neighbourhoods at the paper's tuned settings
(experiments #3, #5 and #6 of Table III) and clusters the same data with each.
"""

# %%
# The neighbourhoods
# ------------------
# Top: the spatial slice (``dv_r = 0``); bottom: distance against Doppler
# difference (``dy = 0``).  The box of Eq. (3) is not rotation invariant, the
# disc of Eq. (4) is; Eq. (5) trades distance against Doppler difference, so
# close detections may differ more in Doppler than remote ones.
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Ellipse, Rectangle

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import get_experiment
from sklearn_radar.metrics import (
    precluster_target,
    radar_homogeneity_completeness_v_measure,
)

settings = {number: get_experiment(number).params for number in (3, 5, 6)}
for number, params in settings.items():
    print(f"#{number} {get_experiment(number).method}: {params}")

fig, axes = plt.subplots(2, 3, figsize=(12, 7.5))
box, xy, xyv = settings[3], settings[5], settings[6]
shapes = [
    (
        "Eq. (3) box, #3",
        Rectangle(
            (-box["eps_xy"], -box["eps_xy"]), 2 * box["eps_xy"], 2 * box["eps_xy"]
        ),
        Rectangle(
            (-box["eps_xy"], -box["eps_vr"]), 2 * box["eps_xy"], 2 * box["eps_vr"]
        ),
    ),
    (
        "Eq. (4) xy, #5",
        Ellipse((0, 0), 2 * xy["eps_xy"], 2 * xy["eps_xy"]),
        Rectangle((-xy["eps_xy"], -xy["eps_vr"]), 2 * xy["eps_xy"], 2 * xy["eps_vr"]),
    ),
    (
        "Eq. (5) xyv, #6",
        Ellipse((0, 0), 2 * xyv["eps_xyv"], 2 * xyv["eps_xyv"]),
        Ellipse((0, 0), 2 * xyv["eps_xyv"], 2 * xyv["eps_xyv"] * xyv["vr_scale"]),
    ),
]
for column, (title, spatial, doppler) in enumerate(shapes):
    top, bottom = axes[0, column], axes[1, column]
    for patch in (spatial, doppler):
        patch.set(fc="C0", alpha=0.35, ec="C0", lw=2)
    top.add_patch(spatial)
    bottom.add_patch(doppler)
    top.set(
        title=title, xlim=(-1.2, 1.2), ylim=(-1.2, 1.2), aspect="equal", xlabel="dx (m)"
    )
    bottom.set(xlim=(-1.2, 1.2), ylim=(-16, 16), xlabel="dx (m)")
    for ax in (top, bottom):
        ax.axhline(0, c="k", lw=0.5)
        ax.axvline(0, c="k", lw=0.5)
axes[0, 0].set_ylabel("dy (m)")
axes[1, 0].set_ylabel("dv_r (m/s)")
fig.suptitle("Neighbourhood of a detection at the origin (|dt| <= 0.25 s in all three)")
fig.tight_layout()
plt.show()

# %%
# Cluster the same data with each
# -------------------------------
# Frame transform (FCS) and filter once, then each criterion at the paper's
# tuned setting; the score is the radar V-measure against the pre-clustered
# target (see the user guide on scoring).
scenes = make_scenes(n_sequences=2, duration=20.0, random_state=2)
X = DopplerDensityFilter().fit_transform(
    FrameTransform(frame="frame").fit_transform(scenes.data)
)
target = precluster_target(X, scenes.target)
labels = {}
for number, params in settings.items():
    labels[number] = RadarDBSCAN(**params).fit_predict(X)
    h, c, v = radar_homogeneity_completeness_v_measure(
        target, labels[number], groups=scenes.groups
    )
    print(
        f"#{number} {params['metric']:<4} homogeneity {h:.3f} "
        f"completeness {c:.3f} V {v:.3f}, {labels[number].max() + 1} clusters"
    )

# %%
# One window, three clusterings
# -----------------------------
# 0.5 s of the first recording around its busiest road user.  Colours are
# cluster ids (independent between panels); grey is noise.
t = X["t"].to_numpy()
first = scenes.groups == scenes.groups[0]
users, sizes = np.unique(
    scenes.target[first & (scenes.target >= 0)], return_counts=True
)
busiest = users[np.argmax(sizes)]
middle = np.median(t[scenes.target == busiest])
now = first & (np.abs(t - middle) < 0.25)
centre = X.loc[now & (scenes.target == busiest), ["x", "y"]].mean().to_numpy()
palette = plt.get_cmap("tab20")

fig, axes = plt.subplots(1, 4, figsize=(16, 4.4), sharex=True, sharey=True)
panels = [("target (pre-clustered)", target)] + [
    (f"#{n} {settings[n]['metric']}", labels[n]) for n in settings
]
x, y = X["x"].to_numpy()[now], X["y"].to_numpy()[now]
for ax, (title, ids) in zip(axes, panels, strict=True):
    ids = ids[now]
    noise = ids < 0
    ax.scatter(x[noise], y[noise], s=3, c="0.8")
    ax.scatter(x[~noise], y[~noise], s=9, c=palette(ids[~noise] % 20))
    ax.set(
        title=title,
        xlabel="x (m)",
        aspect="equal",
        xlim=(centre[0] - 30, centre[0] + 30),
        ylim=(centre[1] - 30, centre[1] + 30),
    )
axes[0].set_ylabel("y (m)")
fig.tight_layout()
plt.show()
