"""
The radar V-measure on toy clusterings
======================================

The paper scores clusterings with a V-measure whose completeness "assumes
perfect matching" of the background.
:func:`~sklearn_radar.metrics.radar_homogeneity_completeness_v_measure`
reads this as homogeneity over all detections and completeness over the
detections of labelled objects only.  Four toy clusterings of two road users
and some background show what that changes against scikit-learn's
:func:`~sklearn.metrics.homogeneity_completeness_v_measure`.
"""

# %%
# Toy data
# --------
# Two road users of six detections each (instances 0 and 1) and eight
# background detections (-1).
import matplotlib.pyplot as plt
import numpy as np
from sklearn.metrics import homogeneity_completeness_v_measure

from sklearn_radar.metrics import radar_homogeneity_completeness_v_measure

rng = np.random.default_rng(0)
truth = np.array([0] * 6 + [1] * 6 + [-1] * 8)
xy = np.r_[
    rng.normal((0, 0), 0.4, (6, 2)),
    rng.normal((4, 0), 0.4, (6, 2)),
    rng.uniform((-2, 2), (6, 5), (8, 2)),
]

cases = {
    "perfect, background is noise": np.array([0] * 6 + [1] * 6 + [-1] * 8),
    "1. background forms clusters": np.array(
        [0] * 6 + [1] * 6 + [2, 2, 2, 3, 3, 3, -1, -1]
    ),
    "2. background inside a road user's cluster": np.array(
        [0] * 6 + [1] * 6 + [0, 0, 0, -1, -1, -1, -1, -1]
    ),
    "3. a road user split in two": np.array([0] * 3 + [4] * 3 + [1] * 6 + [-1] * 8),
}

# %%
# Scores
# ------
# Property 4 (without background, both agree) holds for the object
# detections alone: compare the radar completeness with scikit-learn's on
# ``truth != -1``.
for name, predicted in cases.items():
    radar = radar_homogeneity_completeness_v_measure(truth, predicted)
    sklearn = homogeneity_completeness_v_measure(truth, predicted)
    print(
        f"{name:<44} radar h/c/V {radar[0]:.2f} {radar[1]:.2f} {radar[2]:.2f}   "
        f"sklearn h/c/V {sklearn[0]:.2f} {sklearn[1]:.2f} {sklearn[2]:.2f}"
    )
objects = truth != -1
print(
    "property 4:",
    np.allclose(
        radar_homogeneity_completeness_v_measure(
            truth[objects], cases["3. a road user split in two"][objects]
        ),
        homogeneity_completeness_v_measure(
            truth[objects], cases["3. a road user split in two"][objects]
        ),
    ),
)

# %%
# Picture
# -------
# Marker: the truth (squares and circles are the two road users, crosses the
# background).  Colour: the predicted cluster (grey: noise).
markers = {0: "s", 1: "o", -1: "x"}
fig, axes = plt.subplots(1, 4, figsize=(16, 4.4), sharex=True, sharey=True)
for ax, (name, predicted) in zip(axes, cases.items(), strict=True):
    for instance, marker in markers.items():
        rows = truth == instance
        colour = [("0.6" if p < 0 else f"C{p}") for p in predicted[rows]]
        ax.scatter(xy[rows, 0], xy[rows, 1], marker=marker, c=colour, s=60)
    h, c, v = radar_homogeneity_completeness_v_measure(truth, predicted)
    sh, sc, sv = homogeneity_completeness_v_measure(truth, predicted)
    ax.set_title(
        f"{name}\nradar: h {h:.2f}  c {c:.2f}  V {v:.2f}\n"
        f"sklearn: h {sh:.2f}  c {sc:.2f}  V {sv:.2f}",
        fontsize=10,
    )
    ax.set(xlabel="x (m)", aspect="equal")
axes[0].set_ylabel("y (m)")
fig.tight_layout()
plt.show()
