"""LinkClustering: grouping learned from labelled sequences (objectness, pair links, mean-link agglomeration)."""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar, NamedTuple

import numpy as np
from sklearn.base import BaseEstimator, ClusterMixin, _fit_context
from sklearn.utils import check_array, check_random_state, column_or_1d
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted

from .._executor import _effective_n_jobs, thread_bound
from .._labels import consecutive_labels, drop_small_clusters, roots_to_rows
from .._schema import CLASSIFIER_LAYOUT, CLUSTER_FEATURE_READS, ArrayLayout, ColumnsRead
from .._validation import read_columns, sequence_slices
from ._agglomeration import mean_link_merges, roots_at
from ._causal_agglomeration import confirmed_roots, sequence_merges
from ._causal_link_features import causal_detection_features, causal_pair_features, causal_pairs
from ._cluster_context import CONTEXT_FEATURES, context_merges, links_by_fold
from ._link_features import (
    DETECTION_FEATURES,
    PAIR_FEATURES,
    Detections,
    LocalMotion,
    detection_features,
    pair_features,
    pairs_within,
    usable,
)
from ._link_training import (
    cross_fit,
    fold_classifiers,
    fold_of_groups,
    positive_proba,
    tune,
    tune_causal,
    tune_context,
)

#: Working detections as LinkClustering reads them from an array: the classifiers' layout, then the ego speed
#: ``ego_vx`` (m/s; a measurement without a neutral value: absent, its feature is left out).
LINK_LAYOUT = ArrayLayout(
    name="link detection array",
    columns=(*CLASSIFIER_LAYOUT.columns, "ego_vx"),
    neutral=dict(CLASSIFIER_LAYOUT.neutral),
)
#: The columns LinkClustering reads.
LINK_READS = ColumnsRead(
    required=CLUSTER_FEATURE_READS.required,
    optional=(*CLUSTER_FEATURE_READS.optional, "ego_vx"),
    layout=LINK_LAYOUT,
)

#: The settings the automatic tuning tries (each fixed parameter replaces its grid by its value).
OBJECTNESS_GRID = (0.01, 0.02, 0.05, 0.15, 0.3, 0.5)
LINK_GRID = tuple(np.round(np.arange(0.1, 0.951, 0.05), 2).tolist())
MIN_SIZE_GRID = (1, 3, 6, 10, 15, 20, 25, 30, 40)
#: The parameters that only a causal model takes (None otherwise), and why.
_CAUSAL_ONLY = {
    "max_links_per_detection": "it chooses among a detection's earlier candidates",
    "max_extent": "it limits the causal agglomeration's merges",
    "cluster_window": "it describes the clusters the causal agglomeration has formed so far",
}
#: P(road user) above which a training detection takes part in the link classifier's pairs.
CANDIDATE_OBJECTNESS = 0.05


#: The order of the detections within a sequence (time first), so that nothing depends on the row order.
_SORT_KEY = ("t", "x", "y", "v", "los", "rcs", "range", "sensor", "ego")


class _Sequence(NamedTuple):
    """The kept detections of one sequence in their row-order-free order, with their features."""

    rows: np.ndarray  # global row numbers, sorted by _SORT_KEY
    detections: Detections
    features: np.ndarray  # DETECTION_FEATURES (all columns)
    local: LocalMotion


class LinkClustering(ClusterMixin, BaseEstimator):
    """Group detections into road users with links learned from labelled sequences.

    A supervised replacement for the hand-set thresholds of
    :class:`RadarDBSCAN` and :class:`ClusterMerger`, fitted on sequences with
    ground-truth instances and applied to sequences it never saw
    (:meth:`predict`).  Three steps, per sequence:

    1. **Objectness.**  A classifier gives each kept detection P(road user)
       from its Doppler, RCS, range and neighbourhood: the counts of
       neighbours, their Doppler spread, and a local rigid velocity fitted
       to the moving neighbours' Doppler and lines of sight (the model of
       Eq. 6) with its residual.  Detections at or below
       ``objectness_threshold`` are noise.
    2. **Links.**  Every pair of the remaining detections within
       ``pair_radius`` in x-y and ``pair_window`` in time is a candidate; a
       second classifier gives P(same road user) from symmetric pair
       features (offsets, Doppler difference, how well one rigid velocity
       explains both Doppler values, RCS, range, both sides' neighbourhoods
       and objectness).
    3. **Agglomeration.**  Starting from single detections, the two
       clusters with the largest mean P(link) over the candidate pairs
       between them merge while that mean exceeds ``link_threshold``;
       pairs that are not candidates carry no evidence, so a long track is
       not split by its time span and one strong link does not chain two
       road users.  Clusters smaller than ``min_cluster_size`` detections
       are noise.

    The classifiers are :class:`~sklearn.ensemble.HistGradientBoostingClassifier`
    fitted in :meth:`fit` on the training detections and their candidate
    pairs (a pair is positive when both detections belong to the same
    instance of ``y``).  The three thresholds, when ``"auto"``, are chosen
    for panoptic quality (:func:`~sklearn_radar.metrics.panoptic_quality`,
    windows of ``window`` s) on out-of-fold predictions of the training
    sequences: ``GroupKFold`` over the sequences, each fold's classifiers
    fitted on the others, so that the tuning sees the kind of
    probabilities that new sequences get.  With one sequence, its time is
    cut into ``cv`` equal spans that serve as the groups.

    Labels never join detections of different sequences, do not depend on
    the row order (rows equal in every column read are interchangeable),
    and rows with ``keep = False`` (see :class:`DopplerDensityFilter`) are
    noise and take no part.

    Read more in the :ref:`User Guide <user-guide-learned>`.

    Parameters
    ----------
    link_threshold : "auto" or float in [0, 1], default="auto"
        Clusters merge while their mean link probability exceeds it.
    objectness_threshold : "auto" or float in [0, 1], default="auto"
        Detections with P(road user) at or below it are noise.
    min_cluster_size : "auto" or int >= 1, default="auto"
        Smallest cluster kept, in detections; smaller ones are noise.
    pair_radius : float, default=3.0
        Candidate pairs lie within this distance in x-y, m.
    pair_window : float, default=0.25
        Candidate pairs lie within this time of each other, s.
    max_iter : int, default=150
        Boosting iterations of each classifier.
    max_leaf_nodes : int >= 2, default=31
        Most leaves of each tree of both classifiers; smaller trees walk
        faster scan by scan (see :ref:`online-learned`).
    max_depth : int >= 1 or None, default=None
        Most splits from the root of each tree of both classifiers to a leaf
        (None: as many as ``max_leaf_nodes`` allows); a scan's rows walk a
        tree as many levels as its deepest leaf (see :ref:`online-learned`).
    max_pairs : int, default=400_000
        Training pairs per fit of the link classifier; more are subsampled at random.
    cv : int, default=5
        Most folds of the tuning's ``GroupKFold`` (at most one per sequence, or per time span).
    window : float, default=0.5
        Length of the time windows of the panoptic quality that the tuning
        maximises, s.
    n_jobs : int, default=None
        Threads of the classifiers (OpenMP); None means 1, -1 all cores.
    random_state : int, RandomState instance or None, default=0
        Seeds the classifiers and the pair subsampling.  An int (the
        default) makes :meth:`fit` reproducible.
    causal : bool, default=False
        Decide from the past only, as a stream must
        (:class:`~sklearn_radar.online.OnlinePipeline` runs a fitted causal
        model scan by scan and gives the same clusters).  A detection's
        neighbourhood is then the detections at its time or before; the
        candidate pairs are the same; the agglomeration runs time by time:
        at each time the new detections above the objectness threshold
        enter as single clusters, the link probabilities of their pairs add
        to the evidence between the clusters they join, and mean-link
        merges run until no mean exceeds ``link_threshold`` (older clusters
        may merge; a merged cluster keeps the id of its older side).
        ``min_cluster_size`` is a confirmation: a detection is labelled
        when its cluster has at least that many detections at its time
        (after that time's merges), and is noise otherwise; its label is
        the cluster it ends in.  :meth:`fit` trains the classifiers on the
        causal features and tunes the thresholds with the causal
        agglomeration.
    max_links_per_detection : int >= 1 or None, default=None
        With ``causal=True``, the most candidate pairs that a detection
        forms with earlier ones: its nearest, in x-y distance over
        ``pair_radius`` and time difference over ``pair_window`` (in fit,
        :meth:`predict` and a stream alike).  Bounds the work per scan of
        :class:`~sklearn_radar.online.OnlinePipeline`.  None keeps every
        candidate; ``causal=False`` requires None.
    max_extent : float > 0 or None, default=None
        With ``causal=True``, the longest cluster a merge may make, m: a
        merge is refused when the diagonal of the x-y bounding box of the
        two clusters' detections of the last ``pair_window`` s would exceed
        it (in fit, :meth:`predict` and a stream alike).  None: no limit;
        ``causal=False`` requires None.  Why, and measured: the
        :ref:`User Guide <online-learned-extent>`.
    cluster_window : float > 0 or None, default=None
        With ``causal=True``, the link classifier also sees the cluster
        that a pair's earlier detection already belongs to, described by
        its detections of the last ``cluster_window`` s
        (:data:`~sklearn_radar.cluster._cluster_context.CONTEXT_FEATURES`:
        its size and extent, and how well its rigid velocity of Eq. 6
        predicts the later detection's Doppler and position).  The links of
        each time are then decided after the merges of the times before (in
        fit, :meth:`predict` and a stream alike); :meth:`fit` learns them
        from the clusters that the links without context form on the
        training data, and tunes ``link_threshold`` and
        ``min_cluster_size`` again with them.  None: the pair features
        alone; ``causal=False`` requires None.  Measured: the
        :ref:`User Guide <learned-cluster-context>`.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Cluster per row of the training data, -1 for noise: what :meth:`predict` gives for it.  Ids are
        consecutive, numbered in order of each cluster's first row, unique across sequences.
    link_threshold_ : float
        The link threshold used (tuned or given).
    objectness_threshold_ : float
        The objectness threshold used (tuned or given).
    min_cluster_size_ : int
        The minimum cluster size used (tuned or given).
    cv_score_ : float
        Panoptic quality of the chosen thresholds on the out-of-fold predictions of the training data; NaN when
        nothing was tuned.
    objectness_classifier_ : HistGradientBoostingClassifier or float
        The fitted objectness classifier (a constant probability when the training detections hold one class).
    link_classifier_ : HistGradientBoostingClassifier or float
        The fitted link classifier (a constant probability when the training pairs hold one class or none).
    detection_feature_names_ : ndarray of str
        The per-detection features used (those whose columns X holds).
    pair_feature_names_ : ndarray of str
        The pair features used.
    context_feature_names_ : ndarray of str
        The cluster-context features the link classifier sees after the pair features (empty without
        ``cluster_window``).
    n_training_pairs_ : int
        Candidate pairs of the training data (before subsampling).
    n_features_in_ : int
        Number of columns seen in :meth:`fit`.
    feature_names_in_ : ndarray of str
        Column names seen in :meth:`fit`, when X is a DataFrame.

    See Also
    --------
    ClusterMerger : the framework's hand-set two-stage clustering.

    Notes
    -----
    Reads the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and, when
    present, ``sequence``, ``keep``, ``range_sc`` (m), ``heading``,
    ``azimuth_sc``, ``sensor_yaw`` (rad), ``rcs`` (dBsm), ``sensor_id`` and
    ``ego_vx`` (m/s);
    the features that need an absent measurement are left out (without
    ``azimuth_sc`` and ``sensor_yaw`` there is no line of sight, hence no
    rigid-velocity feature).  A plain array is read by position in the
    order of :data:`~sklearn_radar._schema.CLASSIFIER_LAYOUT` followed by
    ``ego_vx``.

    Examples
    --------
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn_radar import DopplerDensityFilter, FrameTransform, instance_target
    >>> from sklearn_radar.cluster import LinkClustering
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=2, duration=3.0, random_state=0)
    >>> y = instance_target(scenes.data["track_id"], scenes.data["sequence"])
    >>> model = make_pipeline(FrameTransform(), DopplerDensityFilter(), LinkClustering(max_iter=20))
    >>> labels = model.fit(scenes.data, y).predict(scenes.data)
    >>> labels.shape == y.shape
    True
    """

    _parameter_constraints: ClassVar[dict] = {
        "link_threshold": [StrOptions({"auto"}), Interval(Real, 0, 1, closed="both")],
        "objectness_threshold": [StrOptions({"auto"}), Interval(Real, 0, 1, closed="both")],
        "min_cluster_size": [StrOptions({"auto"}), Interval(Integral, 1, None, closed="left")],
        "pair_radius": [Interval(Real, 0, None, closed="neither")],
        "pair_window": [Interval(Real, 0, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "max_leaf_nodes": [Interval(Integral, 2, None, closed="left")],
        "max_depth": [None, Interval(Integral, 1, None, closed="left")],
        "max_pairs": [Interval(Integral, 1, None, closed="left")],
        "cv": [Interval(Integral, 2, None, closed="left")],
        "window": [Interval(Real, 0, None, closed="neither")],
        "n_jobs": [None, Integral],
        "random_state": ["random_state"],
        "causal": ["boolean"],
        "max_links_per_detection": [None, Interval(Integral, 1, None, closed="left")],
        "max_extent": [None, Interval(Real, 0, None, closed="neither")],
        "cluster_window": [None, Interval(Real, 0, None, closed="neither")],
    }

    def __init__(
        self,
        *,
        link_threshold="auto",
        objectness_threshold="auto",
        min_cluster_size="auto",
        pair_radius=3.0,
        pair_window=0.25,
        max_iter=150,
        max_leaf_nodes=31,
        max_depth=None,
        max_pairs=400_000,
        cv=5,
        window=0.5,
        n_jobs=None,
        random_state=0,
        causal=False,
        max_links_per_detection=None,
        max_extent=None,
        cluster_window=None,
    ):
        self.link_threshold = link_threshold
        self.objectness_threshold = objectness_threshold
        self.min_cluster_size = min_cluster_size
        self.pair_radius = pair_radius
        self.pair_window = pair_window
        self.max_iter = max_iter
        self.max_leaf_nodes = max_leaf_nodes
        self.max_depth = max_depth
        self.max_pairs = max_pairs
        self.cv = cv
        self.window = window
        self.n_jobs = n_jobs
        self.random_state = random_state
        self.causal = causal
        self.max_links_per_detection = max_links_per_detection
        self.max_extent = max_extent
        self.cluster_window = cluster_window

    def __setstate__(self, state):
        # A model pickled before max_links_per_detection existed formed every candidate pair; one pickled before
        # max_leaf_nodes (max_depth) existed had trees of 31 leaves (of any depth); one pickled before max_extent
        # existed merged clusters of any length; one pickled before cluster_window existed saw no cluster context.
        state.setdefault("max_links_per_detection", None)
        state.setdefault("max_extent", None)
        state.setdefault("cluster_window", None)
        if "link_classifier_" in state:
            state.setdefault("context_feature_names_", np.zeros(0, dtype=object))
        state.setdefault("max_leaf_nodes", 31)
        state.setdefault("max_depth", None)
        super().__setstate__(state)

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Fit the objectness and link classifiers, tune the thresholds, and label the training data.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections (the output of :class:`FrameTransform`, optionally filtered by
            :class:`DopplerDensityFilter`), or an array in the order of
            :data:`~sklearn_radar._schema.CLASSIFIER_LAYOUT` followed by ``ego_vx``.
        y : array-like of int, shape (n_detections,)
            Ground-truth instance of each detection, -1 for background
            (e.g. :func:`~sklearn_radar.instance_target` of the track ids, or
            :func:`~sklearn_radar.metrics.precluster_target` of it, the target
            the framework is scored against).  Equal ids in different
            sequences are different instances.  Required: None raises a
            ValueError.

        Returns
        -------
        self : LinkClustering
        """
        for name, why in _CAUSAL_ONLY.items():
            if getattr(self, name) is not None and not self.causal:
                raise ValueError(
                    f"LinkClustering: {name} requires causal=True ({why}); leave it None with causal=False"
                )
        X, c = read_columns(self, X, LINK_READS, reset=True)
        y = _check_instances(y, len(c["x"]))
        sequences = _sequences(c, self.causal)
        kept = np.concatenate([s.rows for s in sequences])
        if not np.any(y[kept] >= 0):
            raise ValueError(
                "LinkClustering: y holds no instance (>= 0) among the kept detections: nothing to learn from; "
                "y must give the ground-truth instance of each detection, -1 for background"
            )
        present = _present(c)
        self.detection_feature_names_ = np.asarray(list(DETECTION_FEATURES), dtype=object)[
            usable(DETECTION_FEATURES, present)
        ]
        self.pair_feature_names_ = np.asarray(list(PAIR_FEATURES), dtype=object)[usable(PAIR_FEATURES, present)]
        self.context_feature_names_ = np.asarray(list(CONTEXT_FEATURES), dtype=object)[
            usable(CONTEXT_FEATURES, present) & (self.cluster_window is not None)
        ]
        rng = check_random_state(self.random_state)
        with thread_bound(_effective_n_jobs(self.n_jobs)):
            self._fit(sequences, c, y, rng)
            self.labels_ = self._labels(sequences, len(c["x"]))
        return self

    def predict(self, X):
        """Cluster new detections with the fitted classifiers and thresholds.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections with the columns seen in :meth:`fit`.

        Returns
        -------
        labels : ndarray of int64, shape (n_detections,)
            Cluster per row, -1 for noise; consecutive ids in order of each cluster's first row.
        """
        check_is_fitted(self, "link_classifier_")
        X, c = read_columns(self, X, LINK_READS, reset=False)
        sequences = _sequences(c, self.causal)
        with thread_bound(_effective_n_jobs(self.n_jobs)):
            return self._labels(sequences, len(c["x"]))

    def fit_predict(self, X, y=None, **kwargs):
        """Fit on X and y, and return the labels of X (:attr:`labels_`).

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            As for :meth:`fit`.
        y : array-like of int, shape (n_detections,)
            As for :meth:`fit`.
        **kwargs : dict
            Ignored; for the signature of :class:`~sklearn.base.ClusterMixin`.

        Returns
        -------
        labels : ndarray of int64, shape (n_detections,)
        """
        return self.fit(X, y).labels_

    # ------------------------------------------------------------------ fitting

    def _fit(self, sequences, c, y, rng):
        """Both classifiers and the thresholds, from the training sequences."""
        detection_columns = np.flatnonzero(np.isin(list(DETECTION_FEATURES), self.detection_feature_names_))
        pair_columns = self._pair_columns()
        groups = _groups(sequences, c, self.cv)
        n_groups = len(np.unique(np.concatenate(groups)))
        grids = self._grids()
        tuning = any(len(grid) > 1 for grid in grids)
        if tuning and n_groups < 2:
            tuned = [
                name
                for name in ("link_threshold", "objectness_threshold", "min_cluster_size")
                if getattr(self, name) == "auto"
            ]
            raise ValueError(
                f"LinkClustering: {' and '.join(tuned)}='auto' is tuned on out-of-fold predictions, which need at "
                "least two sequences (or one whose kept detections span more than one time instant); give "
                f"{'it a number' if len(tuned) == 1 else 'them numbers'} to fit on this data"
            )
        folds = fold_of_groups(groups, self.cv) if n_groups >= 2 else [np.zeros(len(g), np.int64) for g in groups]
        seeds = rng.randint(np.iinfo(np.int32).max, size=2)
        tree = {"max_leaf_nodes": self.max_leaf_nodes, "max_depth": self.max_depth}  # both classifiers' trees
        # Objectness: out-of-fold probabilities of the training detections (what the pairs and the tuning see).
        features = [s.features[:, detection_columns] for s in sequences]
        targets = [y[s.rows] >= 0 for s in sequences]
        self.objectness_classifier_, objectness = cross_fit(
            features,
            targets,
            folds,
            self.max_iter,
            seeds[0],
            None,
            rng,
            out_of_fold=n_groups >= 2,
            tree=tree,
        )
        floor = min(CANDIDATE_OBJECTNESS, min(grids[1]))
        pair_x, pair_y, pairs = [], [], []
        for s, p, is_object in zip(sequences, objectness, targets, strict=True):
            i, j = self._pairs(s, p > floor)  # a positive pair: both detections of one instance
            truth = y[s.rows]
            pairs.append((i, j))
            pair_x.append(self._pair_features(s, p, i, j)[:, pair_columns])
            pair_y.append((truth[i] == truth[j]) & is_object[i])
        pair_folds = [fold[i] for fold, (i, _) in zip(folds, pairs, strict=True)]
        self.n_training_pairs_ = int(sum(len(i) for i, _ in pairs))
        self.link_classifier_, links = cross_fit(
            pair_x,
            pair_y,
            pair_folds,
            self.max_iter,
            seeds[1],
            self.max_pairs,
            rng,
            out_of_fold=tuning,
            tree=tree,
        )
        if tuning and self.causal:
            setting, score = tune_causal(
                sequences, objectness, pairs, links, grids, c, y, self.window, self.pair_window, self.max_extent
            )
        elif tuning:
            setting, score = tune(sequences, objectness, pairs, links, grids, c, y, self.window)
        else:
            setting, score = tuple(grid[0] for grid in grids), np.nan
        self.link_threshold_, self.objectness_threshold_ = float(setting[0]), float(setting[1])
        self.min_cluster_size_ = int(setting[2])
        self.cv_score_ = float(score)
        if self.cluster_window is not None:
            training = (sequences, objectness, pairs, pair_x, pair_y, links, pair_folds)
            self._fit_context(training, c, y, grids, tuning, seeds[1], tree, rng)

    def _fit_context(self, training, c, y, grids, tuning, seed, tree, rng):
        """The link classifier in cluster context, learned from the clusters that the links without context
        (out of fold when tuning) form at the tuned thresholds; then the link threshold and the confirmation count
        tuned again with it (out of fold)."""
        gate, columns = self.objectness_threshold_, self._context_columns()
        parts = []
        for s, p, (i, j), x, target, link, fold in zip(*training, strict=True):
            node = p > gate
            both = node[i] & node[j]
            i, j, x, link = i[both], j[both], x[both], link[both]
            context = self._merged(s, node, i, j, lambda rows, _, link=link: link[rows], self.link_threshold_)[2]
            parts.append((s, node, i, j, x, context[:, columns], target[both], fold[both]))
        features = [np.hstack([x, context]) for *_, x, context, _, _ in parts]
        targets, folds = [part[6] for part in parts], [part[7] for part in parts]
        if tuning:
            models = fold_classifiers(features, targets, folds, self.max_iter, seed, self.max_pairs, rng, tree)
        self.link_classifier_, _ = cross_fit(
            features, targets, folds, self.max_iter, seed, self.max_pairs, rng, out_of_fold=False, tree=tree
        )
        if not tuning:
            return

        def merged_at(threshold):
            found = []
            for s, node, i, j, x, _, _, fold in parts:
                roots, sizes, _, _ = self._merged(s, node, i, j, links_by_fold(models, x, fold, columns), threshold)
                found.append((s.rows, roots, sizes))
            return found

        link_grid, _, size_grid = grids
        setting, score = tune_context(merged_at, link_grid, size_grid, c, y, self.window)
        self.link_threshold_, self.min_cluster_size_ = float(setting[0]), int(setting[1])
        self.cv_score_ = float(score)

    def _grids(self):
        """(link, objectness, min size) values to try: the grid of each "auto" parameter, else its value."""
        return tuple(
            grid if value == "auto" else (value,)
            for value, grid in (
                (self.link_threshold, LINK_GRID),
                (self.objectness_threshold, OBJECTNESS_GRID),
                (self.min_cluster_size, MIN_SIZE_GRID),
            )
        )

    def _context_columns(self):
        """The columns of CONTEXT_FEATURES the link classifier sees (after the pair features)."""
        return np.flatnonzero(np.isin(list(CONTEXT_FEATURES), self.context_feature_names_))

    def _pair_features(self, s, objectness, i, j):
        """The pair features of the pairs (i, j) of sequence s (causal: the compiled loop a stream runs too)."""
        features = causal_pair_features if self.causal else pair_features
        return features(s.detections, s.local, objectness, i, j)

    def _pairs(self, s, subset):
        d = s.detections
        if self.causal:  # the same pairs, in the order the causal agglomeration takes them
            return causal_pairs(
                d.x, d.y, d.t, subset, 0, self.pair_radius, self.pair_window, self.max_links_per_detection
            )
        return pairs_within(d.x, d.y, d.t, self.pair_radius, self.pair_window, subset)

    # ------------------------------------------------------------------ labelling

    def _labels(self, sequences, n_rows):
        """Labels of every row from the fitted classifiers and thresholds."""
        roots = np.full(n_rows, -1, dtype=np.int64)
        for s in sequences:
            if self.cluster_window is not None:  # (causal: fit refuses it otherwise)
                objectness, i, j = self._candidates(s, self.objectness_threshold_)
                local = confirmed_roots(*self._context_merges(s, objectness, i, j)[:2], self.min_cluster_size_)
                roots_to_rows(s.rows, local, roots)
                continue
            objectness, i, j, links = self._probabilities(s, self.objectness_threshold_)
            node = objectness > self.objectness_threshold_
            if self.causal:
                d = s.detections
                final, sizes = sequence_merges(
                    d.t, node, i, j, links, self.pair_window, self.link_threshold_, d.x, d.y, self.max_extent
                )
                local = confirmed_roots(final, sizes, self.min_cluster_size_)
            else:
                local = sequence_roots(len(s.rows), i, j, links, node, self.link_threshold_, self.min_cluster_size_)
            roots_to_rows(s.rows, local, roots)
        return consecutive_labels(roots)

    def _probabilities(self, s, gate):
        """The fitted classifiers on sequence ``s``: objectness, the candidate pairs (i, j) of the detections above
        ``gate`` and their P(link).

        With ``cluster_window``, the links are those decided in context at the fitted objectness threshold (and
        ``gate`` must be it); the labels then come from :meth:`_context_merges`.
        """
        objectness, i, j = self._candidates(s, gate)
        if self.cluster_window is not None:
            return objectness, i, j, self._context_merges(s, objectness, i, j)[3]
        links = positive_proba(self.link_classifier_, self._pair_features(s, objectness, i, j)[:, self._pair_columns()])
        return objectness, i, j, links

    def _candidates(self, s, gate):
        """The fitted objectness of sequence ``s`` and the candidate pairs (i, j) of the detections above ``gate``."""
        detection_columns = np.flatnonzero(np.isin(list(DETECTION_FEATURES), self.detection_feature_names_))
        objectness = positive_proba(self.objectness_classifier_, s.features[:, detection_columns])
        return (objectness, *self._pairs(s, objectness > gate))

    def _pair_columns(self):
        """The columns of PAIR_FEATURES the link classifier sees."""
        return np.flatnonzero(np.isin(list(PAIR_FEATURES), self.pair_feature_names_))

    def _context_merges(self, s, objectness, i, j):
        """:func:`context_merges` of sequence ``s`` with the fitted classifier and thresholds: roots, sizes, context
        and links of the pairs (i, j) of the nodes."""
        x = self._pair_features(s, objectness, i, j)[:, self._pair_columns()]
        links_of = links_by_fold(
            {0: self.link_classifier_}, x, np.zeros(len(i), dtype=np.int64), self._context_columns()
        )
        return self._merged(s, objectness > self.objectness_threshold_, i, j, links_of, self.link_threshold_)

    def _merged(self, s, node, i, j, links_of, threshold):
        """:func:`context_merges` of sequence ``s`` at a link threshold, each time's links from ``links_of``."""
        return context_merges(
            s.detections, node, i, j, links_of, self.pair_window, threshold, self.cluster_window, self.max_extent
        )


def sequence_roots(n, i, j, links, node, link_threshold, min_cluster_size):
    """Cluster of each detection of one sequence (a detection number, -1 noise) from its candidate links.

    Parameters
    ----------
    n : int
        Detections of the sequence.
    i, j : ndarray of int64
        Candidate pairs, both ends in ``node``.
    links : ndarray of float64
        P(link) of each pair.
    node : ndarray of bool, shape (n,)
        The detections above the objectness threshold; the others are noise.
    link_threshold : float
        Merging stops when no mean link exceeds it.
    min_cluster_size : int
        Smaller clusters are noise.

    Returns
    -------
    roots : ndarray of int64, shape (n,)
    """
    child, survivor, link = mean_link_merges(n, i, j, links, link_threshold)
    roots = np.where(node, roots_at(n, child, survivor, link, link_threshold), -1)
    return drop_small_clusters(roots, min_cluster_size)


def _check_instances(y, n):
    """``y`` as int64 instance ids (-1 background), one per row; the errors name ``y``."""
    if y is None:
        raise ValueError(
            "LinkClustering.fit requires y: the ground-truth instance of each detection, -1 for background "
            "(e.g. sklearn_radar.instance_target of the track ids)"
        )
    y = column_or_1d(check_array(y, ensure_2d=False, dtype=None, input_name="y"), warn=True)
    if y.dtype.kind == "f" and np.all(y == np.round(y)):
        y = y.astype(np.int64)
    if y.dtype.kind not in "iu":
        raise ValueError(
            "LinkClustering: Unknown label type: y must hold integer instance ids (-1 background), got dtype "
            f"{y.dtype}; sklearn_radar.instance_target turns track ids into them"
        )
    if len(y) != n:
        raise ValueError(f"LinkClustering: y has {len(y)} values for {n} detections")
    if len(y) and y.min() < -1:
        raise ValueError(f"LinkClustering: y holds {y.min()}; instance ids are -1 (background) or >= 0")
    return y.astype(np.int64, copy=False)


def _present(c):
    """The measurements the columns give (names of :class:`Detections`' optional fields)."""
    present = set()
    if c["azimuth_sc"] is not None and c["sensor_yaw"] is not None:
        present.add("los")
    for field, column in (("rcs", "rcs"), ("range", "range_sc"), ("sensor", "sensor_id"), ("ego", "ego_vx")):
        if c[column] is not None:
            present.add(field)
    return present


def _sequences(c, causal=False):
    """The kept detections of each sequence, sorted by a key free of the row order, with their features.

    ``causal``: each detection's features from its past only, and the times as given (not from the sequence's
    first), so that a stream that starts anywhere computes the same numbers.
    """
    n = len(c["x"])
    keep = np.ones(n, dtype=bool) if c["keep"] is None else c["keep"] != 0
    nan = np.full(n, np.nan)
    los = nan
    if c["azimuth_sc"] is not None and c["sensor_yaw"] is not None:
        los = c["azimuth_sc"] + c["sensor_yaw"] + (0.0 if c["heading"] is None else c["heading"])
    columns = {
        "x": c["x"],
        "y": c["y"],
        "t": c["t"],
        "v": c["v_r"],
        "los": los,
        "rcs": nan if c["rcs"] is None else c["rcs"],
        "range": nan if c["range_sc"] is None else c["range_sc"],
        "sensor": nan if c["sensor_id"] is None else c["sensor_id"],
        "ego": nan if c["ego_vx"] is None else c["ego_vx"],
    }
    sequences = []
    for part in sequence_slices(c["sequence"]):
        rows = np.arange(n)[part]
        rows = rows[keep[rows]]
        rows = rows[np.lexsort([columns[name][rows] for name in reversed(_SORT_KEY)])]
        values = {name: columns[name][rows] for name in Detections._fields}
        if len(rows) and not causal:
            values["t"] = values["t"] - values["t"].min()
        detections = Detections(**values)
        features, local = (causal_detection_features if causal else detection_features)(detections)
        sequences.append(_Sequence(rows=rows, detections=detections, features=features, local=local))
    return sequences


def _groups(sequences, c, cv):
    """Cross-validation group of each kept detection, per sequence: its sequence, or with one, its time span."""
    if len(sequences) > 1:
        return [np.full(len(s.rows), k, dtype=np.int64) for k, s in enumerate(sequences)]
    (s,) = sequences
    t = s.detections.t - (s.detections.t.min() if len(s.rows) else 0.0)
    span = float(t.max()) if len(t) else 0.0
    if span <= 0:
        return [np.zeros(len(t), dtype=np.int64)]
    return [np.minimum((t / span * cv).astype(np.int64), cv - 1)]
