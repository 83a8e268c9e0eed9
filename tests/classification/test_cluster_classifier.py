"""ClusterClassifier: what it is fitted on, what it predicts per detection, and the framework's pipeline around it."""

import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import BaseEstimator, ClassifierMixin, ClusterMixin
from sklearn.dummy import DummyClassifier
from sklearn.ensemble import HistGradientBoostingClassifier
from sklearn.metrics import f1_score
from sklearn.model_selection import GroupKFold, cross_validate
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import FunctionTransformer

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.classification import (
    ClusterClassifier,
    PointClassifier,
    cluster_features,
    predict_instances,
    road_user_class,
)
from sklearn_radar.datasets import make_scenes

ROAD_USERS = [0, 1, 2, 3, 4]


class Given(ClusterMixin, BaseEstimator):
    """A clusterer that returns the labels it is given (the clusters are then known to the test)."""

    def __init__(self, labels=None):
        self.labels = labels

    def fit(self, X, y=None):
        self.labels_ = np.asarray(self.labels)
        return self


class Recording(ClassifierMixin, BaseEstimator):
    """Remembers what it is fitted on; predicts car (0.8) for segments of >= 3 detections, else background (0.9)."""

    def fit(self, X, y):
        self.X_, self.y_ = X.copy(), np.asarray(y)
        self.classes_ = np.array([-1, 0])
        return self

    def predict_proba(self, X):
        car = X["n_detections"].to_numpy() >= 3
        return np.where(car[:, None], [0.2, 0.8], [0.9, 0.1])


class AllCars(Recording):
    """Every segment is a car."""

    def predict_proba(self, X):
        return np.tile([0.0, 1.0], (len(X), 1))


def _detections():
    """Two sequences by hand: a car (3 detections, then 2 in the next 0.5 s window), a pedestrian, background."""
    return pd.DataFrame(
        {
            "x": [0.0, 0.5, 1.0, 0.2, 0.7, 20.0, 20.3, 40.0, 41.0, 0.0, 0.4, 9.0],
            "y": [0.0, 0.1, 0.0, 0.0, 0.1, 5.0, 5.1, -3.0, -3.0, 0.0, 0.0, 9.0],
            "v_r": [5.0, 5.1, 4.9, 5.0, 5.2, 1.0, 1.4, 0.0, 0.0, -1.0, -1.2, 0.0],
            "t": [0.0, 0.1, 0.2, 0.6, 0.7, 0.1, 0.2, 0.0, 0.3, 0.0, 0.1, 0.2],
            "sequence": [1, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2],
            "rcs": [5.0, 8.0, 2.0, 4.0, 6.0, -8.0, -9.0, 10.0, 12.0, -7.0, -6.0, 0.0],
            "track_id": ["car", "car", "car", "car", "car", "ped", "ped", "", "", "ped", "ped", ""],
            "label_id": [0, 0, 0, 0, 0, 7, 7, 11, 11, 7, 7, 11],
        }
    )


#: Clusters of _detections(): the car's first window (0), its second window with a wall detection (1), the
#: pedestrian of sequence 1 (2), a wall (3), the pedestrian of sequence 2 (4) and noise.
LABELS = np.array([0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, -1])


def test_fitted_on_the_features_and_the_iou_targets_of_the_segments():
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording(), window=0.5).fit(X, road_user_class(X["label_id"]))
    expected = cluster_features(X, LABELS, window=0.5)
    recorded = model.classifier_
    np.testing.assert_array_equal(recorded.X_.to_numpy(), expected.iloc[:, 3:].to_numpy(dtype=float))
    assert list(recorded.X_.columns) == list(expected.columns[3:]) == list(model.feature_names_)
    # Segments in (sequence, cluster, window) order: car window 0, car window 1, pedestrian, wall, pedestrian.
    assert expected[["sequence", "cluster", "window"]].to_numpy().tolist() == [
        [1, 0, 0], [1, 1, 1], [1, 2, 0], [1, 3, 0], [2, 4, 0]
    ]  # fmt: skip
    assert recorded.y_.tolist() == [0, 0, 3, -1, 3]
    assert model.classes_.tolist() == [-1, 0]


class GroupRecording(Recording):
    """Recording, and the groups its fit is given (it asks for them when metadata routing is on)."""

    def fit(self, X, y, groups=None):
        self.groups_ = None if groups is None else np.asarray(groups)
        return super().fit(X, y)


def test_a_classifier_asking_for_groups_gets_each_segments_sequence_when_routing_is_on():
    import sklearn

    X = _detections()
    y = road_user_class(X["label_id"])
    with sklearn.config_context(enable_metadata_routing=True):
        asking = GroupRecording().set_fit_request(groups=True)
        model = ClusterClassifier(Given(LABELS), asking, window=0.5).fit(X, y)
        assert model.classifier_.groups_.tolist() == [1, 1, 1, 1, 2]  # the segments' sequences, in segment order
        not_asking = ClusterClassifier(Given(LABELS), GroupRecording(), window=0.5).fit(X, y)
        assert not_asking.classifier_.groups_ is None
    off = ClusterClassifier(Given(LABELS), GroupRecording(), window=0.5).fit(X, y)  # routing off: no groups
    assert off.classifier_.groups_ is None


def test_a_grouped_calibration_splits_by_sequence(scenes):
    import sklearn
    from sklearn.calibration import CalibratedClassifierCV

    train, _ = scenes
    y = road_user_class(train.data["label_id"])
    calibrated = CalibratedClassifierCV(HistGradientBoostingClassifier(max_iter=5), cv=GroupKFold(2))
    with pytest.raises(ValueError, match="groups"):  # without the sequences GroupKFold cannot split
        _pipeline(classifier=calibrated).fit(train.data, y)
    with sklearn.config_context(enable_metadata_routing=True):
        model = _pipeline(classifier=calibrated).fit(train.data, y)
    assert len(model[-1].classifier_.calibrated_classifiers_) == 2


def test_whole_clusters_without_windows():
    # window=None: the car's two clusters each hold part of the car (3 and 2 of 5): only the first matches.
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording(), window=None).fit(X, road_user_class(X["label_id"]))
    assert model.classifier_.y_.tolist() == [0, -1, 3, -1, 3]


def test_ignored_instances_are_left_out_of_training():
    X = _detections().assign(label_id=lambda d: d["label_id"].replace({7: 9}))  # the pedestrians become ANIMALs
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    assert model.classifier_.y_.tolist() == [0, 0, -1]  # the two ANIMAL segments are gone


def test_without_instance_ids_the_class_segments_are_the_instances():
    # One object per class and window here, so the "stuff" rule gives the same targets as the track ids.
    X = _detections()
    y = road_user_class(X["label_id"])
    by_track = ClusterClassifier(Given(LABELS), Recording()).fit(X, y)
    by_class = ClusterClassifier(Given(LABELS), Recording(), instance_column=None).fit(X.drop(columns="track_id"), y)
    assert by_class.classifier_.y_.tolist() == by_track.classifier_.y_.tolist()


def test_every_detection_gets_its_segments_class_instance_and_confidence():
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    result = model.predict_instances(X)
    # Segments of >= 3 detections are cars (0.8): the car's first window only; the rest background (0.9), noise 1.
    assert result["class"].tolist() == [0, 0, 0] + [-1] * 9
    assert result["instance"].tolist() == [0, 0, 0] + [-1] * 9
    np.testing.assert_allclose(result["confidence"], [0.8] * 3 + [0.9] * 8 + [1.0])
    np.testing.assert_array_equal(model.predict(X), result["class"])
    proba = model.predict_proba(X)
    np.testing.assert_allclose(proba[0], [0.2, 0.8])
    np.testing.assert_allclose(proba[-1], [1.0, 0.0])  # noise: background
    assert result.index.equals(X.index)


def test_one_cluster_is_one_instance_over_its_windows_and_instances_do_not_span_sequences():
    X = _detections()
    labels = np.array([0, 0, 0, 0, 0, 2, 2, 3, 3, 2, 2, -1])  # label 2 in both sequences; the car one cluster
    model = ClusterClassifier(Given(labels), AllCars()).fit(X, road_user_class(X["label_id"]))
    assert model.predict_instances(X)["instance"].tolist() == [0, 0, 0, 0, 0, 1, 1, 2, 2, 3, 3, -1]


def test_given_labels_are_classified_without_running_the_clusterer():
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    model.clusterer = Given(np.zeros(3))  # would fail (wrong length) if it were run
    # Other cluster ids for the same clusters: the same classes and instances as for LABELS (hand-checked above).
    result = model.predict_instances_of(X, np.where(LABELS >= 0, 10 * LABELS + 7, -1))
    assert result["class"].tolist() == [0, 0, 0] + [-1] * 9
    assert result["instance"].tolist() == [0, 0, 0] + [-1] * 9
    np.testing.assert_allclose(result["confidence"], [0.8] * 3 + [0.9] * 8 + [1.0])
    # The car one cluster over two windows (3 and 2 detections), the pedestrian and the wall one cluster.
    joined = model.predict_instances_of(X, np.array([0, 0, 0, 0, 0, 2, 2, 2, 2, -1, -1, -1]))
    # Segments: car window 0 (3, car), car window 1 (2, background), pedestrian + wall in sequence 1 (4, car).
    assert joined["class"].tolist() == [0, 0, 0, -1, -1, 0, 0, 0, 0, -1, -1, -1]
    assert joined["instance"].tolist() == [0, 0, 0, -1, -1, 1, 1, 1, 1, -1, -1, -1]


def test_predict_instances_is_predict_instances_of_the_clusterers_labels():
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    pd.testing.assert_frame_equal(model.predict_instances(X), model.predict_instances_of(X, LABELS))


@settings(max_examples=25, deadline=None)
@given(ids=st.lists(st.integers(0, 10**9), min_size=5, max_size=5, unique=True))
def test_given_labels_count_only_as_a_partition(ids):
    # Any other ids for the same five clusters: the same classes, instances and confidences.
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    renamed = np.array([ids[label] if label >= 0 else -1 for label in LABELS])
    pd.testing.assert_frame_equal(model.predict_instances_of(X, renamed), model.predict_instances_of(X, LABELS))


@pytest.mark.parametrize(
    "labels, match",
    [(LABELS[:-1], "one label per row of X"), (LABELS.astype(str), "integers"), (LABELS + 0.5, "integers")],
)
def test_bad_given_labels_raise(labels, match):
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    with pytest.raises(ValueError, match=match):
        model.predict_instances_of(X, labels)


def test_score_is_the_pointwise_macro_f1_by_hand():
    X = _detections()
    y = road_user_class(X["label_id"])
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, y)
    # Predicted: car for the first 3 rows, background elsewhere (above).  Car: TP 3, FN 2 -> F1 6/8; pedestrian:
    # TP 0 -> 0; background: 3 true rows, all among the 9 predicted -> F1 6/12.  Mean over the three classes.
    assert model.score(X, y) == pytest.approx((0.75 + 0.0 + 0.5) / 3)
    assert model.score(X, y) == pytest.approx(f1_score(y, model.predict(X), average="macro"))
    # Ignored detections (-2) are left out: the two wall rows of sequence 1 as ANIMAL.  Background: 1 true row,
    # 7 predicted -> F1 2/8.
    ignored = y.copy()
    ignored[[7, 8]] = -2
    assert model.score(X, ignored) == pytest.approx((0.75 + 0.0 + 0.25) / 3)
    with pytest.raises(ValueError, match="y has 11 values for 12 detections"):
        model.score(X, y[:-1])


def test_a_pipeline_scores_and_searches_with_the_classifiers_score():
    X = _detections()
    y = road_user_class(X["label_id"])
    model = make_pipeline(FunctionTransformer(), ClusterClassifier(Given(LABELS), Recording())).fit(X, y)
    assert model.score(X, y) == pytest.approx((0.75 + 0.0 + 0.5) / 3)
    point = make_pipeline(FunctionTransformer(), PointClassifier(AllCars())).fit(X, y)
    # Everything predicted car: car F1 2 * 5 / (2 * 5 + 7) (7 false positives); pedestrian and background 0.
    assert point.score(X, y) == pytest.approx(10 / 17 / 3)


def test_predict_instances_of_a_pipeline_is_its_last_steps_on_the_transformed_rows():
    X = _detections()
    y = road_user_class(X["label_id"])
    # The first step supplies the rcs column that the classifier was fitted with.
    add_rcs = FunctionTransformer(lambda frame: frame.assign(rcs=X["rcs"].to_numpy()))
    raw = X.drop(columns="rcs")
    model = make_pipeline(add_rcs, ClusterClassifier(Given(LABELS), Recording())).fit(raw, y)
    found = predict_instances(model, raw)
    pd.testing.assert_frame_equal(found, model[-1].predict_instances(model[:-1].transform(raw)))
    assert found["class"].tolist() == [0, 0, 0] + [-1] * 9  # as by hand above
    with pytest.raises(ValueError, match="rcs"):
        model[-1].predict_instances(raw)  # the step that adds rcs was skipped
    # A classifier itself: its own method.
    working = model[:-1].transform(raw)
    pd.testing.assert_frame_equal(predict_instances(model[-1], working), model[-1].predict_instances(working))
    with pytest.raises(ValueError, match=r"last step must have predict_instances.*FunctionTransformer"):
        predict_instances(make_pipeline(FunctionTransformer()).fit(X), X)


@pytest.fixture(scope="module")
def scenes():
    train = make_scenes(n_sequences=4, duration=10.0, random_state=11)
    test = make_scenes(n_sequences=2, duration=10.0, random_state=12)
    return train, test


def _pipeline(clusterer=None, **params):
    stage1 = RadarDBSCAN(metric="xyv", eps_xyv=1.04, vr_scale=1.03, min_samples=3, vr_min=0.5)
    return make_pipeline(FrameTransform(), DopplerDensityFilter(), ClusterClassifier(clusterer or stage1, **params))


def test_learns_road_users_on_held_out_sequences(scenes):
    train, test = scenes
    model = _pipeline().fit(train.data, road_user_class(train.data["label_id"]))
    y = road_user_class(test.data["label_id"])
    predicted = model.predict(test.data)
    assert predicted.shape == y.shape
    # Far better than the best constant guess (background everywhere: macro-F1 0 over the road users).
    present = np.unique(y[y >= 0])
    assert len(present) >= 3
    assert f1_score(y, predicted, labels=present, average="macro") > 0.3
    # Most predicted road-user detections are road users of that class.
    objects = predicted >= 0
    assert np.mean(predicted[objects] == y[objects]) > 0.6


def test_prediction_reads_no_ground_truth(scenes):
    train, test = scenes
    model = _pipeline().fit(train.data, road_user_class(train.data["label_id"]))
    with_truth = model[:-1].transform(test.data)
    # The truth erased, the columns kept (scikit-learn checks that predict sees the columns of fit).
    without = with_truth.assign(label_id=11, track_id="", uuid="")
    pd.testing.assert_frame_equal(model[-1].predict_instances(with_truth), model[-1].predict_instances(without))


def test_predictions_agree_with_each_other(scenes):
    train, test = scenes
    model = _pipeline().fit(train.data, road_user_class(train.data["label_id"]))
    Xt = model[:-1].transform(test.data)
    result = model[-1].predict_instances(Xt)
    proba = model[-1].predict_proba(Xt)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)
    np.testing.assert_array_equal(model[-1].classes_[np.argmax(proba, axis=1)], result["class"])
    np.testing.assert_allclose(result["confidence"], proba.max(axis=1))
    assert ((result["instance"] == -1) == (result["class"] == -1)).all()
    # An instance is one cluster of one sequence: one sequence per instance.
    per_instance = pd.DataFrame({"instance": result["instance"], "sequence": Xt["sequence"]})[result["instance"] >= 0]
    assert (per_instance.groupby("instance")["sequence"].nunique() == 1).all()
    assert sorted(per_instance["instance"].unique()) == list(range(per_instance["instance"].nunique()))


def test_after_the_cluster_merger_and_in_grouped_cross_validation(scenes):
    train, _ = scenes
    merger = ClusterMerger(stage1=RadarDBSCAN(metric="xyv", eps_xyv=1.04, vr_scale=1.03, min_samples=3, vr_min=0.5))
    model = _pipeline(merger)
    y = road_user_class(train.data["label_id"])
    scores = cross_validate(model, train.data, y, groups=train.groups, cv=GroupKFold(2), scoring="f1_macro")
    assert scores["test_score"].shape == (2,) and np.all(np.isfinite(scores["test_score"]))
    assert np.all(scores["test_score"] > 0.1)  # 6 classes, 5 of them road users: chance is far below


def test_the_given_estimators_are_cloned(scenes):
    train, _ = scenes
    stage1, classifier = RadarDBSCAN(vr_min=0.5), HistGradientBoostingClassifier(max_iter=5)
    _pipeline(stage1, classifier=classifier).fit(train.data, road_user_class(train.data["label_id"]))
    assert not hasattr(stage1, "labels_") and not hasattr(classifier, "n_iter_")


def test_a_single_training_class_warns_and_predicts_it():
    X = _detections()
    y = np.full(len(X), -1)  # no road user at all
    with pytest.warns(UserWarning, match="one class only"):
        model = ClusterClassifier(Given(LABELS)).fit(X, y)
    assert isinstance(model.classifier_, DummyClassifier)
    assert (model.predict(X) == -1).all()


def test_features_missing_at_prediction_raise():
    X = _detections()
    model = ClusterClassifier(Given(LABELS), Recording()).fit(X, road_user_class(X["label_id"]))
    with pytest.raises(ValueError, match="rcs"):
        model.predict(X.drop(columns="rcs"))


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda X, y: (X.drop(columns="track_id"), y), "no instance column 'track_id'"),
        (lambda X, y: (X.drop(columns="track_id").to_numpy(dtype=float), y), "plain array holds no instance ids"),
        (lambda X, y: (X, y[:-1]), "y has 11 values for 12 detections"),
        (lambda X, y: (X, y - 2), "class code -3"),
        (lambda X, y: (X, np.array(["car"] * len(y))), "Unknown label type"),
        (lambda X, y: (X, None), "requires y"),
    ],
)
def test_bad_targets_name_the_problem(change, match):
    X = _detections()
    X, y = change(X.drop(columns="label_id"), road_user_class(_detections()["label_id"]))
    if not isinstance(X, pd.DataFrame):
        X = X[:, [0, 1, 2, 3]]  # x, y, v_r, t: the first columns of the classifier layout
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        with pytest.raises(ValueError, match=match):
            ClusterClassifier(Given(LABELS), Recording()).fit(X, y)


def test_true_segments_are_learned_beside_the_clusters_from_the_kept_detections():
    X = _detections().assign(keep=True)
    X.loc[4, "keep"] = False  # the filter dropped the car's second detection of its second window
    y = road_user_class(X["label_id"])
    model = ClusterClassifier(Given(LABELS), Recording(), true_segments=True).fit(X, y)
    # The ground truth's segments by hand: the car's two windows (the second without row 4), each pedestrian.
    truth = np.array([0, 0, 0, 0, -1, 1, 1, -1, -1, 2, 2, -1])
    expected = pd.concat([cluster_features(X, LABELS, window=0.5), cluster_features(X, truth, window=0.5)])
    np.testing.assert_array_equal(model.classifier_.X_.to_numpy(), expected.iloc[:, 3:].to_numpy(dtype=float))
    assert model.classifier_.y_.tolist() == [0, 0, 3, -1, 3, 0, 0, 3, 3]  # the clusters, then the true segments
    assert model.n_training_examples_ == 9
    without = ClusterClassifier(Given(LABELS), Recording()).fit(X, y)
    np.testing.assert_array_equal(without.predict(X), model.predict(X))  # prediction does not read the truth


def test_true_segments_teach_the_classes_a_clusterer_misses():
    X = _detections()
    y = road_user_class(X["label_id"])
    with pytest.warns(UserWarning, match="one class only"):
        assert ClusterClassifier(Given(np.full(len(X), -1))).fit(X, y).classes_.tolist() == [-1]
    model = ClusterClassifier(Given(np.full(len(X), -1)), Recording(), true_segments=True).fit(X, y)
    assert model.classifier_.y_.tolist() == [0, 0, 3, 3]
