"""PointClassifier: the baseline without clustering, the same classifier on single detections."""

from __future__ import annotations

from numbers import Real
from typing import ClassVar

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, _fit_context
from sklearn.utils._param_validation import HasMethods, Interval
from sklearn.utils.validation import check_is_fitted

from .._config import config_context
from .._schema import POINT_FEATURE_READS
from .._validation import read_columns
from ..cluster import RadarDBSCAN
from ._classes import BACKGROUND, IGNORED
from ._neighbourhood import NEIGHBOURHOOD_FEATURES, neighbourhood_features
from ._wrapped import check_class_target, class_proba, fit_classifier, macro_f1_score

__all__ = ["NEIGHBOURHOOD_FEATURES", "POINT_FEATURES", "PointClassifier"]

#: ``{feature: (unit, meaning, columns it needs)}`` of a single detection, in the order of the feature rows.
POINT_FEATURES = {
    "v_r": ("m/s", "compensated Doppler velocity", ("v_r",)),
    "rcs": ("dBsm", "radar cross section", ("rcs",)),
    "range_sc": ("m", "range to the measuring sensor", ("range_sc",)),
    "azimuth": ("rad", "line of sight in the car frame, azimuth_sc + sensor_yaw", ("azimuth_sc", "sensor_yaw")),
}


class PointClassifier(BaseEstimator):
    """Classify every detection on its own, then join detections of one class into instances: the baseline.

    What a user would try instead of clustering first: the classifier of
    :class:`ClusterClassifier` on the features of single detections
    (:data:`POINT_FEATURES`: compensated Doppler ``v_r`` in m/s, RCS in
    dBsm, range in m and the car-frame azimuth ``azimuth_sc + sensor_yaw``
    in rad; features whose columns X lacks are left out).  Comparing the
    two shows what the clustering buys: the cluster features see extent,
    Doppler spread, the number of sensors and the velocity of Eq. 6, which a
    single detection cannot show.  The positions are not features (in the
    sequence frame they say where the recording was made, not what the
    object is).

    With ``radius`` set, each detection also gets the features of its
    neighbourhood (:data:`NEIGHBOURHOOD_FEATURES`: the number of detections
    within ``radius`` in x-y and ``time_window`` in time, their x-y spread,
    the mean and standard deviation of their Doppler and RCS, the largest
    RCS), as point-wise learners that group each point's surroundings
    (PointNet++) see them: the fair point-wise rival of the cluster
    classifier.  Neighbours are the kept detections of the same sequence;
    offline they lie within ``time_window`` before or after the detection,
    with ``causal=True`` only before (or at the same time).

    The instance metrics need instance ids, so :meth:`predict_instances`
    joins the detections of each sequence that received the same road-user
    class into connected components: two such detections are connected
    when they lie within ``eps_xy`` in x-y and ``eps_t`` in time (the
    components of a DBSCAN in x, y and t with one point per core, as
    :class:`~sklearn_radar.RadarDBSCAN` with ``metric="xy"``, no Doppler
    limit, ``min_samples=1`` and ``vr_min=-inf`` computes them).
    Detections with ``keep = 0`` (removed by
    :class:`~sklearn_radar.DopplerDensityFilter`) are background and take no
    part in training.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classifier : classifier with ``fit`` and ``predict_proba``, default=None
        Classifies the detections' feature rows (cloned).  None means a
        :class:`~sklearn.ensemble.HistGradientBoostingClassifier` with
        ``max_iter=30`` and ``random_state=0``, the default of
        :class:`ClusterClassifier`.  With scikit-learn's metadata routing
        enabled, a classifier whose ``fit`` asks for ``groups`` gets each
        training detection's sequence as its group.
    eps_xy : float, default=1.0
        Distance in x-y within which two detections of one class join one
        instance, m, > 0.
    eps_t : float, default=0.25
        Time within which they may join, s, >= 0 (the paper's eps_t).
    radius : float or None, default=None
        x-y radius of a detection's neighbourhood, m, > 0.  None: no
        neighbourhood features, the four features of a single detection.
    time_window : float, default=0.25
        Time within which a neighbour lies, s, > 0: before or after the
        detection, or only before it with ``causal=True``.  Used only with
        ``radius``.
    causal : bool, default=False
        Neighbours from the past only (what a car can compute scan by scan).
        Used only with ``radius``.

    Attributes
    ----------
    classes_ : ndarray of int64
        The class codes it predicts, sorted; always includes -1 (background).
        The codes of :func:`~sklearn_radar.classification.road_user_class`,
        not the devkit's: see :class:`ClusterClassifier` for the table and
        :func:`~sklearn_radar.classification.devkit_class_index`.
    classifier_ : classifier
        The fitted clone of ``classifier`` (a
        :class:`~sklearn.dummy.DummyClassifier` of the one class, with a
        warning, when the training detections hold a single class).
    feature_names_ : ndarray of str
        The features of :data:`POINT_FEATURES` it uses, then those of
        :data:`NEIGHBOURHOOD_FEATURES` with ``radius``.
    n_training_examples_ : int
        The detections it was trained on (kept by the filter, not ignored).
    n_features_in_ : int
        Number of columns seen in :meth:`fit`.
    feature_names_in_ : ndarray of str
        Column names seen in :meth:`fit`, when X is a DataFrame.

    See Also
    --------
    ClusterClassifier : classification of clusters.

    Notes
    -----
    A plain array is read by position in the order of
    :data:`~sklearn_radar._schema.CLASSIFIER_LAYOUT`.  Unlike
    :class:`ClusterClassifier`, :meth:`predict` and :meth:`predict_proba` of
    a detection do not depend on the other detections without ``radius``;
    the instance ids do.  With ``radius`` they depend on its neighbours.

    Examples
    --------
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn_radar import FrameTransform
    >>> from sklearn_radar.classification import PointClassifier, road_user_class
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=1, duration=4.0, random_state=0)
    >>> y = road_user_class(scenes.data["label_id"])
    >>> model = make_pipeline(FrameTransform(), PointClassifier()).fit(scenes.data, y)
    >>> model.predict(scenes.data).shape == y.shape
    True
    """

    _parameter_constraints: ClassVar[dict] = {
        "classifier": [HasMethods(["fit", "predict_proba"]), None],
        "eps_xy": [Interval(Real, 0, None, closed="neither")],
        "eps_t": [Interval(Real, 0, None, closed="left")],
        "radius": [Interval(Real, 0, None, closed="neither"), None],
        "time_window": [Interval(Real, 0, None, closed="neither")],
        "causal": ["boolean"],
    }

    def __init__(self, classifier=None, *, eps_xy=1.0, eps_t=0.25, radius=None, time_window=0.25, causal=False):
        self.classifier = classifier
        self.eps_xy = eps_xy
        self.eps_t = eps_t
        self.radius = radius
        self.time_window = time_window
        self.causal = causal

    @_fit_context(prefer_skip_nested_validation=False)
    def fit(self, X, y):
        """Fit the classifier on the features of the kept detections.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections (the output of :class:`~sklearn_radar.FrameTransform`),
            or an array in the order of :data:`~sklearn_radar._schema.CLASSIFIER_LAYOUT`.
        y : array-like of int, shape (n_detections,)
            Road-user class of each detection: -1 background, -2 ignored (left
            out), >= 0 a road-user class.

        Returns
        -------
        self : PointClassifier
        """
        _, c = read_columns(self, X, POINT_FEATURE_READS, reset=True)
        classes = check_class_target(y, len(c["x"]), type(self).__name__)
        features, self.feature_names_ = self._features(c)
        learn = _kept(c) & (classes != IGNORED)
        groups = None if c["sequence"] is None else c["sequence"][learn]
        self.classifier_ = fit_classifier(
            self.classifier, features[learn], classes[learn], self.feature_names_, self, groups=groups
        )
        self.classes_ = np.union1d([BACKGROUND], np.asarray(self.classifier_.classes_, dtype=np.int64))
        self.n_training_examples_ = int(np.count_nonzero(learn))
        return self

    def predict(self, X):
        """Road-user class of each detection, -1 for background (and for detections the filter removed).

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit`.

        Returns
        -------
        classes : ndarray of int64, shape (n_detections,)
        """
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]

    def predict_proba(self, X):
        """Probability of each class of ``classes_`` for each detection.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit`.

        Returns
        -------
        proba : ndarray of float64, shape (n_detections, n_classes)
            Rows of detections with ``keep = 0`` are 1 for background (-1).
        """
        proba, _ = self._proba(X)
        return proba

    def score(self, X, y):
        """Point-wise macro-F1 of :meth:`predict` on X against the codes ``y`` (as :meth:`ClusterClassifier.score`).

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`predict`.
        y : array-like of int, shape (n_detections,)
            True road-user class of each detection, as for :meth:`fit`
            (detections of class -2, ignored, are left out).

        Returns
        -------
        score : float
            Macro-F1 over the classes (background included), dimensionless,
            in [0, 1].
        """
        return macro_f1_score(self, X, y)

    def predict_instances(self, X):
        """The road users in X: a class, an instance id and a confidence per detection.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit`.

        Returns
        -------
        instances : DataFrame of shape (n_detections, 3)
            Row for row with X (with X's index when X is a DataFrame):
            ``class`` (int64, -1 background), ``instance`` (int64, -1 where the
            class is -1: the connected component of the detection among the
            detections of its class and sequence, numbered 0, 1, ... in order
            of first row, unique across sequences) and ``confidence``
            (float64: the mean, over the instance's detections, of the
            probability of its class; 1 for background), one ranking score
            per instance.
        """
        proba, c = self._proba(X)
        best = np.argmax(proba, axis=1)
        classes = self.classes_[best]
        confidence = proba[np.arange(len(best)), best]
        instance = self._components(c, classes)
        found = instance >= 0
        if found.any():
            sums = np.bincount(instance[found], weights=confidence[found])
            confidence[found] = (sums / np.bincount(instance[found]))[instance[found]]
        index = X.index if isinstance(X, pd.DataFrame) else None
        return pd.DataFrame({"class": classes, "instance": instance, "confidence": confidence}, index=index)

    def _proba(self, X):
        check_is_fitted(self)
        _, c = read_columns(self, X, POINT_FEATURE_READS, reset=False)
        features, _ = self._features(c)
        proba = np.zeros((len(c["x"]), len(self.classes_)))
        proba[:, np.searchsorted(self.classes_, BACKGROUND)] = 1.0
        kept = _kept(c)
        proba[kept] = class_proba(self.classifier_, features[kept], self.feature_names_, self.classes_)
        return proba, c

    def _features(self, c):
        """The feature rows of every detection and their names: the point's, then its neighbourhood's."""
        features, names = _point_features(c)
        if self.radius is None:
            return features, names
        kept = np.flatnonzero(_kept(c))
        around = neighbourhood_features(c, kept, self.radius, self.time_window, self.causal)
        extra = np.full((len(features), len(around)), np.nan)
        extra[kept] = np.column_stack(list(around.values()))
        return np.column_stack([features, extra]), np.asarray([*names, *around], dtype=object)

    def _components(self, c, classes):
        """Connected components of the detections of each (sequence, class), -1 for background."""
        instance = np.full(len(classes), -1, dtype=np.int64)
        found = np.flatnonzero(classes != BACKGROUND)
        if not len(found):
            return instance
        sequence = np.zeros(len(classes)) if c["sequence"] is None else c["sequence"]
        pseudo = pd.factorize(pd.MultiIndex.from_arrays([sequence[found], classes[found]]))[0]
        points = pd.DataFrame(
            {"x": c["x"][found], "y": c["y"][found], "v_r": c["v_r"][found], "t": c["t"][found], "sequence": pseudo}
        )
        no_doppler_limit = np.finfo(np.float64).max  # eps_vr must be finite; no Doppler difference reaches it
        components = RadarDBSCAN(
            metric="xy", eps_xy=self.eps_xy, eps_vr=no_doppler_limit, eps_t=self.eps_t, min_samples=1, vr_min=-np.inf
        )
        with config_context(check_plausibility=False):  # X was checked; a subset of one class is no radar scan
            instance[found] = components.fit(points).labels_
        return instance


def _kept(c):
    return np.ones(len(c["x"]), dtype=bool) if c["keep"] is None else c["keep"] != 0


def _point_features(c):
    """The feature rows of :data:`POINT_FEATURES` whose columns are present, and their names."""
    columns = {"v_r": c["v_r"], "rcs": c["rcs"], "range_sc": c["range_sc"]}
    if c["azimuth_sc"] is not None and c["sensor_yaw"] is not None:
        columns["azimuth"] = np.remainder(c["azimuth_sc"] + c["sensor_yaw"] + np.pi, 2.0 * np.pi) - np.pi
    present = {name: values for name, values in columns.items() if values is not None}
    names = np.asarray(list(present), dtype=object)
    return np.column_stack(list(present.values())), names
