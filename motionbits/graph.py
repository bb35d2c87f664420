"""The spatial-twist similarity graph (paper Sec. 5.1, BuildTwistSimGraph).

Edge (i, j) for j in the k nearest neighbours of i has weight exp(-0.5 Mdist^2), the
Mahalanobis distance of the twist difference under the covariance of the twists of N*(i).
Six twists in 3-D give a near-singular covariance, so it is regularised with the covariance
the fitted twist would have from ``flow_noise`` px of noise on each of the 6 points,
sigma^2 (J^T J)^-1 with J the Jacobian of point velocities w.r.t. the twist: the regulariser
carries the strong omega / v coupling of a twist expressed about a distant origin.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from motionbits.nodes import NodeGrid

__all__ = ["inv_sym3", "twist_noise_covariance", "local_covariances", "twist_edge_weights", "apply_temporal_constraints", "project_past_max",
           "symmetric_graph"]


def inv_sym3(a: np.ndarray) -> np.ndarray:
    """Inverses of a batch of symmetric 3x3 matrices, (n, 3, 3) -> (n, 3, 3), by cofactors
    (one vectorised pass; LAPACK per 3x3 matrix costs more in call overhead than in work)."""
    entries = _inv_sym3_entries(a)
    out = np.empty_like(a, dtype=entries[0][0].dtype)
    for i in range(3):
        for j in range(3):
            out[:, i, j] = entries[i][j]
    return out


def _inv_sym3_entries(a: np.ndarray) -> list[list[np.ndarray]]:
    """:func:`inv_sym3` as a 3x3 nested list of (n,) arrays (entry [i][j] of every inverse)."""
    a00, a01, a02 = a[:, 0, 0], a[:, 0, 1], a[:, 0, 2]
    a11, a12, a22 = a[:, 1, 1], a[:, 1, 2], a[:, 2, 2]
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    i00, i01, i02, i11, i12, i22 = (c / det for c in (c00, c01, c02, c11, c12, c22))
    return [[i00, i01, i02], [i01, i11, i12], [i02, i12, i22]]


def twist_noise_covariance(points: np.ndarray, neighbors: np.ndarray, flow_noise: float
                           ) -> np.ndarray:
    """Covariance a twist fitted to each N* = {i} + neighbours has from flow noise alone.

    sigma^2 (J^T J)^-1 with J the Jacobian of the velocities u(p) = omega (-y, x) + v of the
    m points of N* w.r.t. the twist. It depends on the grid only, so it is computed once.

    Args:
        points: (n, 2) node positions (x, y) about the image origin.
        neighbors: (n, k) neighbour indices.
        flow_noise: flow noise standard deviation in px.

    Returns:
        (n, 3, 3) float64.
    """
    idx = np.concatenate([np.arange(len(points))[:, None], neighbors], axis=1)
    p = points.astype(np.float64)[idx]
    x, y = p[..., 0], p[..., 1]
    jtj = np.empty((len(points), 3, 3))
    jtj[:, 0, 0] = (x * x + y * y).sum(1)
    jtj[:, 0, 1] = jtj[:, 1, 0] = -y.sum(1)
    jtj[:, 0, 2] = jtj[:, 2, 0] = x.sum(1)
    jtj[:, 1, 1] = jtj[:, 2, 2] = float(idx.shape[1])
    jtj[:, 1, 2] = jtj[:, 2, 1] = 0.0
    return flow_noise**2 * inv_sym3(jtj)


def local_covariances(twists: np.ndarray, neighbors: np.ndarray, noise_cov: np.ndarray
                      ) -> np.ndarray:
    """Regularised covariance of the twists of each node's N* = {i} + neighbours.

    Args:
        twists: (n, 3) twists [omega, v_x, v_y].
        neighbors: (n, k) neighbour indices.
        noise_cov: (n, 3, 3) regulariser from :func:`twist_noise_covariance`.

    Returns:
        (n, 3, 3) float64 symmetric positive-definite covariances.
    """
    idx = np.concatenate([np.arange(len(twists))[:, None], neighbors], axis=1).T  # (m, n)
    m = idx.shape[0]
    if 2 <= m < 8:  # numpy sums fewer than 8 numbers in order: row by row, along the nodes
        idx = np.ascontiguousarray(idx)

        def total(v: np.ndarray) -> np.ndarray:
            out = v[0] + v[1]
            for row in v[2:]:
                out += row
            return out
    else:
        def total(v: np.ndarray) -> np.ndarray:
            return v.sum(axis=0)
    vc = []  # per component, (m, n): the twists of N* about their mean
    for i in range(3):
        v = twists[:, i][idx]
        vc.append(v - total(v) / m)
    out = noise_cov.copy()
    for i in range(3):
        for j in range(i, 3):
            sij = total(vc[i] * vc[j]) / (m - 1)
            out[:, i, j] += sij
            if i != j:
                out[:, j, i] += sij
    return out


def twist_edge_weights(twists: np.ndarray, neighbors: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """(n, k) weights exp(-0.5 * Mdist(i, j)^2) of the edges i -> neighbors[i, s]."""
    # computed as (k, n): every operation runs along the n nodes
    nb = np.ascontiguousarray(neighbors.T)
    diff = [twists[:, i][nb] - twists[:, i] for i in range(3)]  # (k, n) each
    prec = _inv_sym3_entries(cov)  # [i][j]: (n,)
    d2 = np.zeros(nb.shape)
    for i in range(3):
        for j in range(3):
            term = diff[i] * prec[i][j]
            term *= diff[j]
            d2 += term
    np.maximum(d2, 0.0, out=d2)
    d2 *= -0.5
    return np.ascontiguousarray(np.exp(d2, out=d2).T)


def project_past_max(past_max: np.ndarray, grid: NodeGrid, source: np.ndarray) -> np.ndarray:
    """Largest earlier weight of each current edge, read from the previous frame's graph at
    the nodes nearest to where the edge's endpoints came from.

    Args:
        past_max: (..., n, k) largest earlier weight of each edge of the previous frame's
            graph (leading axes: several such graphs, projected alike).
        grid: the node grid (the same at both frames); its ``neighbors`` are the edges.
        source: (n,) int index of the node nearest to where each node came from (its
            backward-flow target, e.g. :meth:`motionbits.nodes.NodeGrid.nearest_node`).

    Returns:
        (..., n, k) float64; 0 where the edge's source endpoints are not neighbours.
    """
    si = source[:, None]
    slot = grid.edge_slot(si, source[grid.neighbors])  # (n, k)
    return np.where(slot >= 0, past_max[..., si, np.maximum(slot, 0)], 0.0)


def apply_temporal_constraints(weights: np.ndarray, neighbors: np.ndarray, history: np.ndarray,
                               past_max: np.ndarray) -> np.ndarray:
    """Edge removal and addition from earlier label maps (paper Sec. 5.1).

    ``history`` is the per-node class of the meet of all earlier label partitions carried
    to the current frame (0 = background at every earlier frame): two nodes share a class
    iff they shared a label at every earlier frame.

    - Separated at some earlier frame (different classes): the edge is removed.
    - Together in a MotionBit at every earlier frame (same non-zero class): the edge is
      added with the largest earlier weight (kept at the current one if that is larger).
    - Never moved (both class 0): the current twist similarity decides alone.

    Args:
        weights: (n, k) current edge weights.
        neighbors: (n, k) neighbour indices.
        history: (n,) int history class of each node.
        past_max: (n, k) largest earlier weight of each edge, projected to this frame.

    Returns:
        (n, k) constrained weights.
    """
    hi = history[:, None]
    hj = history[neighbors]
    out = np.where(hi != hj, 0.0, weights)
    together = (hi == hj) & (hi != 0)
    return np.where(together, np.maximum(out, past_max), out)


def symmetric_graph(weights: np.ndarray, neighbors: np.ndarray, keep: np.ndarray | None = None
                    ) -> sp.csr_matrix:
    """Sparse symmetric affinity W = max(W, W^T) over the k-NN edges.

    Args:
        weights: (n, k) weights of the edges i -> neighbors[i, s].
        neighbors: (n, k) neighbour indices.
        keep: optional (n,) bool; the graph is induced on these nodes and re-indexed in
            their order (``np.flatnonzero(keep)``).

    Returns:
        (m, m) CSR matrix, m = n or keep.sum().
    """
    n, k = neighbors.shape
    rows = np.repeat(np.arange(n), k)
    cols = neighbors.ravel()
    vals = weights.ravel()
    if keep is not None:
        new_index = np.full(n, -1, np.int64)
        new_index[keep] = np.arange(int(keep.sum()))
        rows, cols = new_index[rows], new_index[cols]
        ok = (rows >= 0) & (cols >= 0)
        rows, cols, vals = rows[ok], cols[ok], vals[ok]
        n = int(keep.sum())
    ok = vals > 0
    w = sp.csr_matrix((vals[ok], (rows[ok], cols[ok])), shape=(n, n))
    return w.maximum(w.T).tocsr()
