"""The compiled fit of :mod:`sklearn_radar.cluster._velocity`: RANSAC over pairs and least squares, per group.

The rows of one group satisfy ``v_r ~ vx cos(theta) + vy sin(theta)``
(``v_r`` in m/s, ``theta`` the line of sight in rad).  The estimator module
draws the hypothesis pairs with numpy and calls :func:`fit_groups`: the fit
of every group is one compiled loop (numba): the 2x2 systems solved in
closed form, the residuals of each hypothesis, and the least squares of
:func:`numpy.linalg.lstsq` (the SVD's minimum-norm solution with its
``rcond=None`` cut-off) computed for the two columns by one-sided Jacobi
rotations, which give the singular values to the same accuracy (its cost:
:ref:`online-speed`).
"""

from __future__ import annotations

import numba
import numpy as np

#: Pairs with ``|sin(theta_j - theta_i)|`` below this are skipped (near-singular 2x2 system).
_MIN_PAIR_SINE = 1e-3

_EPS = float(np.finfo(np.float64).eps)


@numba.njit(cache=True, nogil=True)
def rotated_sums(cos_t, sin_t, v_r, mask, cs, sn):
    """Sums over the masked rows, columns rotated to p = cs c1 - sn c2, q = sn c1 + cs c2: p.p, q.q, p.q, p.v, q.v."""
    a = d = e = bp = bq = 0.0
    for m in range(len(v_r)):
        if mask[m]:
            p = cs * cos_t[m] - sn * sin_t[m]
            q = sn * cos_t[m] + cs * sin_t[m]
            a += p * p
            d += q * q
            e += p * q
            bp += p * v_r[m]
            bq += q * v_r[m]
    return a, d, e, bp, bq


@numba.njit(cache=True, nogil=True)
def masked_lstsq(cos_t, sin_t, v_r, mask):
    """Least squares on the masked rows of one group: ``v_r ~ vx cos_t + vy sin_t``; returns (vx, vy).

    The solution of :func:`numpy.linalg.lstsq` (``rcond=None``): through
    the singular value decomposition of the (k, 2) design, singular values
    below ``eps * max(k, 2) * s_max`` dropped (the minimum-norm solution).
    For two columns the decomposition is one-sided Jacobi (Hestenes): the
    rotation that makes the columns orthogonal gives the right singular
    vectors, the norms of the rotated columns the singular values (to full
    relative accuracy, as LAPACK's), repeated while the columns are not yet
    orthogonal to working precision.
    """
    k = 0
    for m in range(len(v_r)):
        k += mask[m]
    cs, sn = 1.0, 0.0  # the accumulated rotation
    for _sweep in range(4):
        a, d, e, _, _ = rotated_sums(cos_t, sin_t, v_r, mask, cs, sn)
        if not abs(e) > _EPS * np.sqrt(a * d):  # orthogonal (or a zero column): done
            break
        zeta = (d - a) / (2.0 * e)
        tan = (1.0 if zeta >= 0 else -1.0) / (abs(zeta) + np.sqrt(1.0 + zeta * zeta))
        c_rot = 1.0 / np.sqrt(1.0 + tan * tan)
        s_rot = c_rot * tan
        cs, sn = cs * c_rot - sn * s_rot, sn * c_rot + cs * s_rot
    a, d, _, bp, bq = rotated_sums(cos_t, sin_t, v_r, mask, cs, sn)
    sigma_p, sigma_q = np.sqrt(a), np.sqrt(d)
    cut = _EPS * max(k, 2) * max(sigma_p, sigma_q)
    wp = bp / a if sigma_p > cut else 0.0  # (u_p . b) / sigma_p
    wq = bq / d if sigma_q > cut else 0.0
    # x = V diag(w): V's columns (cs, -sn) for p and (sn, cs) for q.
    return cs * wp + sn * wq, -sn * wp + cs * wq


@numba.njit(cache=True, nogil=True)
def axial_spread(theta, mask):
    """Spread (max - min, rad) of the masked line-of-sight directions of one group, taken modulo pi.

    Deviations are measured from the axial circular mean (the mean of the
    doubled angles, halved), so the result does not jump at +-pi, and
    opposite directions (theta and theta + pi), which constrain the same
    velocity component, count as no spread.  In ``[0, pi)``.
    """
    sum_sin = sum_cos = 0.0
    for m in range(len(theta)):
        if mask[m]:
            sum_sin += np.sin(2.0 * theta[m])
            sum_cos += np.cos(2.0 * theta[m])
    mean = np.arctan2(sum_sin, sum_cos)
    high, low = -np.inf, np.inf
    for m in range(len(theta)):
        if mask[m]:
            deviation = np.remainder(2.0 * theta[m] - mean + np.pi, 2.0 * np.pi) - np.pi
            high = max(high, deviation)
            low = min(low, deviation)
    return 0.5 * (high - low)


@numba.njit(cache=True, nogil=True)
def fit_groups(
    v_r, cos_t, sin_t, theta, start, size, pair_start, n_pairs, pair_i, pair_j, min_detections, min_spread, threshold
):
    """RANSAC over pairs, least squares, one re-selection, final fit, for each group.

    Group g is the rows ``[start[g], start[g] + size[g])`` of ``v_r``,
    ``cos_t``, ``sin_t`` and ``theta``; its hypotheses are the pairs
    ``pair_i[k], pair_j[k]`` (indices within the group) for ``k`` in
    ``[pair_start[g], pair_start[g] + n_pairs[g])``.  Returns ``vx``, ``vy``
    (NaN when unknown) and ``n_inliers``, each of shape (G,); a group of
    fewer than ``min_detections`` rows is unknown with 0 inliers.
    """
    n_groups = len(start)
    vx = np.full(n_groups, np.nan)
    vy = np.full(n_groups, np.nan)
    n_inliers = np.zeros(n_groups, dtype=np.int64)
    largest = 0
    for g in range(n_groups):
        largest = max(largest, size[g])
    mask = np.zeros(largest, dtype=np.bool_)
    best_mask = np.zeros(largest, dtype=np.bool_)
    for g in range(n_groups):
        n = size[g]
        if n < min_detections:  # too few detections: unknown, no inlier
            continue
        r, c, s = v_r[start[g] : start[g] + n], cos_t[start[g] : start[g] + n], sin_t[start[g] : start[g] + n]
        best_count, best_squared, has_pair = -2, np.inf, False
        for h in range(pair_start[g], pair_start[g] + n_pairs[g]):
            i, j = pair_i[h], pair_j[h]
            # Closed-form solution of [[c_i, s_i], [c_j, s_j]] @ (vx, vy) = (r_i, r_j).
            det = c[i] * s[j] - s[i] * c[j]  # = sin(theta_j - theta_i)
            valid = abs(det) >= _MIN_PAIR_SINE
            if not valid:
                det = 1.0
            hx = (r[i] * s[j] - r[j] * s[i]) / det
            hy = (c[i] * r[j] - c[j] * r[i]) / det
            count, squared = 0, 0.0
            for m in range(n):
                residual = r[m] - (hx * c[m] + hy * s[m])
                mask[m] = abs(residual) < threshold
                if mask[m]:
                    count += 1
                    squared += residual * residual
            if not valid:
                count = -1
            has_pair |= valid
            # Most inliers; tie: least squared residual; tie: the first hypothesis.
            if count > best_count or (count == best_count and squared < best_squared):
                best_count, best_squared = count, squared
                best_mask[:n] = mask[:n]
        fx, fy = masked_lstsq(c, s, r, best_mask[:n])
        n_reselected = 0
        for m in range(n):
            mask[m] = abs(r[m] - (fx * c[m] + fy * s[m])) < threshold
            n_reselected += mask[m]
        if n_reselected >= 2:
            best_mask[:n] = mask[:n]
        fx, fy = masked_lstsq(c, s, r, best_mask[:n])
        count = 0
        for m in range(n):
            count += best_mask[m]
        n_inliers[g] = count if has_pair else 0
        if has_pair and count >= min_detections:
            if axial_spread(theta[start[g] : start[g] + n], best_mask[:n]) >= min_spread:
                vx[g], vy[g] = fx, fy
    return vx, vy, n_inliers
