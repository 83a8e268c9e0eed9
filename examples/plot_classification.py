"""
Road users with a class: the stage after clustering
===================================================

The framework of Scheiner et al. (2019) clusters radar detections so that a
classifier can work on clusters: "object instances in the radar data have to be
identified and classified".  This example runs the whole chain on simulated data,
from detections to classified road users, and compares it with the baseline a user
would try instead, a classifier of single detections.
"""

# %%
# Data
# ----
# Simulated recordings (realistic preset): six for training and three others for
# testing.  The classifiers learn the road-user class of each detection, from the
# RadarScenes ``label_id`` mapped as the RadarScenes devkit maps it
# (:func:`~sklearn_radar.classification.road_user_class`): car, large vehicle,
# two-wheeler, pedestrian, pedestrian group, and -1 for static background.
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from sklearn.metrics import ConfusionMatrixDisplay, f1_score
from sklearn.pipeline import make_pipeline

from sklearn_radar.classification import (
    ROAD_USER_CLASSES,
    ClusterClassifier,
    PointClassifier,
    cluster_features,
    predict_instances,
    road_user_class,
)
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import semantic_scores

train = make_scenes(n_sequences=6, duration=20.0, random_state=0)
test = make_scenes(n_sequences=3, duration=20.0, random_state=1)
y_train = road_user_class(train.data["label_id"])
y_test = road_user_class(test.data["label_id"])
names = {-1: "background", **ROAD_USER_CLASSES}
print(pd.Series(y_train).map(names).value_counts().to_string())

# %%
# The pipeline
# ------------
# The frame transform, the Doppler-density filter and stage 1 of the paper's best
# experiment (#8), then :class:`~sklearn_radar.classification.ClusterClassifier`,
# which wraps the clusterer as :class:`~sklearn_radar.ClusterMerger` wraps its
# stage 1.  It cuts every cluster into 0.5 s windows, describes each part by its
# features (extent, Doppler and RCS statistics, the Eq. 6 velocity, ...) and
# classifies it with a histogram gradient-boosting classifier.  It learns from the
# clusters matched to the ground truth: a part takes the class of the annotated
# road user it overlaps with an IoU above 0.5, and is background otherwise.
paper = experiment_pipeline(8)
model = make_pipeline(
    paper["frame"], paper["filter"], ClusterClassifier(paper["cluster"])
)
model.fit(train.data, y_train)
predicted = model.predict(test.data)

# %%
# The baseline: the same classifier on single detections (compensated Doppler,
# RCS, range and azimuth), with instances joined as connected components of the
# detections of one class.
baseline = make_pipeline(paper["frame"], PointClassifier())
baseline.fit(train.data, y_train)
predicted_points = baseline.predict(test.data)

# %%
# Point-wise scores
# -----------------
# Every detection of the test recordings counts, as in semantic segmentation: a
# road-user detection that the clustering leaves as noise is a miss of the cluster
# classifier.  F1 per class and its mean over the five road-user classes:
road_users = list(ROAD_USER_CLASSES)
scores = pd.DataFrame(
    {
        "clusters (#8) + classifier": f1_score(
            y_test, predicted, labels=road_users, average=None
        ),
        "single detections": f1_score(
            y_test, predicted_points, labels=road_users, average=None
        ),
    },
    index=[ROAD_USER_CLASSES[code] for code in road_users],
)
scores.loc["macro-F1"] = scores.mean()
print(scores.round(3).to_string())

# %%
# Road users, not detections
# --------------------------
# The semantic instance-segmentation scores count road users per 0.5 s window
# (:func:`~sklearn_radar.metrics.semantic_scores`): class PQ and mAP@0.5 need a
# predicted instance of the right class with IoU > 0.5 against an annotated one;
# mCov is the class-agnostic coverage of the annotated instances.  A pipeline
# passes on ``predict`` but not the classifier's own ``predict_instances``:
# :func:`~sklearn_radar.classification.predict_instances` runs the pipeline's
# other steps, then it.
times = test.data["timestamp"].to_numpy() * 1e-6


def instance_scores_of(pipeline):
    found = predict_instances(pipeline, test.data)
    return semantic_scores(
        y_test,
        test.target,
        found["class"].to_numpy(),
        found["instance"].to_numpy(),
        found["confidence"].to_numpy(),
        times=times,
        groups=test.groups,
    )


keys = ["pq", "map", "macro_f1", "mcov"]
instance_table = pd.DataFrame(
    {
        name: [instance_scores_of(pipeline)[key] for key in keys]
        for name, pipeline in (
            ("clusters (#8) + classifier", model),
            ("single detections", baseline),
        )
    },
    index=["class PQ", "mAP@0.5", "macro-F1 (background counted)", "mCov"],
)
print(instance_table.round(3).to_string())

# %%
# Where the errors are: the confusion matrix of the cluster classifier, each row
# normalised by the true class (background is most of the data).
labels = [-1, *road_users]
fig, ax = plt.subplots(figsize=(7.5, 6.5))
ConfusionMatrixDisplay.from_predictions(
    y_test,
    predicted,
    labels=labels,
    display_labels=[names[code] for code in labels],
    normalize="true",
    values_format=".2f",
    xticks_rotation=45,
    colorbar=False,
    ax=ax,
)
ax.set_title("Cluster classifier, point-wise (rows: true class)")
fig.tight_layout()
plt.show()

# %%
# Classified road users
# ---------------------
# Half a second of the first test recording: the ground-truth class of each
# detection, and the road users the pipeline finds, each cluster labelled with its
# class and confidence (``predict_instances`` gives class, instance id and
# confidence per detection).
Xt = model[:-1].transform(test.data)
found = model[-1].predict_instances(Xt)
t = Xt["t"].to_numpy()
first = test.groups == test.groups[0]
busiest = np.bincount(
    np.floor(t[first & (y_test >= 0)] - t[first].min()).astype(int)
).argmax()
start = t[first].min() + busiest
now = first & (t >= start) & (t < start + 0.5)
x, y = Xt["x"].to_numpy(), Xt["y"].to_numpy()
colours = {-1: "0.85", 0: "tab:blue", 1: "tab:purple", 2: "tab:green", 3: "tab:red"}
colours[4] = "tab:orange"
fig, axes = plt.subplots(1, 2, figsize=(12, 5.5), sharex=True, sharey=True)
for ax, classes, title in (
    (axes[0], y_test, "ground truth"),
    (axes[1], found["class"].to_numpy(), "pipeline: classified clusters"),
):
    for code, colour in colours.items():
        mine = now & (classes == code)
        ax.scatter(
            x[mine], y[mine], s=4 if code < 0 else 12, c=colour, label=names[code]
        )
    ax.set(title=title, xlabel="x (m, FCS)", aspect="equal")
for instance in np.unique(found["instance"][now & (found["instance"] >= 0)]):
    mine = now & (found["instance"] == instance).to_numpy()
    code, confidence = found["class"][mine].iloc[0], found["confidence"][mine].iloc[0]
    axes[1].annotate(
        f"{names[code]} {confidence:.2f}", (x[mine].mean(), y[mine].mean()), fontsize=8
    )
users = now & (y_test >= 0)
axes[0].set(
    xlim=(x[users].min() - 15, x[users].max() + 15),
    ylim=(y[users].min() - 15, y[users].max() + 15),
    ylabel="y (m, FCS)",
)
axes[0].legend(loc="lower left", markerscale=2, fontsize=8)
fig.tight_layout()
plt.show()

# %%
# What the data hold
# ------------------
# A classifier can only learn what tells the classes apart.  The features of the
# annotated road users themselves (each object's detections per 0.5 s window): the
# simulator gives each class its own RCS, extent and Doppler spread (the
# micro-Doppler of limbs and wheels), so on perfectly clustered road users the
# classes separate well; the errors above come mostly from the clustering.
Xtrain = model[:-1].transform(train.data)
truth, rows = cluster_features(Xtrain, train.target, window=0.5, return_rows=True)
truth["class"] = (
    pd.Series(y_train[rows >= 0], index=rows[rows >= 0]).groupby(level=0).first()
)
fig, axes = plt.subplots(1, 3, figsize=(13, 4))
for ax, (feature, unit) in zip(
    axes, [("rcs_mean", "dBsm"), ("extent_along", "m"), ("vr_std", "m/s")], strict=True
):
    ax.boxplot(
        [truth.loc[truth["class"] == code, feature] for code in road_users],
        showfliers=False,
    )
    ax.set_xticks(range(1, 6), [ROAD_USER_CLASSES[c] for c in road_users], rotation=30)
    ax.set(title=feature, ylabel=unit)
fig.tight_layout()
plt.show()
