"""ClusterClassifier: the framework's next stage, a class for every cluster (semantic instance segmentation)."""

from __future__ import annotations

from numbers import Real
from typing import ClassVar

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, _fit_context, clone
from sklearn.frozen import FrozenEstimator
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions
from sklearn.utils.validation import check_is_fitted

from .._labels import consecutive_labels
from .._schema import CLASSIFIER_LAYOUT, CLUSTER_FEATURE_READS, ColumnsRead, instance_target
from .._validation import validated_input
from ..cluster import RadarDBSCAN
from ._classes import BACKGROUND, IGNORED
from ._features import _check_labels, segment_features, window_index
from ._history import HISTORY_OPTIONS, cluster_starts, cluster_weighted_mean, running_weighted_mean, with_history
from ._reading import columns_at, time_columns
from ._targets import segment_targets
from ._wrapped import check_class_target, class_proba, fit_classifier, instance_column_of, macro_f1_score

#: The column that says which detections the filter kept (read for the true segments).
KEEP_READS = ColumnsRead(required=(), optional=("keep",), layout=CLASSIFIER_LAYOUT)


class ClusterClassifier(BaseEstimator):
    """Classify the clusters of a radar clusterer into road users: a class, an instance and a confidence per detection.

    The stage the paper clusters for (Scheiner et al. 2019, Sec. I: "object
    instances in the radar data have to be identified and classified"; the
    classification chain of Scheiner et al. 2018).  ``clusterer`` (for
    example a :class:`~sklearn_radar.RadarDBSCAN` or a
    :class:`~sklearn_radar.ClusterMerger`) clusters the detections; each
    cluster is cut into *segments*, one per time window of ``window``
    seconds (or one per cluster and sequence), and every segment is
    described by the features of
    :func:`~sklearn_radar.classification.cluster_features` and classified
    by ``classifier``.  Segments classified as background become noise.
    Like :class:`~sklearn_radar.ClusterMerger` with its ``stage1``, it wraps
    the clusterer, so that it is the last step of a pipeline of
    :class:`~sklearn_radar.FrameTransform` and
    :class:`~sklearn_radar.DopplerDensityFilter`, and a search reaches every
    stage's parameters (in a ``make_pipeline``:
    ``clusterclassifier__clusterer__eps_xyv``,
    ``clusterclassifier__classifier__max_iter``, ...).

    **Training target** (:meth:`fit`).  ``y`` is the road-user class of each
    detection (:func:`~sklearn_radar.classification.road_user_class` of
    ``label_id``); the ground-truth instances are the ``instance_column`` of
    X (RadarScenes ``track_id``, per ``sequence``, as
    :func:`~sklearn_radar.instance_target` numbers them).  A segment's
    target is the class of the instance whose detections in the same window
    have an intersection over union > 0.5 with the segment's detections
    (at most one can), and background (-1) when no instance does.  Segments
    matched to an ignored instance (-2: RadarScenes ANIMAL and OTHER) are
    left out of training.  A cluster that is one part of a long track is
    therefore a positive example wherever it covers the object in a window,
    and the clusters of static structure (most clusters of V-measure-tuned
    settings: the paper's V-measure does not count them) are the background
    examples.

    **Class codes.**  ``y``, :meth:`predict` and ``classes_`` use the codes
    of :func:`~sklearn_radar.classification.road_user_class`, which number
    the classes otherwise than the RadarScenes devkit's
    ``ClassificationLabel``;
    :func:`~sklearn_radar.classification.devkit_class_index` converts them
    (the table is :data:`~sklearn_radar.classification.DEVKIT_CLASS_INDEX`,
    the names :data:`~sklearn_radar.classification.DEVKIT_CLASS_NAMES`):

    ====  ================  ==============================
    code  class             devkit ``ClassificationLabel``
    ====  ================  ==============================
    0     car               CAR 0
    1     large vehicle     LARGE_VEHICLE 4
    2     two-wheeler       TWO_WHEELER 3
    3     pedestrian        PEDESTRIAN 1
    4     pedestrian group  PEDESTRIAN_GROUP 2
    -1    background        STATIC 5
    -2    ignored           none (ANIMAL, OTHER)
    ====  ================  ==============================

    Code -2 appears in ``y`` only: it is never predicted.

    **In a pipeline.**  A :class:`~sklearn.pipeline.Pipeline` passes on
    :meth:`predict`, :meth:`predict_proba` and :meth:`score` but not
    :meth:`predict_instances`:
    ``predict_instances(pipeline, X)``
    (:func:`~sklearn_radar.classification.predict_instances`) gives the
    road users of a pipeline that ends in this classifier.

    Parameters
    ----------
    clusterer : estimator with ``fit_predict``, FrozenEstimator or None, default=None
        The clusterer, fitted on the data it labels (cloned each time);
        None means ``RadarDBSCAN()``.  A clusterer fitted beforehand on
        other data (a :class:`~sklearn_radar.cluster.LinkClustering` fitted
        on labelled sequences) is given wrapped in a
        :class:`~sklearn.frozen.FrozenEstimator`: its ``predict`` labels the
        data, and it is never refitted.  Its labels must be integers, -1 for
        noise.
    classifier : classifier with ``fit`` and ``predict_proba``, default=None
        Classifies the segments' feature rows (cloned).  None means a
        :class:`~sklearn.ensemble.HistGradientBoostingClassifier` with
        ``max_iter=30`` and ``random_state=0``, which takes the NaN of an
        unknown velocity as missing (why 30 boosting iterations:
        :ref:`User Guide <classification-cost>`).  A classifier that
        cannot take NaN needs an imputer in front
        (``make_pipeline(SimpleImputer(), ...)``).  With scikit-learn's
        metadata routing enabled, a classifier whose ``fit`` asks for
        ``groups`` (``CalibratedClassifierCV(cv=GroupKFold())``) gets each
        training segment's sequence as its group.
    window : float or None, default=0.5
        Length of the time windows a cluster is cut into, s, > 0; windows
        start at each sequence's first detection.  The default, 500 ms, is
        the window of the object-level scores
        (:func:`~sklearn_radar.metrics.instance_scores`, Scheiner et al.
        2021).  None: one segment per cluster and sequence, classified as a
        whole (and matched over the whole sequence).
    instance_column : str or None, default="track_id"
        Column of X holding each detection's ground-truth instance (strings
        or integers; ``""`` or -1 for none), read in :meth:`fit` only.  None:
        no instance ids; the detections of one class in one window of one
        sequence are one instance (panoptic segmentation's rule for "stuff"
        classes), which is what a plain array needs.
    history : {"mean_proba", "features", "cluster_mean_proba"} or None, default=None
        Classify a cluster that spans several windows from its past as well
        (a cluster id seen in several windows is one road user: the clusters
        of the object setting, the object ids of
        :class:`~sklearn_radar.online.OnlinePipeline` given to
        :meth:`predict_instances_of`).  Causal but for
        ``"cluster_mean_proba"``: a segment reads only the segments of its
        cluster at or before its own window.  None: each
        window is classified alone.  ``"mean_proba"``: the class
        probabilities of a segment are the mean of its own and those of the
        cluster's earlier segments, each weighted by its number of
        detections (the classifier is trained on single windows).
        ``"features"``: the classifier sees, besides the window's features,
        ``history_windows`` (windows seen, this one included),
        ``history_age`` (s since the cluster's first window), the running
        mean ``mean_<feature>`` of every feature over the windows seen, and
        the running maximum ``max_<feature>`` of ``n_detections``, the
        extents, ``vr_range``, ``rcs_max`` and ``speed`` (units those of the
        feature); it is trained on them.  ``"cluster_mean_proba"``: as
        ``"mean_proba"`` over all of the cluster's windows, later ones
        included, so that a cluster gets one class; not causal (a whole
        recording, offline).  Measured in the
        :ref:`User Guide <classification-history>`.
    true_segments : bool, default=False
        Learn, besides the clusterer's segments, from the segments of the
        ground truth: each instance's kept detections (``keep``) in each
        window, labelled with its class, as a clusterer without mistakes
        would give them.  Every class of the training data then has
        examples even where the clusterer misses it (as a clusterer fitted
        on other sequences does).  :meth:`fit` only; prediction is
        unchanged.  Measured in the
        :ref:`User Guide <classification-true-segments>`.

    Attributes
    ----------
    classes_ : ndarray of int64
        The class codes it predicts, sorted; always includes -1 (background).
        The codes of the table above, not the devkit's.
    classifier_ : classifier
        The fitted clone of ``classifier``, on the training segments.  When
        they hold a single class (or no segment exists), a
        :class:`~sklearn.dummy.DummyClassifier` that predicts it, with a
        warning.
    feature_names_ : ndarray of str
        The features of :func:`~sklearn_radar.classification.cluster_features`
        it uses: those whose columns X holds.
    n_training_examples_ : int
        The segments it was trained on (those not matched to an ignored
        instance), the true segments included.
    n_features_in_ : int
        Number of columns seen in :meth:`fit`.
    feature_names_in_ : ndarray of str
        Column names seen in :meth:`fit`, when X is a DataFrame.

    See Also
    --------
    PointClassifier : the same classifier on single detections, without clustering.
    cluster_features : the features of a segment.

    Notes
    -----
    Reads the columns of :class:`~sklearn_radar.ClusterMerger` (``x``, ``y``,
    ``v_r``, ``t``; ``sequence``, ``keep``, ``range_sc``, ``heading``,
    ``azimuth_sc``, ``sensor_yaw`` when present) plus ``rcs`` (dBsm) and
    ``sensor_id`` when present, and passes X unchanged to the clusterer.  A
    plain array is read by position ``[x, y, v_r, t, sequence, keep,
    range_sc, heading, azimuth_sc, sensor_yaw, rcs, sensor_id]``
    (:data:`~sklearn_radar._schema.CLASSIFIER_LAYOUT`); features whose
    columns are missing are left out, never made up.  Prediction clusters
    X afresh, so it depends on the whole of X (as a clusterer's labels do),
    and reads no ground truth.

    It is not a scikit-learn classifier in the sense of
    :func:`~sklearn.base.is_classifier`: its classes are fixed integer codes
    with a background (-1) that it also assigns to noise, and ``y`` alone
    does not determine the target (the instances do too).  :meth:`score` is
    the point-wise macro-F1, not a classifier's accuracy; scorers that call
    :meth:`predict` (``"accuracy"``, ``"f1_macro"``) work against the class
    codes, and :func:`~sklearn_radar.metrics.make_semantic_scorer` gives the
    instance scores of :meth:`predict_instances`.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
    >>> from sklearn_radar.classification import ClusterClassifier, road_user_class
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=2, duration=6.0, random_state=0)
    >>> y = road_user_class(scenes.data["label_id"])
    >>> model = make_pipeline(
    ...     FrameTransform(), DopplerDensityFilter(), ClusterClassifier(RadarDBSCAN(metric="xyv", vr_min=-np.inf))
    ... )
    >>> predicted = model.fit(scenes.data, y).predict(scenes.data)
    >>> predicted.shape == y.shape
    True
    """

    #: The defaults of a classifier pickled before ``history`` (``true_segments``) existed: its file then loads and
    #: classifies as saved.
    history = None
    true_segments = False

    _parameter_constraints: ClassVar[dict] = {
        "clusterer": [HasMethods(["fit_predict"]), FrozenEstimator, None],
        "classifier": [HasMethods(["fit", "predict_proba"]), None],
        "window": [Interval(Real, 0, None, closed="neither"), None],
        "instance_column": [str, None],
        "history": [StrOptions(set(HISTORY_OPTIONS)), None],
        "true_segments": ["boolean"],
    }

    def __init__(
        self,
        clusterer=None,
        classifier=None,
        *,
        window=0.5,
        instance_column="track_id",
        history=None,
        true_segments=False,
    ):
        self.clusterer = clusterer
        self.classifier = classifier
        self.window = window
        self.instance_column = instance_column
        self.history = history
        self.true_segments = true_segments

    @_fit_context(prefer_skip_nested_validation=False)
    def fit(self, X, y):
        """Cluster X, match the segments to the ground truth and fit the classifier on their features.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections (the output of :class:`~sklearn_radar.FrameTransform`,
            optionally filtered by :class:`~sklearn_radar.DopplerDensityFilter`)
            with ``instance_column``, or an array in the order of
            :data:`~sklearn_radar._schema.CLASSIFIER_LAYOUT` (with
            ``instance_column=None``).
        y : array-like of int, shape (n_detections,)
            Road-user class of each detection: -1 background, -2 ignored,
            >= 0 a road-user class (:func:`~sklearn_radar.classification.road_user_class`).

        Returns
        -------
        self : ClusterClassifier
        """
        X, time, table, rows = self._read_segments(X, reset=True)
        classes = check_class_target(y, len(rows), type(self).__name__)
        instances = self._instances(X, time["sequence"], classes)
        windows = window_index(time["t"], time["sequence"], self.window)
        targets = segment_targets(classes, instances, time["sequence"], windows, rows, len(table))
        if self.true_segments:
            table, targets = self._with_true_segments(X, table, targets, classes, instances, time, windows)
        learn = targets != IGNORED
        self.feature_names_ = np.asarray(table.columns[3:], dtype=object)
        self.classifier_ = fit_classifier(
            self.classifier,
            table.to_numpy(dtype=np.float64)[learn, 3:],
            targets[learn],
            self.feature_names_,
            self,
            groups=table["sequence"].to_numpy()[learn],
        )
        self.classes_ = np.union1d([BACKGROUND], np.asarray(self.classifier_.classes_, dtype=np.int64))
        self.n_training_examples_ = int(learn.sum())
        return self

    def _with_true_segments(self, X, table, targets, classes, instances, time, windows):
        """The training segments and targets with the ground truth's segments (kept detections) appended."""
        keep = columns_at(self, X, KEEP_READS, None)["keep"]
        truth = instances if keep is None else np.where(keep != 0, instances, -1)
        _, true_table, true_rows = self._describe(X, truth, time)
        true_targets = segment_targets(classes, truth, time["sequence"], windows, true_rows, len(true_table))
        return pd.concat([table, true_table], ignore_index=True), np.concatenate([targets, true_targets])

    def predict(self, X):
        """Road-user class of each detection; -1 for noise and for clusters classified as background.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit` (no ground truth is read).

        Returns
        -------
        classes : ndarray of int64, shape (n_detections,)
        """
        return self.predict_instances(X)["class"].to_numpy()

    def predict_proba(self, X):
        """Probability of each class of ``classes_`` for each detection: its segment's.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit`.

        Returns
        -------
        proba : ndarray of float64, shape (n_detections, n_classes)
            Rows of noise detections are 1 for background (-1), 0 elsewhere.
        """
        _, rows, segment_proba = self._segments(X)
        proba = np.zeros((len(rows), len(self.classes_)))
        proba[:, np.searchsorted(self.classes_, BACKGROUND)] = 1.0
        clustered = rows >= 0
        proba[clustered] = segment_proba[rows[clustered]]
        return proba

    def score(self, X, y):
        """Point-wise macro-F1 of :meth:`predict` on X against the class codes ``y``.

        :func:`~sklearn_radar.metrics.pointwise_macro_f1` (background
        included): the F1 over detections of each class present in ``y`` or
        in the prediction, averaged, the detections whose true class is
        ignored (-2) left out.  A search or ``cross_validate`` without
        ``scoring``, and ``Pipeline.score``, use it.  Details in the
        :ref:`user guide <user-guide-classification>`.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`predict`.
        y : array-like of int, shape (n_detections,)
            True road-user class of each detection, as for :meth:`fit`.

        Returns
        -------
        score : float
            Macro-F1, dimensionless, in [0, 1]; 1 when every detection gets
            its class.
        """
        return macro_f1_score(self, X, y)

    def predict_instances(self, X):
        """The road users in X: a class, an instance id and a confidence per detection.

        Clusters X with a fresh clone of ``clusterer``, then classifies its
        clusters as :meth:`predict_instances_of` does.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit`.

        Returns
        -------
        instances : DataFrame of shape (n_detections, 3)
            ``class``, ``instance`` and ``confidence`` per detection, as
            :meth:`predict_instances_of` returns them.
        """
        check_is_fitted(self)
        X = validated_input(self, X, CLUSTER_FEATURE_READS, reset=False)
        return self._instances_of(X, self._cluster(X, X.shape[0]))

    def predict_instances_of(self, X, labels):
        """Classify clusters computed elsewhere: a class, an instance id and a confidence per detection.

        The same classification as :meth:`predict_instances`, on the given
        ``labels`` instead of those of ``clusterer`` (which is not run): for
        example the persistent object ids of
        :class:`~sklearn_radar.online.OnlinePipeline` or the clusters of a
        setting saved by ``sklearn-radar reproduce``.  The classifier was
        trained on the clusters of its own ``clusterer``; on those of
        another clustering it is applied to clusters that can look unlike
        its training examples.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections, as for :meth:`fit`.
        labels : array-like of int, shape (n_detections,)
            Cluster of each detection, -1 for noise; any integers (they are
            renumbered), a cluster id may span sequences (its detections in
            each sequence are then separate segments).

        Returns
        -------
        instances : DataFrame of shape (n_detections, 3)
            Row for row with X (with X's index when X is a DataFrame):

            * ``class`` (int64): the predicted class of the detection's
              segment, -1 for noise and background;
            * ``instance`` (int64): the road user, -1 where the class is -1:
              the detection's cluster, numbered 0, 1, ... in order of first
              row, unique across sequences (one cluster is one instance in
              every window it is not background, whatever class each window
              is given);
            * ``confidence`` (float64): the probability the classifier gives
              the predicted class for the segment, in [0, 1] (1 for noise),
              the ranking score of mAP.

        Raises
        ------
        ValueError
            If ``labels`` is not one integer per row of X.
        """
        check_is_fitted(self)
        X = validated_input(self, X, CLUSTER_FEATURE_READS, reset=False)
        labels = _check_labels(labels, X.shape[0], "ClusterClassifier.predict_instances_of: the")
        return self._instances_of(X, labels)

    def _instances_of(self, X, labels):
        """``predict_instances_of`` of a validated X and checked labels: the one classification code path."""
        table, rows, segment_proba = self._segments_of(X, labels)
        best = np.argmax(segment_proba, axis=1)
        clustered = rows >= 0
        classes = np.full(len(rows), BACKGROUND, dtype=np.int64)
        classes[clustered] = self.classes_[best][rows[clustered]]
        confidence = np.ones(len(rows))
        confidence[clustered] = segment_proba[np.arange(len(best)), best][rows[clustered]]
        # The table is sorted by (sequence, cluster, window): a cluster's segments are consecutive rows.
        sequence, cluster = table["sequence"].to_numpy(), table["cluster"].to_numpy()
        new_cluster = np.ones(len(table), dtype=bool)
        new_cluster[1:] = (sequence[1:] != sequence[:-1]) | (cluster[1:] != cluster[:-1])
        cluster_of_segment = np.cumsum(new_cluster) - 1
        keys = np.full(len(rows), -1, dtype=np.int64)
        found = classes != BACKGROUND
        keys[found] = cluster_of_segment[rows[found]]
        index = X.index if isinstance(X, pd.DataFrame) else None
        return pd.DataFrame(
            {"class": classes, "instance": consecutive_labels(keys), "confidence": confidence}, index=index
        )

    def _segments(self, X):
        """The segment table of X, the table row of each detection (-1: noise) and each segment's probabilities."""
        check_is_fitted(self)
        X = validated_input(self, X, CLUSTER_FEATURE_READS, reset=False)
        return self._segments_of(X, self._cluster(X, X.shape[0]))

    def _segments_of(self, X, labels):
        """``_segments`` of a validated X with the given cluster labels."""
        _, table, rows = self._describe(X, labels)
        missing = sorted(set(self.feature_names_) - set(table.columns))
        if missing:
            raise ValueError(f"ClusterClassifier: X lacks the columns of the feature(s) {missing} it was fitted with")
        features = table[list(self.feature_names_)].to_numpy(dtype=np.float64)
        proba = class_proba(self.classifier_, features, self.feature_names_, self.classes_)
        weights = table["n_detections"].to_numpy(dtype=np.float64)
        if self.history == "mean_proba":  # the windows seen so far, each weighted by its detections
            proba = running_weighted_mean(proba, weights, cluster_starts(table))
        elif self.history == "cluster_mean_proba":  # all the cluster's windows, later ones too
            proba = cluster_weighted_mean(proba, weights, cluster_starts(table))
        return table, rows, proba

    def _read_segments(self, X, *, reset):
        """Validate, cluster and describe X: ``(X, time columns, feature table, table row of each detection)``."""
        X = validated_input(self, X, CLUSTER_FEATURE_READS, reset=reset)
        time, table, rows = self._describe(X, self._cluster(X, X.shape[0]))
        return X, time, table, rows

    def _describe(self, X, labels, time=None):
        """The segments of a validated X with cluster ``labels``: ``(time columns, feature table, table rows)``.

        Only ``t`` and ``sequence`` are read for every row (the windows start at
        each sequence's first detection; ``time``: those columns, already
        read); the other columns only for the clustered detections
        (:mod:`._reading`).
        """
        n = X.shape[0]
        if time is None:
            time = time_columns(self, X, CLUSTER_FEATURE_READS)
        clustered = np.flatnonzero(labels >= 0)
        c = columns_at(self, X, CLUSTER_FEATURE_READS, clustered, skip=("t", "sequence"))
        c["t"] = time["t"][clustered]
        c["sequence"] = None if time["sequence"] is None else time["sequence"][clustered]
        windows = window_index(time["t"], time["sequence"], self.window, clustered)
        table, local_rows = segment_features(c, labels[clustered], windows)
        if self.history == "features":
            table = with_history(table, self.window)
        rows = np.full(n, -1, dtype=np.int64)
        rows[clustered] = local_rows
        return time, table, rows

    def _cluster(self, X, n):
        """The clusterer's labels of X (a fresh clone, or a frozen fitted one's ``predict``), checked."""
        if isinstance(self.clusterer, FrozenEstimator):
            names = getattr(self.clusterer, "feature_names_in_", None)
            if names is not None and isinstance(X, pd.DataFrame):  # it was fitted without the ground truth's column
                X = X[[name for name in names if name in X.columns]]
            return _check_labels(self.clusterer.predict(X), n, "ClusterClassifier: the frozen clusterer's")
        clusterer = RadarDBSCAN() if self.clusterer is None else clone(self.clusterer)
        return _check_labels(clusterer.fit_predict(X), n, "ClusterClassifier: the clusterer's")

    def _instances(self, X, sequence, classes):
        """Ground-truth instance of each detection (-1 none): the instance column, or the class segments."""
        if self.instance_column is None:
            return np.where(classes != BACKGROUND, classes, -1).astype(np.int64)
        column = instance_column_of(X, self.instance_column, type(self).__name__)
        if column.dtype.kind in "OUST":
            return instance_target(column, sequence)
        return column.astype(np.int64)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        return tags
