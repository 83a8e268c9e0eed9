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

Implementation.  Everything is vectorised with numpy: over the pairs (the
2x2 systems are solved in closed form and a hypotheses x detections residual
matrix is formed) and, in :func:`estimate_velocities`, over all clusters of
the same size at once.  The least-squares fits are those of
:func:`numpy.linalg.lstsq` (SVD, ``rcond=None`` cut-off) evaluated for a
stack of systems, with the non-inlier rows zeroed.

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

from numbers import Integral, Real

import numpy as np
from sklearn.utils._param_validation import Interval, validate_params

__all__ = ["estimate_velocities", "estimate_velocity"]

#: Pairs with ``|sin(theta_j - theta_i)|`` below this are skipped (near-singular 2x2 system).
_MIN_PAIR_SINE = 1e-3

#: Largest number of (group, hypothesis, detection) residuals held at once.
_BLOCK_ELEMENTS = 1 << 20


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


def _masked_lstsq(cos_t, sin_t, v_r, mask):
    """Least squares per group on its masked rows: rows (G, n) -> velocity (G, 2).

    Masked-out rows are zeroed, which leaves the least-squares solution of
    the remaining rows unchanged.  Solved through the SVD with the cut-off
    of :func:`numpy.linalg.lstsq` (``rcond=None``: singular values below
    ``eps * max(m, 2) * s_max`` are dropped, giving the minimum-norm
    solution), i.e. ``numpy.linalg.lstsq`` applied to a stack of systems.
    """
    weight = mask.astype(np.float64)
    design = np.stack((cos_t * weight, sin_t * weight), axis=2)
    u, s, vt = np.linalg.svd(design, full_matrices=False)
    rcond = np.finfo(np.float64).eps * np.maximum(mask.sum(axis=1), 2)
    large = s > rcond[:, None] * s.max(axis=1, keepdims=True)
    inverse = np.divide(1.0, s, out=np.zeros_like(s), where=large)
    projected = np.einsum("gnk,gn->gk", u, v_r * weight) * inverse
    return np.einsum("gkj,gk->gj", vt, projected)


def _axial_spread(theta, mask):
    """Spread (max - min, rad) of each group's masked line-of-sight directions taken modulo pi.

    Deviations are measured from the axial circular mean (the mean of the
    doubled angles, halved), so the result does not jump at +-pi, and
    opposite directions (theta and theta + pi), which constrain the same
    velocity component, count as no spread.  In ``[0, pi)``.
    """
    doubled = 2.0 * theta
    mean = np.arctan2((np.sin(doubled) * mask).sum(axis=1), (np.cos(doubled) * mask).sum(axis=1))
    deviation = np.mod(doubled - mean[:, None] + np.pi, 2.0 * np.pi) - np.pi
    high = np.where(mask, deviation, -np.inf).max(axis=1)
    low = np.where(mask, deviation, np.inf).min(axis=1)
    return 0.5 * (high - low)


def _fit_block(v_r, cos_t, sin_t, theta, pair_i, pair_j, min_detections, min_spread, threshold):
    """RANSAC over pairs, least squares, one re-selection, final fit, for G groups of n detections.

    ``v_r``, ``cos_t``, ``sin_t``, ``theta`` have shape (G, n); ``pair_i``,
    ``pair_j`` shape (1 or G, n_pairs).  Returns ``vx``, ``vy`` (NaN when
    unknown) and ``n_inliers``, each of shape (G,).
    """
    n_groups = v_r.shape[0]
    rows = np.arange(n_groups)
    g = rows[:, None]
    ci, si, ri = cos_t[g, pair_i], sin_t[g, pair_i], v_r[g, pair_i]
    cj, sj, rj = cos_t[g, pair_j], sin_t[g, pair_j], v_r[g, pair_j]

    # Closed-form solution of [[c_i, s_i], [c_j, s_j]] @ (vx, vy) = (r_i, r_j) for every pair.
    det = ci * sj - si * cj  # = sin(theta_j - theta_i)
    valid = np.abs(det) >= _MIN_PAIR_SINE
    det = np.where(valid, det, 1.0)
    hx = (ri * sj - rj * si) / det
    hy = (ci * rj - cj * ri) / det

    # Residuals (groups x hypotheses x detections) and the consensus of each hypothesis.
    residual = v_r[:, None, :] - (hx[:, :, None] * cos_t[:, None, :] + hy[:, :, None] * sin_t[:, None, :])
    inlier = np.abs(residual) < threshold
    count = np.where(valid, inlier.sum(axis=2), -1)
    squared = np.where(inlier, residual * residual, 0.0).sum(axis=2)
    top = count == count.max(axis=1, keepdims=True)
    best = np.argmin(np.where(top, squared, np.inf), axis=1)  # most inliers; tie: least squared residual
    mask = inlier[rows, best]

    velocity = _masked_lstsq(cos_t, sin_t, v_r, mask)
    predicted = velocity[:, :1] * cos_t + velocity[:, 1:] * sin_t
    reselected = np.abs(v_r - predicted) < threshold
    mask = np.where((reselected.sum(axis=1) >= 2)[:, None], reselected, mask)
    velocity = _masked_lstsq(cos_t, sin_t, v_r, mask)

    has_pair = valid.any(axis=1)
    n_inliers = np.where(has_pair, mask.sum(axis=1), 0)
    known = has_pair & (n_inliers >= min_detections) & (_axial_spread(theta, mask) >= min_spread)
    return (
        np.where(known, velocity[:, 0], np.nan),
        np.where(known, velocity[:, 1], np.nan),
        n_inliers,
    )


def _estimate(v_r, theta, group_id, n_groups, min_detections, min_spread, threshold, max_trials, random_state):
    """Estimate every group; rows must be finite and sorted by ``group_id`` (0 .. n_groups - 1).

    Groups of equal size are stacked and processed together in blocks.
    """
    vx = np.full(n_groups, np.nan)
    vy = np.full(n_groups, np.nan)
    n_inliers = np.zeros(n_groups, dtype=np.int64)
    sizes = np.bincount(group_id, minlength=n_groups)
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    reseed = _reseedable(random_state)
    shared_rng = None if reseed else np.random.default_rng(random_state)
    for n in np.unique(sizes[sizes >= min_detections]).tolist():
        members = np.flatnonzero(sizes == n)
        random = n * (n - 1) // 2 > max_trials
        n_pairs = max_trials if random else n * (n - 1) // 2
        if not random or reseed:
            # Same draw for every group of this size: a generator seeded afresh, as for one group.
            pair_i, pair_j = _pairs(n, max_trials, np.random.default_rng(random_state) if random else None, 1)
        block = max(1, _BLOCK_ELEMENTS // (n_pairs * n))
        for first in range(0, members.shape[0], block):
            chunk = members[first : first + block]
            if random and not reseed:
                pair_i, pair_j = _pairs(n, max_trials, shared_rng, chunk.shape[0])
            index = starts[chunk][:, None] + np.arange(n)
            vx[chunk], vy[chunk], n_inliers[chunk] = _fit_block(
                v_r[index],
                cos_t[index],
                sin_t[index],
                theta[index],
                pair_i,
                pair_j,
                min_detections,
                min_spread,
                threshold,
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
