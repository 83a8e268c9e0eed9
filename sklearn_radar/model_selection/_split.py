"""Train/test split by sequence (Sec. "Experiments & Results" of Scheiner et al. 2019)."""

from __future__ import annotations

import numpy as np
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, RealNotInt, validate_params

__all__ = ["sequence_train_test_split"]


@validate_params(
    {
        "groups": ["array-like"],
        "test_size": [Interval(RealNotInt, 0, 1, closed="neither")],
        "random_state": ["random_state"],
    },
    prefer_skip_nested_validation=True,
)
def sequence_train_test_split(groups, *, test_size=0.5, random_state=None):
    """Split whole sequences into a training and a test part of balanced detection counts.

    The paper splits its data set "into two disjoint parts of almost equal
    size, one for parameter estimation (training set) and one for evaluation
    (test set)".  Here a sequence (recording) is never cut: detections of one
    sequence are correlated in time, so a row-wise split would leak.  The
    sequences are assigned greedily, largest first, each to the side that is
    further below its target share of detections (``test_size`` of all
    detections for the test side, the rest for the training side).  Equal
    sequence sizes and equal shortfalls are ordered by ``random_state``.  For
    ``test_size=0.5`` the two sides then differ by at most the detection
    count of the largest sequence.  Each side receives at least one sequence.

    Cross-validation inside the training part should be grouped by sequence
    too, for example with :class:`sklearn.model_selection.GroupKFold` and
    ``groups=groups[train_index]`` (what :func:`make_bayes_search` sets up).

    Read more in the :ref:`User Guide <user-guide-tuning>`.

    Parameters
    ----------
    groups : array-like of shape (n_detections,)
        Sequence id of each detection (any hashable, sortable labels), e.g.
        the ``groups`` of :func:`sklearn_radar.datasets.make_scenes` or the
        ``sequence`` column of the detection table.
    test_size : float, default=0.5
        Target share of the *detections* in the test part, in (0, 1).
    random_state : int, RandomState instance or None, default=None
        Breaks ties between sequences of equal size and between sides of equal
        shortfall.  Pass an int for reproducible splits.

    Returns
    -------
    train_index, test_index : ndarray of int64
        Sorted row positions of the training and the test detections.
        Together they hold every row exactly once.

    Raises
    ------
    ValueError
        If ``groups`` is not 1-D or holds fewer than two sequences, or if
        ``test_size`` is not a float in (0, 1).

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_radar.model_selection import sequence_train_test_split
    >>> groups = np.repeat([1, 2, 3, 4], [50, 40, 30, 20])
    >>> train, test = sequence_train_test_split(groups, random_state=0)
    >>> len(train), len(test)
    (70, 70)
    >>> sorted(set(groups[train]) & set(groups[test]))
    []
    """
    groups = np.asarray(groups)
    if groups.ndim != 1:
        raise ValueError(f"groups must be 1-D (one sequence id per detection), got shape {groups.shape}")
    sequences, codes, sizes = np.unique(groups, return_inverse=True, return_counts=True)
    if len(sequences) < 2:
        raise ValueError(f"groups must hold at least 2 sequences to split by sequence, got {len(sequences)}")
    side = sequence_sides(sizes, test_size, random_state)
    test_rows = side[codes.ravel()] == 1
    return np.flatnonzero(~test_rows).astype(np.int64), np.flatnonzero(test_rows).astype(np.int64)


def sequence_sides(sizes, test_size=0.5, random_state=None):
    """The side of each sequence in :func:`sequence_train_test_split`, from the sequences' sizes alone.

    A run whose data lives on several machines splits it without a row per
    detection in one place; :func:`sequence_train_test_split` is this applied
    to the counts of its ``groups``.

    Parameters
    ----------
    sizes : ndarray of int of shape (n_sequences,)
        Detections per sequence, in increasing sequence id (at least 2).
    test_size : float, default=0.5
    random_state : int, RandomState instance or None, default=None

    Returns
    -------
    side : ndarray of int64 of shape (n_sequences,)
        0 for the training side, 1 for the test side.
    """
    sizes = np.asarray(sizes)
    rng = check_random_state(random_state)
    # Largest first; a random permutation before the stable sort orders equal sizes.
    shuffled = rng.permutation(len(sizes))
    order = shuffled[np.argsort(-sizes[shuffled], kind="stable")]
    total = sizes.sum()
    target = np.array([(1.0 - test_size) * total, test_size * total])
    totals = np.zeros(2)
    side = np.empty(len(sizes), dtype=np.int64)  # 0 = train, 1 = test
    for k in order:
        shortfall = target - totals
        if shortfall[0] == shortfall[1]:
            chosen = int(rng.randint(2))
        else:
            chosen = int(np.argmax(shortfall))
        side[k] = chosen
        totals[chosen] += sizes[k]
    for empty in (0, 1):
        if not np.any(side == empty):  # extreme test_size: give the empty side the smallest sequence
            smallest = order[::-1][0]
            side[smallest] = empty
    return side
