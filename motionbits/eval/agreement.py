"""Agreement between two partitions of the same items, whatever their label numbers."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix

__all__ = ["adjusted_rand_index"]


def _pairs(counts: np.ndarray) -> float:
    counts = np.asarray(counts, np.float64)
    return float((counts * (counts - 1) / 2).sum())


def adjusted_rand_index(a: np.ndarray, b: np.ndarray) -> float:
    """Adjusted Rand index (Hubert & Arabie, 1985) of two labelings of the same items.

    ARI = (sum_ij C(n_ij, 2) - E) / (((sum_i C(a_i, 2) + sum_j C(b_j, 2)) / 2) - E) with
    E = sum_i C(a_i, 2) sum_j C(b_j, 2) / C(n, 2), n_ij the contingency table, a_i and b_j
    its row and column sums. 1 for identical partitions (up to renumbering), ~0 for
    independent ones. Two partitions that are both a single cluster (or all singletons)
    score 1.

    Args:
        a, b: label arrays of the same shape: non-negative integers (int, bool, or floats
            holding whole numbers); any numbering, 0 is a label like any other.

    Returns:
        ARI in [-1, 1].

    Raises:
        TypeError: not a numeric array.
        ValueError: fractional, NaN or negative labels, or the shapes differ.
    """
    a, b = np.asarray(a), np.asarray(b)
    for name, x in (("a", a), ("b", b)):  # 0.5 and 0.7 were one label, NaN and -1 (void) labels
        if x.dtype.kind not in "biuf":
            raise TypeError(f"{name} must be an integer label array, got dtype {x.dtype}")
        if x.dtype.kind == "f" and not (np.isfinite(x).all() and (x == np.round(x)).all()):
            raise ValueError(f"{name} must hold whole-number labels, got {x.dtype} values such as "
                             f"{float(x[~(np.isfinite(x) & (x == np.round(x)))].flat[0])!r}")
        if x.size and x.dtype != np.bool_ and x.min() < 0:
            raise ValueError(f"{name} holds negative labels (min {x.min()}); labels must be >= 0")
    if a.shape != b.shape:  # else a (10, 40) and a (20, 20) map were compared pixel by pixel
        raise ValueError(f"label arrays differ in shape: {a.shape} vs {b.shape}; they must "
                         "label the same items")
    a, b = a.ravel(), b.ravel()
    n = a.size
    if n < 2:
        return 1.0
    ia = np.unique(a, return_inverse=True)[1]
    ib = np.unique(b, return_inverse=True)[1]
    table = coo_matrix((np.ones(n), (ia, ib))).tocsr()
    table.sum_duplicates()
    index = _pairs(table.data)
    sa = _pairs(np.bincount(ia))
    sb = _pairs(np.bincount(ib))
    expected = sa * sb / (n * (n - 1) / 2)
    top = (sa + sb) / 2
    if top == expected:  # both trivial partitions of the same kind
        return 1.0
    return (index - expected) / (top - expected)
