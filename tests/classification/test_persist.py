"""save_classifier / load_classifier: round trip, versions, refusals naming the file, no foreign file replaced."""

import copy
import hashlib
import io
import json
import os

import joblib
import numpy as np
import pandas as pd
import pytest
import sklearn
from sklearn.pipeline import make_pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN, __version__
from sklearn_radar.classification import (
    ClassifierVersionWarning,
    ClusterClassifier,
    load_classifier,
    road_user_class,
    save_classifier,
)
from sklearn_radar.datasets import make_scenes

MAGIC = b"sklearn-radar classifier\n"


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=6.0, random_state=3)


@pytest.fixture(scope="module")
def fitted(scenes):
    stage1 = RadarDBSCAN(metric="xyv", eps_xyv=1.04, vr_scale=1.03, min_samples=3, vr_min=0.5)
    model = make_pipeline(FrameTransform(), DopplerDensityFilter(), ClusterClassifier(stage1))
    return model.fit(scenes.data, road_user_class(scenes.data["label_id"]))


def _file(path, header, payload):
    """A classifier file in the documented layout: magic line, JSON header line, payload."""
    path.write_bytes(MAGIC + json.dumps(header).encode("ascii") + b"\n" + payload)
    return path


def _header(payload, **changes):
    header = {
        "format": 1,
        "sklearn_radar": __version__,
        "sklearn": sklearn.__version__,
        "type": "Pipeline",
        "payload_bytes": len(payload),
        "payload_sha256": hashlib.sha256(payload).hexdigest(),
    }
    return {**header, **changes}


def _pickled(obj):
    buffer = io.BytesIO()
    joblib.dump(obj, buffer)
    return buffer.getvalue()


def test_round_trip_predicts_the_same(fitted, scenes, tmp_path):
    path = tmp_path / "classifier.joblib"
    save_classifier(fitted, path)
    loaded = load_classifier(path)
    pd.testing.assert_frame_equal(
        loaded[-1].predict_instances(loaded[:-1].transform(scenes.data)),
        fitted[-1].predict_instances(fitted[:-1].transform(scenes.data)),
    )
    assert sorted(os.listdir(tmp_path)) == ["classifier.joblib"]  # no temporary left


def test_a_bare_cluster_classifier_round_trips(fitted, scenes, tmp_path):
    path = tmp_path / "bare.joblib"
    save_classifier(fitted[-1], path)
    loaded = load_classifier(path)
    assert isinstance(loaded, ClusterClassifier)
    working = fitted[:-1].transform(scenes.data)
    np.testing.assert_array_equal(loaded.predict(working), fitted[-1].predict(working))


def test_the_header_holds_the_versions_and_the_payload_checksum(fitted, tmp_path):
    path = tmp_path / "classifier.joblib"
    save_classifier(fitted, path)
    raw = path.read_bytes()
    assert raw.startswith(MAGIC)
    line, payload = raw[len(MAGIC) :].split(b"\n", 1)
    header = json.loads(line)
    assert header == _header(payload)
    assert isinstance(joblib.load(io.BytesIO(payload)), type(fitted))


def test_another_sklearn_radar_version_warns_and_loads(fitted, tmp_path):
    payload = _pickled(fitted)
    path = _file(tmp_path / "old.joblib", _header(payload, sklearn_radar="0.0.1"), payload)
    with pytest.warns(ClassifierVersionWarning, match="sklearn-radar 0.0.1"):
        loaded = load_classifier(path)
    assert isinstance(loaded[-1], ClusterClassifier)


def test_another_scikit_learn_version_is_refused(fitted, tmp_path):
    payload = _pickled(fitted)
    path = _file(tmp_path / "other.joblib", _header(payload, sklearn="1.0.2"), payload)
    with pytest.raises(ValueError, match=r"other\.joblib.*scikit-learn 1\.0\.2"):
        load_classifier(path)


def _truncated(raw):
    return raw[: len(raw) - 100]


def _damaged(raw):
    return raw[:-10] + bytes([raw[-10] ^ 0xFF]) + raw[-9:]


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda raw, fitted: b'{"best": "13", "experiments": {}}', "not a classifier file written by sklearn-radar"),
        (lambda raw, fitted: _pickled(fitted), "a plain joblib or pickle file is not loaded"),
        (lambda raw, fitted: _truncated(raw), "truncated"),
        (lambda raw, fitted: raw[: len(MAGIC) + 10], "header line is not JSON"),
        (lambda raw, fitted: _damaged(raw), "damaged"),
        (lambda raw, fitted: raw + b"more", "damaged"),
        (lambda raw, fitted: MAGIC + b'{"format": 2}\n', "format 2"),
        (lambda raw, fitted: MAGIC + b'{"format": 1, "sklearn": "1"}\n', "lacks 'sklearn_radar'"),
        (lambda raw, fitted: b"", "not a classifier file"),
    ],
    ids=["json", "plain-joblib", "truncated", "truncated-header", "damaged", "longer", "format", "header", "empty"],
)
def test_bad_files_are_refused_naming_the_file(fitted, tmp_path, make, match):
    good = tmp_path / "good.joblib"
    save_classifier(fitted, good)
    bad = tmp_path / "bad.joblib"
    bad.write_bytes(make(good.read_bytes(), fitted))
    with pytest.raises(ValueError, match=match) as error:
        load_classifier(bad)
    assert str(bad) in str(error.value)


def test_a_valid_file_of_something_else_is_refused_after_loading(tmp_path):
    payload = _pickled(RadarDBSCAN())
    path = _file(tmp_path / "dbscan.joblib", _header(payload), payload)
    with pytest.raises(ValueError, match=r"dbscan\.joblib: must hold a fitted ClusterClassifier.*got RadarDBSCAN"):
        load_classifier(path)


def test_a_classifier_saved_before_a_parameter_rename_is_refused(fitted, tmp_path):
    # As a file written before frame_length became window: the pickled estimator has the old attribute only.
    old = copy.deepcopy(fitted)
    classifier = old.steps[-1][1]
    classifier.frame_length = classifier.window
    del classifier.window
    payload = _pickled(old)
    path = _file(tmp_path / "old.joblib", _header(payload), payload)
    with pytest.raises(ValueError, match=r"old\.joblib: the classifier was saved with other parameters.*window"):
        load_classifier(path)


def test_a_classifier_saved_before_history_existed_loads_and_classifies_each_window_alone(fitted, tmp_path):
    # As a file written before the history parameter: the pickled estimator lacks the attribute.
    old = copy.deepcopy(fitted)
    del old.steps[-1][1].history
    payload = _pickled(old)
    loaded = load_classifier(_file(tmp_path / "before.joblib", _header(payload), payload))
    assert loaded.steps[-1][1].get_params()["history"] is None


def test_a_payload_that_cannot_be_unpickled_is_refused(tmp_path):
    payload = b"\x80\x05not a pickle"
    path = _file(tmp_path / "junk.joblib", _header(payload), payload)
    with pytest.raises(ValueError, match=r"junk\.joblib: cannot unpickle"):
        load_classifier(path)


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="classifier file not found"):
        load_classifier(tmp_path / "absent.joblib")
    with pytest.raises(ValueError, match="is a folder"):
        load_classifier(tmp_path)


@pytest.mark.parametrize(
    "model, match",
    [
        (RadarDBSCAN(), "got RadarDBSCAN"),
        (make_pipeline(FrameTransform(), RadarDBSCAN()), "a Pipeline ending in RadarDBSCAN"),
        (ClusterClassifier(), "not fitted"),
        (make_pipeline(FrameTransform(), ClusterClassifier()), "not fitted"),
    ],
)
def test_only_a_fitted_cluster_classifier_is_saved(model, match, tmp_path):
    with pytest.raises(ValueError, match=match):
        save_classifier(model, tmp_path / "c.joblib")
    assert list(tmp_path.iterdir()) == []


def test_never_replaces_a_file_it_did_not_write(fitted, tmp_path):
    foreign = tmp_path / "c.joblib"
    foreign.write_text("mine\n")
    with pytest.raises(FileExistsError, match=r"c\.joblib exists and is not a classifier file"):
        save_classifier(fitted, foreign)
    assert foreign.read_text() == "mine\n" and sorted(os.listdir(tmp_path)) == ["c.joblib"]
    link = tmp_path / "link.joblib"
    link.symlink_to(foreign)
    with pytest.raises(FileExistsError, match="symbolic link"):
        save_classifier(fitted, link)


def test_replaces_its_own_file_and_an_empty_one(fitted, tmp_path):
    path = tmp_path / "c.joblib"
    path.write_bytes(b"")
    save_classifier(fitted[-1], path)
    save_classifier(fitted, path)  # a classifier file: replaced
    assert isinstance(load_classifier(path)[-1], ClusterClassifier)
