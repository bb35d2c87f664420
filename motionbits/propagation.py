"""Soft label propagation (paper Sec. 5.2, SoftLabelPropagation; after Zhou et al.)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = ["grid_seeds", "propagate_components", "propagate_labels", "row_stochastic"]


def grid_seeds(rows: int, cols: int, stride: int) -> np.ndarray:
    """Uniformly spaced seed nodes: every ``stride``-th node of a rows x cols grid, centred.

    Returns:
        (C,) int64 row-major node indices; C ~ n / stride^2 (the paper's C = 0.04 n at
        stride 5).
    """
    off = stride // 2
    r = np.arange(off, rows, stride)
    c = np.arange(off, cols, stride)
    return (r[:, None] * cols + c[None, :]).ravel().astype(np.int64)


def row_stochastic(w: sp.csr_matrix) -> sp.csr_matrix:
    """A = D^-1 W; rows of isolated nodes stay zero."""
    deg = np.asarray(w.sum(axis=1)).ravel()
    inv = np.divide(1.0, deg, out=np.zeros_like(deg), where=deg > 0)
    return sp.diags(inv) @ w


def propagate_labels(w: sp.csr_matrix, seeds: np.ndarray, iters: int, reseed_every: int,
                     dtype: type = np.float64, classes: np.ndarray | None = None) -> np.ndarray:
    """Diffuse one-hot seed labels over the graph.

    B(0) = Y; B(r+1) = A B(r); every ``reseed_every`` iterations B += Y ("pour more paint").

    Args:
        w: (m, m) sparse non-negative affinities.
        seeds: (C,) indices of seed nodes (into 0..m-1); seed c gets class c.
        iters: R, the number of diffusion steps.
        reseed_every: r*.
        dtype: float type of the computation.
        classes: optional (C,) column of each seed instead of c. Paint never crosses
            between connected components of ``w``, so seeds of different components may
            share a column: numbering seeds within their component gives the same
            embedding with far fewer columns.

    Returns:
        (m, C') soft label embedding B(R) of type ``dtype``, C' = number of classes.
    """
    m = w.shape[0]
    classes = np.arange(len(seeds)) if classes is None else np.asarray(classes)
    y = np.zeros((m, int(classes.max()) + 1 if len(classes) else 0), dtype)
    y[seeds, classes] = 1.0
    a = row_stochastic(w.tocsr()).astype(dtype)
    b = y.copy()
    for r in range(1, iters + 1):
        b = a @ b
        if r % reseed_every == 0:
            b += y
    return b


def propagate_components(w: sp.csr_matrix, seeds: np.ndarray, iters: int, reseed_every: int,
                         dtype: type = np.float64, propagate_fn=None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`propagate_labels` with the seeds numbered within their connected component.

    W is block-diagonal over its connected components and paint never crosses between
    them, so seeds of different components share columns: one column per seed of the
    largest component.

    Args:
        w: (m, m) sparse non-negative affinities.
        seeds: (S,) indices of seed nodes (into 0..m-1).
        iters, reseed_every, dtype: as in :func:`propagate_labels`.
        propagate_fn: optional replacement of :func:`propagate_labels` with its signature
            (e.g. :meth:`motionbits.torch_ops.TorchOps.propagate_labels`).

    Returns:
        b (m, C') embedding of type ``dtype``; comp (m,) int component of each node;
        n_seeds (n_comp,) int seeds of each component (its seeds are b's first columns).
    """
    n_comp, comp = connected_components(w, directed=False)
    seed_comp = comp[seeds]
    order = np.argsort(seed_comp, kind="stable")
    starts = np.searchsorted(seed_comp[order], seed_comp[order])
    classes = np.empty(len(seeds), np.int64)
    classes[order] = np.arange(len(seeds)) - starts
    b = (propagate_fn or propagate_labels)(w, seeds, iters, reseed_every, dtype=dtype,
                                           classes=classes)
    return b, comp, np.bincount(seed_comp, minlength=n_comp)
