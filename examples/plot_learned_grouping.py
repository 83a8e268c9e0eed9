"""
Learned grouping: clusters learned from labelled recordings
===========================================================

:class:`~sklearn_radar.cluster.LinkClustering` learns from recordings whose
detections carry a track id (as RadarScenes gives them) which detections belong
to a road user and which pairs of them belong to the same one, then groups new
recordings with those learned links instead of hand-set distance thresholds.
This example trains it on two simulated recordings, applies it to two others and
compares it with the framework's stages at the paper's setting.
"""

# %%
# Labelled data
# -------------
# Four simulated recordings of 8 s (realistic preset), split by recording: two for
# training, two for testing.  The target is one instance id per detection, -1 for
# background; :func:`~sklearn_radar.metrics.precluster_target` splits each road user
# into the pieces that a 0.25 s window can see together, the target the framework
# is scored against.
import matplotlib.pyplot as plt
import numpy as np
from sklearn.pipeline import make_pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.cluster import LinkClustering
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.metrics import instance_errors, panoptic_quality, precluster_target
from sklearn_radar.model_selection import sequence_train_test_split

scenes = make_scenes(
    n_sequences=4, duration=8.0, difficulty="realistic", random_state=0
)
y = precluster_target(scenes.data, scenes.target)
train, test = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=0)
X_train, y_train = scenes.data.iloc[train], y[train]
X_test, y_test = scenes.data.iloc[test], y[test]
print(f"{len(train)} training and {len(test)} test detections")

# %%
# Training
# --------
# The learned grouping takes the place of the clustering stages, after the frame
# transform and the Doppler-density filter.  ``fit`` trains its two classifiers
# (objectness per detection, links per pair of nearby detections) and tunes its
# three thresholds for panoptic quality on out-of-fold predictions of the
# training recordings.  ``max_iter=40`` boosting iterations keep this example
# fast; the default is 150.
learned = make_pipeline(
    FrameTransform(frame="frame"),
    DopplerDensityFilter(),
    LinkClustering(max_iter=40),
)
learned.fit(X_train, y_train)
model = learned[-1]
print(
    f"link threshold {model.link_threshold_}, objectness threshold "
    f"{model.objectness_threshold_}, min cluster size {model.min_cluster_size_}"
)

# %%
# Recordings it never saw
# -----------------------
# ``predict`` groups the test recordings with the fitted classifiers and
# thresholds.  Beside it, the framework's object pipeline (the paper's #12, Eq. 6
# velocity merging on #8's stage 1) at the paper's setting, without tuning: the
# user guide compares the learned grouping with it and with scikit-learn's
# clusterers, each tuned for the same objective.  Panoptic quality counts road
# users per 0.5 s window (a match needs IoU > 0.5).
labels = {
    "LinkClustering": learned.predict(X_test),
    "object pipeline (paper's setting)": np.concatenate(
        [
            object_pipeline(2).fit_predict(X_test[X_test["sequence"] == number])
            for number in np.unique(X_test["sequence"])
        ]
    ),
}
times = X_test["timestamp"].to_numpy() * 1e-6
groups = X_test["sequence"].to_numpy()
for name, found in labels.items():
    scores = panoptic_quality(y_test, found, times=times, groups=groups)
    errors = instance_errors(y_test, found, times=times, groups=groups)
    print(
        f"{name:<34} PQ {scores.pq:.3f}  recall {scores.recall:.3f}  precision "
        f"{scores.precision:.3f}  missed {errors['missed']} of {errors['n_true']}  "
        f"false {errors['false']}"
    )

# %%
# One time window
# ---------------
# Half a second of the first test recording, in world coordinates: the window
# with the most annotated road users.  The annotated road users, and the
# clusters of both methods (grey: background or noise; a colour per instance or
# cluster, not matched between panels), around the road users.
world = learned[:-1].transform(X_test)
number = np.unique(groups)[0]
elapsed = times - times[groups == number].min()
window = np.floor(elapsed / 0.5)
mine = (groups == number) & (y_test >= 0)
counts = {w: len(np.unique(y_test[mine & (window == w)])) for w in np.unique(window)}
chosen = max(counts, key=counts.get)
shown = (groups == number) & (window == chosen)
x, yy = world["x"].to_numpy()[shown], world["y"].to_numpy()[shown]
users = y_test[shown] >= 0
panels = {"ground truth": y_test, **labels}
palette = np.array([c for k, c in enumerate(plt.cm.tab10.colors) if k != 7])  # no grey
fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), sharex=True, sharey=True)
for ax, (title, values) in zip(axes, panels.items(), strict=True):
    value = np.asarray(values)[shown]
    ax.scatter(x[value < 0], yy[value < 0], s=4, c="lightgrey")
    ax.scatter(
        x[value >= 0], yy[value >= 0], s=12, c=palette[value[value >= 0] % len(palette)]
    )
    ax.set_title(title)
    ax.set_xlabel("x (m, world frame)")
    ax.set_aspect("equal", adjustable="box")
axes[0].set_xlim(x[users].min() - 15, x[users].max() + 15)
axes[0].set_ylim(yy[users].min() - 15, yy[users].max() + 15)
axes[0].set_ylabel("y (m, world frame)")
fig.suptitle(
    f"Test recording {number}, {0.5 * chosen:.1f}-{0.5 * chosen + 0.5:.1f} s after "
    f"its start: {counts[chosen]} annotated road-user pieces"
)
fig.tight_layout()
plt.show()

# %%
# Saving the model
# ----------------
# A fitted pipeline pickles like any scikit-learn estimator, so a model trained
# once applies to new recordings later (``joblib.dump`` and ``joblib.load``
# work the same way).
import pickle

restored = pickle.loads(pickle.dumps(learned))
print(np.array_equal(restored.predict(X_test), labels["LinkClustering"]))
