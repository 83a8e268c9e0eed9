"""Full 2-D velocity of a radar cluster from its detections' Doppler values.

A radar measures only the radial component of a target's velocity.  For a
rigid object translating with velocity ``(vx, vy)`` (no rotation), every
detection ``i`` on it has the ego-motion-compensated radial velocity

.. math::

    v_{r,i} = v_x \\cos\\theta_i + v_y \\sin\\theta_i,

where ``theta_i`` is the direction of the line of sight from the sensor that
saw detection ``i`` to the detection, all expressed in one common frame
(e.g. the car frame, or the sequence frame).  Two detections with different
line-of-sight directions -- at different azimuths of one sensor, or seen by
two sensors mounted apart -- determine ``(vx, vy)``; more detections give an
over-determined linear system.  This is the object velocity estimation used
in the cluster-merging stage of Scheiner et al., "A Multi-Stage Clustering
Framework for Automotive Radar Data" (ITSC 2019), which follows Kellner et
al., "Instantaneous Full-Motion Estimation of Arbitrary Objects using Dual
Doppler Radar" (IEEE IV 2013).

Detections that violate the rigid-body model -- micro-Doppler of
pedestrians' limbs or of wheels, multipath, clutter -- are rejected with
RANSAC over pairs of detections (each pair gives an exact 2x2 solution); the
inliers of the best hypothesis are then fitted by least squares, the inliers
re-selected once with the refined velocity, and fitted again.

Conditioning.  The component of the velocity along the mean line of sight
is measured directly; the lateral component is inferred from how ``v_r``
changes across the angular spread of the lines of sight, so its error grows
roughly like ``sigma_vr / (sqrt(n) * std(theta))``.  A distant object seen
by one sensor subtends only a few degrees, so the estimate is declared
unknown (NaN) when the angular spread of the inliers' lines of sight is
below ``min_spread``.

Sign convention: ``v_r`` is positive when the detection moves away from the
sensor along the line of sight and negative when it approaches (as
RadarScenes' ``vr_compensated``).  The returned velocity is in the frame
in which ``los_angle`` is given.
"""

from __future__ import annotations

import functools
from numbers import Integral, Real

import numpy as np
from sklearn.utils._param_validation import Interval, validate_params

from ._velocity_kernels import fit_groups

__all__ = ["estimate_velocities", "estimate_velocity"]

#: Largest number of (group, hypothesis, detection) residuals held at once.
_BLOCK_ELEMENTS = 1 << 20

#: ``_estimate``'s settings after ``n_groups`` for the defaults of :func:`estimate_velocities`:
#: min_detections, min_spread (rad), inlier_threshold (m/s), max_trials, random_state.
_VELOCITY_DEFAULTS = (3, 0.05, 0.25, 60, 0)


#: Seeds :func:`numpy.random.default_rng` accepts (an int must be non-negative).
_SEEDS = [
    None,
    Interval(Integral, 0, None, closed="left"),
    np.random.Generator,
    np.random.BitGenerator,
    np.random.SeedSequence,
]

#: Constraints of the keyword arguments shared by both public functions.
_SETTINGS_CONSTRAINTS = {
    "min_detections": [Interval(Integral, 2, None, closed="left")],
    "min_spread": [Interval(Real, 0, None, closed="left")],
    "inlier_threshold": [Interval(Real, 0, None, closed="neither")],
    "max_trials": [Interval(Integral, 1, None, closed="left")],
    "random_state": _SEEDS,
}


def _as_1d(v_r, los_angle):
    v_r = np.asarray(v_r, dtype=np.float64)
    los_angle = np.asarray(los_angle, dtype=np.float64)
    if v_r.ndim != 1 or los_angle.shape != v_r.shape:
        raise ValueError(
            f"v_r and los_angle must be 1-D arrays of equal length, got shapes {v_r.shape} and {los_angle.shape}"
        )
    return v_r, los_angle


def _reseedable(random_state):
    """True when ``default_rng(random_state)`` gives the same stream every time it is called."""
    return random_state is not None and not isinstance(random_state, (np.random.Generator, np.random.BitGenerator))


def _pairs(n, max_trials, rng, n_sets):
    """Hypothesis pairs ``(i, j)``, ``i != j``, as index arrays of shape (1 or n_sets, n_pairs).

    All ``n * (n - 1) / 2`` pairs (shape (1, n_pairs)) when that is at most
    ``max_trials``; otherwise ``max_trials`` pairs drawn uniformly from
    ``rng`` for each of the ``n_sets`` groups.
    """
    if n * (n - 1) // 2 <= max_trials:
        i, j = np.triu_indices(n, 1)
        return i[None, :], j[None, :]
    i = rng.integers(0, n, size=(n_sets, max_trials))
    j = rng.integers(0, n - 1, size=(n_sets, max_trials))
    j += j >= i  # uniform over the n - 1 indices other than i
    return i, j


def _fresh_pairs(n, max_trials, random_state):
    """The pairs of :func:`_pairs` for ``n`` detections, drawn by a generator seeded afresh with ``random_state``.

    Remembered for an int seed (the package's default, 0) and for all pairs
    (no draw), as they depend on ``(n, max_trials, random_state)`` only.
    """
    if n * (n - 1) // 2 <= max_trials:
        return _remembered_pairs(n, max_trials, 0)
    if isinstance(random_state, Integral) and not isinstance(random_state, bool):
        return _remembered_pairs(n, max_trials, int(random_state))
    return _pairs(n, max_trials, np.random.default_rng(random_state), 1)


def _pair_table(sizes, max_trials, random_state):
    """The pairs of every group size in ``sizes`` (a sorted tuple), one after the other.

    Returns ``(pair_i, pair_j, where)``: flat int64 arrays and, per size,
    (first position, number of pairs) in them.  Remembered for an int seed.
    """
    if isinstance(random_state, Integral) and not isinstance(random_state, bool):
        return _remembered_table(sizes, max_trials, int(random_state))
    return _table(sizes, max_trials, random_state)


@functools.lru_cache(maxsize=512)  # a table holds at most 60 pairs per size: below 1 kB per size
def _remembered_table(sizes, max_trials, seed):
    return _table(sizes, max_trials, seed)


def _table(sizes, max_trials, random_state):
    tables = [_fresh_pairs(n, max_trials, random_state) for n in sizes]
    counts = [pair_i.shape[1] for pair_i, _ in tables]
    firsts = np.concatenate(([0], np.cumsum(counts)[:-1])).tolist()
    where = {n: (first, count) for n, first, count in zip(sizes, firsts, counts, strict=True)}
    pair_i = np.concatenate([pair_i[0] for pair_i, _ in tables]).astype(np.int64)
    pair_j = np.concatenate([pair_j[0] for _, pair_j in tables]).astype(np.int64)
    return pair_i, pair_j, where


@functools.lru_cache(maxsize=1024)
def _remembered_pairs(n, max_trials, seed):
    """:func:`_pairs` with a generator seeded with ``seed``; the arrays are shared: never written to."""
    return _pairs(n, max_trials, np.random.default_rng(seed), 1)


def _estimate(v_r, theta, group_id, n_groups, min_detections, min_spread, threshold, max_trials, random_state):
    """Estimate every group; rows must be finite and sorted by ``group_id`` (0 .. n_groups - 1).

    Groups of equal size share their hypothesis pairs, unless a shared
    generator draws them: then it draws them for blocks of groups of one
    size (as many as ``_BLOCK_ELEMENTS`` residuals), the order in which the
    stacked numpy form consumed its stream.
    """
    sizes = np.bincount(group_id, minlength=n_groups)
    starts = np.cumsum(sizes) - sizes
    v_r, theta = np.ascontiguousarray(v_r, dtype=np.float64), np.ascontiguousarray(theta, dtype=np.float64)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    settings = (min_detections, min_spread, threshold)
    if _reseedable(random_state):  # the pairs depend on the size only: one table for all sizes, one compiled call
        size_list = sizes.tolist()  # a few groups: Python is cheaper than np.unique here
        fitted_sizes = tuple(sorted({n for n in size_list if n >= min_detections}))
        if not fitted_sizes:
            return np.full(n_groups, np.nan), np.full(n_groups, np.nan), np.zeros(n_groups, dtype=np.int64)
        pair_i, pair_j, where = _pair_table(fitted_sizes, max_trials, random_state)
        table = np.array([where.get(n, (0, 0)) for n in size_list], dtype=np.int64).reshape(-1, 2)
        return fit_groups(
            v_r,
            cos_t,
            sin_t,
            theta,
            starts,
            sizes,
            np.ascontiguousarray(table[:, 0]),
            np.ascontiguousarray(table[:, 1]),
            pair_i,
            pair_j,
            *settings,
        )
    vx = np.full(n_groups, np.nan)
    vy = np.full(n_groups, np.nan)
    n_inliers = np.zeros(n_groups, dtype=np.int64)
    fitted = np.flatnonzero(sizes >= min_detections)
    shared_rng = np.random.default_rng(random_state)
    for n in np.unique(sizes[fitted]).tolist():
        members = np.flatnonzero(sizes == n)
        n_pairs = max_trials if n * (n - 1) // 2 > max_trials else n * (n - 1) // 2
        block = max(1, _BLOCK_ELEMENTS // (n_pairs * n))
        for first in range(0, members.shape[0], block):
            chunk = members[first : first + block]
            pair_i, pair_j = _pairs(n, max_trials, shared_rng, chunk.shape[0])
            rows = pair_i.shape[0]  # 1 (all pairs, shared) or one row per group
            pair_start = (np.arange(len(chunk)) if rows > 1 else np.zeros(len(chunk), dtype=np.int64)) * n_pairs
            vx[chunk], vy[chunk], n_inliers[chunk] = fit_groups(
                v_r,
                cos_t,
                sin_t,
                theta,
                starts[chunk],
                sizes[chunk],
                pair_start.astype(np.int64),
                np.full(len(chunk), n_pairs, dtype=np.int64),
                pair_i.ravel(),
                pair_j.ravel(),
                *settings,
            )
    return vx, vy, n_inliers


@validate_params(
    {"v_r": ["array-like"], "los_angle": ["array-like"]} | _SETTINGS_CONSTRAINTS,
    prefer_skip_nested_validation=True,
)
def estimate_velocity(
    v_r,
    los_angle,
    *,
    min_detections=3,
    min_spread=0.05,
    inlier_threshold=0.25,
    max_trials=60,
    random_state=0,
):
    """Estimate one rigid object's 2-D velocity from the Doppler of its detections.

    Solves ``v_r[i] = vx * cos(los_angle[i]) + vy * sin(los_angle[i])`` with
    RANSAC over pairs of detections followed by least squares on the inliers
    (Kellner et al. 2013, as used by Scheiner et al. 2019).

    Read more in the :ref:`User Guide <user-guide-merging>`.

    Parameters
    ----------
    v_r : array-like of shape (n_detections,)
        Ego-motion-compensated radial velocity of each detection, m/s.
        Negative when the detection approaches the sensor (moves against the
        line of sight), positive when it recedes.
    los_angle : array-like of shape (n_detections,)
        Direction of the line of sight from the sensor that measured the
        detection to the detection, rad, in one common frame for all
        detections (for RadarScenes in car coordinates
        ``azimuth_sc + yaw_sensor``, i.e.
        ``atan2(y_cc - y_sensor, x_cc - x_sensor)``).
    min_detections : int, default=3
        Minimum number of inliers (>= 2) for a known estimate.
    min_spread : float, default=0.05
        Minimum angular spread (max - min), rad, of the inliers' lines of
        sight, taken modulo pi and measured around their circular mean so
        that it is continuous across +-pi.  Below it the lateral velocity
        component is ill-conditioned and the estimate is unknown.
    inlier_threshold : float, default=0.25
        A detection is an inlier of a velocity hypothesis when the absolute
        difference between its measured and predicted radial velocity is
        below this, m/s.
    max_trials : int, default=60
        If the number of pairs ``n * (n - 1) / 2`` is at most this, every
        pair is a hypothesis (deterministic); otherwise ``max_trials``
        random pairs are drawn.
    random_state : int, numpy.random.Generator, BitGenerator, SeedSequence or None, default=0
        Passed to :func:`numpy.random.default_rng` to draw the pairs; an int
        must be >= 0.

    Returns
    -------
    vx, vy : float
        Velocity, m/s, in the frame of ``los_angle``; both NaN when unknown:
        fewer than ``min_detections`` (finite) detections or inliers, no pair
        of detections with ``|sin(theta_j - theta_i)| >= 1e-3``, or an inlier
        angular spread below ``min_spread``.
    n_inliers : int
        Number of detections in the final least-squares fit, also reported
        when the estimate is unknown because of too few inliers or too small
        a spread; 0 when no hypothesis was formed (too few detections, no
        valid pair).

    Notes
    -----
    Detections with a non-finite ``v_r`` or ``los_angle`` are ignored.

    Hypotheses are the exact solutions of pairs of detections, skipping
    pairs with ``|sin(theta_j - theta_i)| < 1e-3``.  The best has the most
    detections with ``|residual| < inlier_threshold`` (tie: the smaller sum
    of squared inlier residuals).  Its inliers are fitted by least squares,
    the inliers re-selected once with that velocity (kept if at least two)
    and fitted again.

    The model assumes a non-rotating rigid object; a turning vehicle's yaw
    rate shows up as residuals that grow with its extent.  The lateral
    component (across the lines of sight) has a standard deviation of about
    ``sigma_vr / (sqrt(n_inliers) * std(los_angle))``, so it is poor for a
    distant object seen by one sensor.
    """
    v_r, los_angle = _as_1d(v_r, los_angle)
    finite = np.isfinite(v_r) & np.isfinite(los_angle)
    if not finite.all():
        v_r, los_angle = v_r[finite], los_angle[finite]
    vx, vy, n_inliers = _estimate(
        v_r,
        los_angle,
        np.zeros(v_r.shape[0], dtype=np.intp),
        1,
        int(min_detections),
        float(min_spread),
        float(inlier_threshold),
        int(max_trials),
        random_state,
    )
    return float(vx[0]), float(vy[0]), int(n_inliers[0])


@validate_params(
    {"v_r": ["array-like"], "los_angle": ["array-like"], "groups": ["array-like"]} | _SETTINGS_CONSTRAINTS,
    prefer_skip_nested_validation=True,
)
def estimate_velocities(
    v_r,
    los_angle,
    groups,
    *,
    min_detections=3,
    min_spread=0.05,
    inlier_threshold=0.25,
    max_trials=60,
    random_state=0,
):
    """Estimate the velocity of every group (cluster) of detections.

    Gives the same result as :func:`estimate_velocity` applied to each
    group's detections (in their original order) with the same keyword
    arguments, for an integer ``random_state``.  Faster: one stable argsort
    finds the groups, and groups of equal size are stacked and processed
    together (their random pairs, which then depend only on the size, are
    drawn once per size).

    Read more in the :ref:`User Guide <user-guide-merging>`.

    Parameters
    ----------
    v_r : array-like of shape (n_detections,)
        Ego-motion-compensated radial velocity, m/s (negative = approaching).
    los_angle : array-like of shape (n_detections,)
        Line-of-sight direction from the measuring sensor to the detection,
        rad, in one common frame.
    groups : array-like of shape (n_detections,)
        Group (cluster) label of each detection; any sortable values, in any
        order.
    min_detections, min_spread, inlier_threshold, max_trials, random_state
        As in :func:`estimate_velocity`.  An integer (or a
        :class:`numpy.random.SeedSequence`) seeds a fresh generator for each
        group, exactly as :func:`estimate_velocity`; a Generator, a
        BitGenerator or None is one generator shared by all groups.

    Returns
    -------
    vx, vy : ndarray of float64, shape (n_groups,)
        Velocity of each group, m/s, NaN when unknown.
    n_inliers : ndarray of int64, shape (n_groups,)
        Inlier count of each group (see :func:`estimate_velocity`).
    unique_groups : ndarray of shape (n_groups,)
        The sorted unique group labels the entries refer to.
    """
    return _estimate_velocities(
        v_r,
        los_angle,
        groups,
        min_detections=min_detections,
        min_spread=min_spread,
        inlier_threshold=inlier_threshold,
        max_trials=max_trials,
        random_state=random_state,
    )


def _estimate_velocities(
    v_r,
    los_angle,
    groups,
    *,
    min_detections=3,
    min_spread=0.05,
    inlier_threshold=0.25,
    max_trials=60,
    random_state=0,
):
    """:func:`estimate_velocities` without its parameter validation, for callers inside the package.

    The settings must satisfy the constraints of the public function.
    """
    v_r, los_angle = _as_1d(v_r, los_angle)
    groups = np.asarray(groups)
    if groups.shape != v_r.shape:
        raise ValueError(f"groups must have the shape of v_r {v_r.shape}, got {groups.shape}")

    order = np.argsort(groups, kind="stable")  # stable: keeps each group's detection order
    sorted_groups = groups[order]
    new_group = np.empty(order.shape[0], dtype=bool)
    new_group[:1] = True
    np.not_equal(sorted_groups[1:], sorted_groups[:-1], out=new_group[1:])
    unique_groups = sorted_groups[new_group]
    group_id = np.cumsum(new_group) - 1

    v_r, theta = v_r[order], los_angle[order]
    finite = np.isfinite(v_r) & np.isfinite(theta)
    if not finite.all():
        v_r, theta, group_id = v_r[finite], theta[finite], group_id[finite]
    vx, vy, n_inliers = _estimate(
        v_r,
        theta,
        group_id,
        unique_groups.shape[0],
        int(min_detections),
        float(min_spread),
        float(inlier_threshold),
        int(max_trials),
        random_state,
    )
    return vx, vy, n_inliers, unique_groups


def _velocities_and_residuals(v_r, theta, group_id, n_groups):
    """Velocity and RMS Doppler residual of every group, at the defaults of :func:`estimate_velocities`.

    The batched estimate of :func:`_estimate` (one compiled call for all
    groups), then, vectorised over all rows, the root mean square over each
    group's detections (outliers included) of ``v_r - (vx cos(theta) + vy
    sin(theta))``: how far the Doppler of the group departs from one rigid
    translation (the micro-Doppler of limbs and wheels, multipath, mixed
    objects), m/s.

    Parameters
    ----------
    v_r, theta : ndarray of float64, shape (n,)
        Compensated radial velocity (m/s) and line-of-sight direction (rad) of
        each row; finite, rows sorted by ``group_id``.
    group_id : ndarray of int64, shape (n,)
        Group of each row, 0 .. n_groups - 1, sorted ascending.
    n_groups : int

    Returns
    -------
    vx, vy, residual : ndarray of float64, shape (n_groups,)
        Velocity (m/s) and residual (m/s) of each group; all three NaN where
        the velocity is unknown.
    """
    vx, vy, _ = _estimate(v_r, theta, group_id, n_groups, *_VELOCITY_DEFAULTS)
    predicted = vx[group_id] * np.cos(theta) + vy[group_id] * np.sin(theta)
    squared = np.bincount(group_id, weights=(v_r - predicted) ** 2, minlength=n_groups)
    counts = np.bincount(group_id, minlength=n_groups)
    with np.errstate(invalid="ignore", divide="ignore"):
        residual = np.sqrt(squared / counts)
    return vx, vy, residual
