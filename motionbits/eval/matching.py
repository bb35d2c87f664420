"""One-to-one matching of predicted to ground-truth objects (Hungarian, maximum total F)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

__all__ = ["hungarian_match"]


def hungarian_match(score: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Assign GT rows to predicted columns maximising the total score.

    ``scipy.optimize.linear_sum_assignment`` on the (K, M) score matrix (rectangular allowed:
    min(K, M) pairs). Pairs with score 0 (no overlapping pixel) are dropped: such a GT object
    counts as unmatched and such a prediction as unmatched.

    Args:
        score: (K, M) float, e.g. the overlap F of every (GT, predicted) pair.

    Returns:
        ``(rows, cols)``: (L,) int64 matched GT and predicted indices, L <= min(K, M),
        sorted by row.
    """
    score = np.asarray(score, dtype=np.float64)
    if score.ndim != 2:
        raise ValueError(f"score must be a (K, M) matrix, got shape {score.shape}")
    if score.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    rows, cols = linear_sum_assignment(score, maximize=True)
    keep = score[rows, cols] > 0
    return rows[keep].astype(np.int64), cols[keep].astype(np.int64)
