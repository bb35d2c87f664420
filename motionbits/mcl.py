"""Hard Markov clustering of the soft label embedding (paper Sec. 5.2, HardMarkovClustering).

X = B^ B^T (rows of B l2-normalised), unit self-loops, column-normalised, then MCL (van
Dongen): expansion (matrix power), inflation (element-wise power), column
re-normalisation, pruning of tiny entries. Clusters are the attractor systems.

Exact devices keep it affordable on a CPU:

- MCL never joins what is disconnected: on a block-diagonal matrix (up to a permutation)
  it runs on each connected block of the support independently, with the same result;
- rows of the iterate that are entirely zero stay zero, so each expansion only multiplies
  the rows that still hold mass;
- nodes with identical rows of B^ have identical rows and columns in every iterate, so
  they can be clustered once with their multiplicity (``multiplicity``): the result is
  the same as on the expanded matrix.

Pruning: an entry under ``prune / m`` (m = nodes clustered) is set to zero. A threshold
fixed in absolute terms caps a cluster at ~1/p nodes and shatters large bodies; relative to
m it never cuts a uniform column of any cluster (entries >= 1/m).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["markov_cluster", "markov_cluster_coarse", "normalize_rows", "normalized_similarity",
           "attractor_labels", "cluster_components", "cluster_component"]


def normalize_rows(b: np.ndarray) -> np.ndarray:
    """B^: the rows of an (m, C) embedding scaled to unit l2 norm (zero rows stay zero)."""
    norm = np.linalg.norm(b, axis=1, keepdims=True)
    return np.divide(b, norm, out=np.zeros_like(b), where=norm > 0)


def normalized_similarity(b: np.ndarray) -> np.ndarray:
    """X = B^ B^T with B^ the row-l2-normalised embedding; (m, C) -> (m, m), dtype of ``b``."""
    bh = normalize_rows(b)
    return bh @ bh.T


def attractor_labels(m: np.ndarray) -> np.ndarray:
    """Cluster index of every column of an MCL iterate: the attractor systems.

    Each node is linked to the row holding most of its column's mass; the connected
    components of those links are the clusters (at convergence: attractors that share
    columns form one system, and every node joins the system it flows to).

    Returns:
        (m,) int64 labels 0..K-1, numbered by first appearance.
    """
    return _attractors(np.argmax(m, axis=0))


def _attractors(dest: np.ndarray) -> np.ndarray:
    """:func:`attractor_labels` from the row ``dest`` (m,) holding most of each column."""
    return _by_first_appearance(_functional_components(dest))


def _functional_components(dest: np.ndarray) -> np.ndarray:
    """Weak components of the graph i -> dest[i], labelled by the smallest node on their cycle.

    Every node has one out-edge, so each component holds exactly one cycle; pointer
    doubling finds, in log2(n) vectorised rounds, a cycle node for every node and the
    smallest index on every cycle (no sparse graph is built).
    """
    n = len(dest)
    rounds = max(1, int(np.ceil(np.log2(max(n, 2)))))
    on_cycle = dest.copy()
    low = np.arange(n)
    step = dest.copy()
    for _ in range(rounds):
        on_cycle = on_cycle[on_cycle]  # after 2^rounds >= n hops every node is on its cycle
        low = np.minimum(low, low[step])  # min over the next 2^r nodes of each walk
        step = step[step]
    return low[on_cycle]


def _by_first_appearance(labels: np.ndarray) -> np.ndarray:
    """Renumber (any integer) labels 0..K-1 in the order they first appear."""
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    return np.argsort(np.argsort(first))[inverse]


def _normalize_columns(m: np.ndarray, mult: np.ndarray) -> np.ndarray:
    s = mult @ m
    return m / np.where(s > 0, s, 1.0)


def markov_cluster(
    x: np.ndarray,
    *,
    expansion: int = 2,
    inflation: float = 1.15,
    prune: float = 0.6,
    max_iters: int = 100,
    stable_iters: int | None = 5,
    multiplicity: np.ndarray | None = None,
    prune_total: float | None = None,
    dtype: type = np.float64,
    factor: np.ndarray | None = None,
    block_fn=None,
) -> tuple[np.ndarray, int]:
    """Markov clustering of a symmetric non-negative similarity matrix.

    Args:
        x: (m, m) similarity (e.g. :func:`normalized_similarity`); its diagonal is set to 1
            (unit self-loops).
        expansion: e, the matrix power per iteration.
        inflation: r, the element-wise power per iteration.
        prune: entries below ``prune / M`` are zeroed (M = ``prune_total``, by default the
            total multiplicity).
        max_iters: iteration cap.
        stable_iters: stop once the labels are unchanged for this many iterations (MCL at
            low inflation converges slowly while its clusters settle early); ``None`` runs
            every block until its iterate is idempotent (the reference computation).
        multiplicity: (m,) positive integers, how many identical nodes each row stands for.
        prune_total: M of the pruning threshold, when ``x`` is one block of a larger problem.
        dtype: float type of the iterate (float32 halves the cost of each product).
        factor: optional (m, C) B^ with unit rows and ``x = B^ B^T``: the first expansion
            (with expansion 2) is then computed through it, in m^2 C instead of m^3
            operations, since X D X = B^ (B^T D B^) B^T.
        block_fn: optional replacement of the per-block MCL with the signature of ``_mcl_block``
            (e.g. :meth:`motionbits.torch_ops.TorchOps.mcl_block`).

    Returns:
        (labels (m,) int64 in 0..K-1 numbered by first appearance, largest iteration count
        of any block).
    """
    size = x.shape[0]
    if size == 0:
        return np.zeros(0, np.int64), 0
    mult = np.ones(size) if multiplicity is None else np.asarray(multiplicity, np.float64)
    threshold = prune / (mult.sum() if prune_total is None else prune_total)
    if np.all(x != 0):  # the usual case for one graph component: a single block
        n_blocks, block = 1, np.zeros(size, np.int64)
    else:
        n_blocks, block = connected_components(coo_matrix(x != 0), directed=False)
    labels = np.zeros(size, np.int64)
    offset = 0
    iters = 0
    for b in range(n_blocks):
        idx = np.flatnonzero(block == b)
        sub = x if n_blocks == 1 else x[np.ix_(idx, idx)]
        fac = None if factor is None else factor[idx]
        lab, it = (block_fn or _mcl_block)(sub, mult[idx], expansion, inflation, threshold,
                                           max_iters, stable_iters, dtype, fac)
        labels[idx] = lab + offset
        offset += int(lab.max()) + 1
        iters = max(iters, it)
    return _by_first_appearance(labels), iters


def _mcl_block(x, mult, expansion, inflation, threshold, max_iters, stable_iters, dtype,
               factor=None):
    if x.shape[0] == 1:
        return np.zeros(1, np.int64), 0
    m = np.array(x, dtype=dtype, copy=True)
    mult = mult.astype(dtype)
    unit = bool(np.all(mult == 1))
    np.fill_diagonal(m, 1.0)
    col_sums = mult @ m
    inv_sums = 1.0 / np.where(col_sums > 0, col_sums, 1.0)
    m *= inv_sums
    tol = 1e-9 if np.dtype(dtype) == np.float64 else 1e-6
    dest = np.argmax(m, axis=0)
    labels = _attractors(dest)
    same = 0
    it = 0
    for it in range(1, max_iters + 1):
        prev = m
        if it == 1 and factor is not None and expansion == 2:
            # M = X S^-1 (S: column sums) -> M Dmult M = B^ (B^T (Dmult S^-1) B^) B^T S^-1
            f = factor.astype(dtype)
            inner = f.T @ (f * (mult * inv_sums)[:, None])
            m = (f @ inner) @ (f.T * inv_sums)
        else:
            for _ in range(expansion - 1):
                live = m.any(axis=1)
                if live.all():
                    m = (m if unit else m * mult) @ m
                else:
                    rows = np.flatnonzero(live)
                    nxt = np.zeros_like(m)
                    nxt[rows] = (m[np.ix_(rows, rows)] * mult[rows]) @ m[rows]
                    m = nxt
        np.power(m, inflation, out=m)
        m = _normalize_columns(m, mult)
        if threshold > 0:
            m[m < threshold] = 0.0
            m = _normalize_columns(m, mult)
        if stable_iters is None:  # the reference: iterate until idempotent
            if np.abs(m - prev).max() <= tol:
                break
        else:
            # the labels are a function of each column's argmax: unchanged argmax, same labels
            new_dest = np.argmax(m, axis=0)
            if np.array_equal(new_dest, dest):
                same += 1
            else:
                new = _attractors(new_dest)
                same = same + 1 if np.array_equal(new, labels) else 0
                labels, dest = new, new_dest
            if same >= stable_iters:
                break
    return (attractor_labels(m) if stable_iters is None else labels), it


def markov_cluster_coarse(
    bh: np.ndarray, cells: np.ndarray, max_items: int, **mcl_options
) -> tuple[np.ndarray, int]:
    """MCL of X = B^ B^T through fewer items (the fast path's bound on the cubic cost of
    dense MCL on a large block).

    Neighbouring grid nodes inside one body carry nearly the same embedding, and identical
    nodes can be clustered once with their multiplicity (:func:`markov_cluster`). So an
    item is the set of nodes of one f x f square of grid cells whose embeddings peak at
    the same seed (a square that straddles two bodies splits along them, since each body
    is painted by its own seeds); it enters MCL as its members' mean direction with their
    number as multiplicity, and every member takes its cluster. f grows from 2 until at
    most ``max_items`` items remain (or stops helping). With ``len(bh) <= max_items`` this
    is :func:`markov_cluster` on all nodes.

    Args:
        bh: (m, C) row-normalised embedding.
        cells: (m, 2) int grid (row, column) of each node.
        max_items: the most items MCL should run on.
        **mcl_options: passed to :func:`markov_cluster` (not ``multiplicity`` or ``factor``).

    Returns:
        (labels (m,) int64 0..K-1 by first appearance, iterations).
    """
    m = bh.shape[0]
    if m <= max_items:
        return markov_cluster(bh @ bh.T, factor=bh, **mcl_options)
    peak = np.argmax(bh, axis=1)
    best = None
    for f in range(2, 9):
        square = (cells[:, 0] // f) * (int(cells[:, 1].max()) // f + 1) + cells[:, 1] // f
        _, item = np.unique(square * bh.shape[1] + peak, return_inverse=True)
        n_items = int(item.max()) + 1
        if best is None or n_items < best[0]:
            best = (n_items, item)
        if n_items <= max_items:
            break
    n_items, item = best
    size = np.bincount(item, minlength=n_items).astype(np.float64)
    rep = normalize_rows(_group_sums(item, bh))
    lab, iters = markov_cluster(rep @ rep.T, factor=rep, multiplicity=size, **mcl_options)
    return _by_first_appearance(lab[item]), iters


def _group_sums(group: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(G, C) sums of the (m, C) ``rows`` over each of the G groups numbered in ``group``
    (every group 0..G-1 present; each summed in row order)."""
    order = np.argsort(group, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(group[order]) != 0])
    return np.add.reduceat(rows[order], starts, axis=0)


def cluster_components(b: np.ndarray, w, comp: np.ndarray, n_seeds: np.ndarray,
                       nodes: np.ndarray, n_nodes: int, cols: int, *, max_items: int | None,
                       expansion: int, inflation: float, prune: float, max_iters: int,
                       stable_iters: int | None, dtype: type, block_fn=None) -> np.ndarray:
    """Cluster index of every grid node: :func:`cluster_component` on each connected
    component of the graph, clusters numbered on from those of the components before.

    Args:
        b: (m, C) soft label embedding of the m graph nodes; a component's seeds are its
            first columns (seeds numbered within their component).
        w: (m, m) sparse graph.
        comp: (m,) int connected component of each graph node.
        n_seeds: (n_comp,) int seeds of each component.
        nodes: (m,) int grid node of each graph node.
        n_nodes: grid nodes in all.
        cols: columns of the node grid (row-major node numbering).
        max_items, expansion, inflation, prune, max_iters, stable_iters, dtype, block_fn:
            as in :func:`cluster_component`.

    Returns:
        (n_nodes,) int64; 0 = not in the graph, clusters 1..K.
    """
    painted_total = int((b.sum(axis=1) > 0).sum())
    node_cluster = np.zeros(n_nodes, np.int64)
    n_comp = len(n_seeds)
    members_of = np.split(np.argsort(comp, kind="stable"),
                          np.cumsum(np.bincount(comp, minlength=n_comp))[:-1]) if n_comp else []
    top = 0  # clusters numbered so far
    for c, members in enumerate(members_of):
        if n_seeds[c] == 0:  # no paint reached it: connected, so one group
            node_cluster[nodes[members]] = top = top + 1
            continue
        cluster = cluster_component(
            b[members, :n_seeds[c]], w, members, nodes[members], painted_total, cols,
            max_items=max_items, expansion=expansion, inflation=inflation, prune=prune,
            max_iters=max_iters, stable_iters=stable_iters, dtype=dtype, block_fn=block_fn)
        node_cluster[nodes[members]] = cluster + top
        top += int(cluster.max())
    return node_cluster


def cluster_component(b: np.ndarray, w, members: np.ndarray, nodes: np.ndarray,
                      painted_total: int, cols: int, *, max_items: int | None, expansion: int,
                      inflation: float, prune: float, max_iters: int,
                      stable_iters: int | None, dtype: type, block_fn=None) -> np.ndarray:
    """Cluster indices 1..K of the nodes of one connected component of a graph.

    MCL (:func:`markov_cluster_coarse`) on the rows of ``b`` that received paint, pruning
    relative to ``painted_total`` (the painted nodes of the whole frame); nodes that no
    seed reached are grouped by graph connectivity.

    Args:
        b: (m, C) soft label embedding of the component's m nodes.
        w: (M, M) sparse graph of the whole frame.
        members: (m,) int rows of ``w`` of the component's nodes.
        nodes: (m,) int grid node of each of them.
        painted_total: painted nodes of the whole frame.
        cols: columns of the node grid (row-major node numbering).
        max_items: MCL runs on at most this many representatives; ``None`` = on every node
            (the reference computation).
        expansion, inflation, prune, max_iters, stable_iters, dtype, block_fn: passed to
            :func:`markov_cluster`.

    Returns:
        (m,) int64 cluster indices 1..K.
    """
    m = b.shape[0]
    out = np.zeros(m, np.int64)
    if m == 0:
        return out
    painted = b.sum(axis=1) > 0
    if painted.any():
        bh = normalize_rows(b[painted])
        node = nodes[painted]
        lab, _ = markov_cluster_coarse(
            bh, np.stack([node // cols, node % cols], axis=1),
            len(bh) if max_items is None else max_items, expansion=expansion,
            inflation=inflation, prune=prune, max_iters=max_iters, stable_iters=stable_iters,
            prune_total=painted_total, dtype=dtype, block_fn=block_fn)
        out[painted] = lab + 1
    if not painted.any():  # a component without seeds: connected, so one group
        out[:] = 1
    elif not painted.all():
        rest = members[~painted]
        sub = w[rest][:, rest]
        _, comp = connected_components(sub, directed=False)
        out[~painted] = out.max() + 1 + comp
    return out
