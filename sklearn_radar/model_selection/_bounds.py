"""Which tuned parameters stopped at an end of their search range: a sign that the range is too narrow."""

from __future__ import annotations

import math

from .._skopt import Integer

#: Ends of a range that are limits of the parameter itself, not of the search, by parameter name (without the
#: ``step__`` prefix): a gate at 0 m/s or alpha_r at 0 or 1 is a setting, not a range that stopped the search.
NATURAL_ENDS = {
    "alpha_r": (0.0, 1.0),
    "vr_min": (0.0,),
    "vr_threshold": (0.0,),
    "gate": (0.0,),
    "cluster_vr_min": (0.0,),
    "min_samples": (1,),
    # 1: ClusterMerger's rule off; 2: HDBSCAN's smallest cluster.
    "min_cluster_size": (1, 2),
}


def bounds_reached(params, space, *, tolerance=0.01, natural=None):
    """Names of the parameters of ``params`` that lie at an end of their dimension in ``space``.

    A real value counts when it lies within ``tolerance`` of the range's span from an end (measured on the log
    scale for log-uniform dimensions); an integer when it equals an end.  Ends listed in ``natural``
    (default :data:`NATURAL_ENDS`) are not counted.

    Parameters
    ----------
    params : dict
        Tuned setting, ``{name: value}``.
    space : dict
        ``{name: skopt Dimension}``; names of ``params`` without a dimension are ignored.
    tolerance : float, default=0.01
        Share of the span.
    natural : dict or None, default=None
        ``{parameter name: ends}`` not to count.

    Returns
    -------
    names : list of str
        In the order of ``space``.

    Examples
    --------
    >>> from sklearn_radar._skopt import Real
    >>> bounds_reached({"cluster__eps": 2.99, "cluster__vr_min": 0.0},
    ...                {"cluster__eps": Real(0.2, 3.0), "cluster__vr_min": Real(0.0, 1.5)})
    ['cluster__eps']
    """
    natural = NATURAL_ENDS if natural is None else natural
    reached = []
    for name, dimension in space.items():
        if name not in params:
            continue
        ends = [end for end in dimension.bounds if end not in natural.get(name.split("__")[-1], ())]
        value = params[name]
        if isinstance(dimension, Integer):
            if value in ends:
                reached.append(name)
            continue
        scale = math.log if getattr(dimension, "prior", "uniform") == "log-uniform" else float
        low, high = (scale(end) for end in dimension.bounds)
        if any(abs(scale(value) - scale(end)) <= tolerance * (high - low) for end in ends):
            reached.append(name)
    return reached


__all__ = ["NATURAL_ENDS", "bounds_reached"]
