"""One-to-one matching of predicted to ground-truth objects (Hungarian, maximum total F)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_array, csr_array
from scipy.sparse.csgraph import connected_components, min_weight_full_bipartite_matching

__all__ = ["hungarian_match", "sparse_hungarian_match", "DENSE_MATCH_CELLS"]

#: Largest K x M score matrix matched densely; larger ones are matched on their non-zero
#: pairs only (at most one per pixel), in memory and time bounded by the image size.
DENSE_MATCH_CELLS = 4_000_000


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


def sparse_hungarian_match(k: int, m: int, rows: np.ndarray, cols: np.ndarray,
                           score: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`hungarian_match` of a (K, M) matrix given by its positive entries.

    Small problems (K M <= ``DENSE_MATCH_CELLS``) are solved densely, exactly as
    :func:`hungarian_match`. Larger ones are split into the connected components of the
    bipartite graph of positive pairs (objects that share no pixel never interact); a
    component with one GT object or one prediction takes its best pair, any other small
    component is solved densely and a large one as a minimum-weight full matching
    of an augmented sparse graph in which every object may also stay unmatched (LAPJVsp,
    ``scipy.sparse.csgraph.min_weight_full_bipartite_matching``).

    Args:
        k, m: numbers of GT and predicted objects.
        rows, cols: (L,) int indices of the pairs; each pair at most once.
        score: (L,) float > 0 scores of the pairs.

    Returns:
        ``(rows, cols)`` of the matched pairs, (P,) int64, sorted by row.
    """
    rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
    score = np.asarray(score, np.float64)
    pos = score > 0
    rows, cols, score = rows[pos], cols[pos], score[pos]
    if k * m <= DENSE_MATCH_CELLS:
        dense = np.zeros((k, m))
        dense[rows, cols] = score
        return hungarian_match(dense)
    # components of the bipartite graph: GT objects are nodes 0..k-1, predictions k..k+m-1
    graph = coo_array((np.ones(len(rows)), (rows, cols + k)), shape=(k + m, k + m))
    _, comp = connected_components(graph, directed=False)
    edge_comp = comp[rows]
    n_rows = np.bincount(comp[:k], minlength=comp.max() + 1)
    n_cols = np.bincount(comp[k:], minlength=comp.max() + 1)
    # one GT object or one prediction in the component: its best pair (the usual case)
    star = (n_rows[edge_comp] == 1) | (n_cols[edge_comp] == 1)
    order = np.lexsort((cols, rows, -score, edge_comp))
    order = order[star[order]]
    first = order[np.r_[True, np.diff(edge_comp[order]) != 0]] if order.size else order
    out_r, out_c = [rows[first]], [cols[first]]
    rest = np.flatnonzero(~star)
    order = rest[np.argsort(edge_comp[rest], kind="stable")]
    bounds = np.flatnonzero(np.diff(edge_comp[order])) + 1
    for idx in np.split(order, bounds) if order.size else []:
        r_ids, r = np.unique(rows[idx], return_inverse=True)
        c_ids, c = np.unique(cols[idx], return_inverse=True)
        if r_ids.size * c_ids.size <= DENSE_MATCH_CELLS:
            dense = np.zeros((r_ids.size, c_ids.size))
            dense[r, c] = score[idx]
            mr, mc = hungarian_match(dense)
        else:
            mr, mc = _augmented_match(r_ids.size, c_ids.size, r, c, score[idx])
        out_r.append(r_ids[mr])
        out_c.append(c_ids[mc])
    r, c = np.concatenate(out_r).astype(np.int64), np.concatenate(out_c).astype(np.int64)
    order = np.argsort(r, kind="stable")
    return r[order], c[order]


def _augmented_match(k: int, m: int, rows: np.ndarray, cols: np.ndarray,
                     score: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Maximum-score matching (unmatched allowed) as a minimum-weight full matching.

    Rows: k real + m dummy; columns: m real + k dummy. Real pair (i, j) costs 2 - s,
    real row i - dummy column i (i unmatched) costs 2, dummy row j - real column j (j
    unmatched) costs 2, and dummy row j - dummy column i costs 2 for every real pair (i, j),
    so that every matching of the real pairs completes to a full one. A full matching with
    P real pairs costs 2 (k + m) - sum of their scores: the minimum maximises the score.
    """
    n = k + m
    ar = np.arange(k)
    am = np.arange(m)
    r = np.concatenate([rows, ar, k + am, k + cols])
    c = np.concatenate([cols, m + ar, am, m + rows])
    w = np.concatenate([2.0 - score, np.full(k + m + len(rows), 2.0)])
    match = min_weight_full_bipartite_matching(csr_array((w, (r, c)), shape=(n, n)))[1]
    real = match[:k]
    hit = real < m
    return np.flatnonzero(hit).astype(np.int64), real[hit].astype(np.int64)
