"""Unit tests of the pure array functions: twists, graph weights, propagation, MCL, history."""

import numpy as np
import pytest

from motionbits.graph import (
    apply_temporal_constraints,
    inv_sym3,
    local_covariances,
    twist_edge_weights,
    twist_noise_covariance,
)
from motionbits.identity import match_ids, refine_history
from motionbits.eval import adjusted_rand_index
from motionbits.mcl import markov_cluster, markov_cluster_coarse, normalize_rows, normalized_similarity
from motionbits.nodes import NodeGrid, sample_bilinear
from motionbits.propagation import grid_seeds, propagate_labels
from motionbits.graph import symmetric_graph
from motionbits.twists import fit_local_motions, kabsch_2d, se2_exp, se2_log


def _rigid(points, theta, t):
    c, s = np.cos(theta), np.sin(theta)
    return points @ np.array([[c, s], [-s, c]]) + t


def test_se2_log_exp_roundtrip():
    rng = np.random.default_rng(0)
    theta = rng.uniform(-1, 1, 50)
    theta[:5] = 0.0
    t = rng.normal(scale=20, size=(50, 2))
    th2, t2 = se2_exp(se2_log(theta, t))
    np.testing.assert_allclose(th2, theta, atol=1e-12)
    np.testing.assert_allclose(t2, t, atol=1e-9)


def test_kabsch_recovers_motion_and_ignores_zero_weight_outlier():
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 100, size=(8, 2))
    q = _rigid(p, 0.3, np.array([5.0, -2.0]))
    q[0] += 40  # an outlier with zero weight
    w = np.ones(8)
    w[0] = 0
    theta, t = kabsch_2d(p, q, w)
    assert theta == pytest.approx(0.3, abs=1e-9)
    np.testing.assert_allclose(t, [5.0, -2.0], atol=1e-9)


def test_local_twists_equal_on_one_rigid_body_and_robust_to_an_outlier():
    grid = NodeGrid.build(120, 160, 20, 5)
    theta, t = 0.02, np.array([1.5, -0.7])
    back = _rigid(grid.points.astype(np.float64), theta, t)
    back[55] += [3.0, -3.0]  # one bad flow vector
    motions = fit_local_motions(grid.points, back, grid.neighbors, np.ones(grid.n), 0.3)
    expected = -se2_log(np.array(theta), t)
    # every node whose fit rejects the outlier recovers the body's single spatial twist
    ok = ~np.isin(np.arange(grid.n), [55])
    np.testing.assert_allclose(motions.twist[ok], np.broadcast_to(expected, (ok.sum(), 3)),
                               atol=1e-6)
    assert not motions.inliers[55, 0]


def test_mahalanobis_weights_separate_two_motions():
    grid = NodeGrid.build(100, 100, 10, 5)
    twist = np.zeros((grid.n, 3))
    left = grid.points[:, 0] < 50
    twist[left] = [0.0, 2.0, 0.0]  # left half translates, right half is static
    twist += np.random.default_rng(0).normal(scale=0.01, size=twist.shape)
    cov = local_covariances(twist, grid.neighbors,
                            twist_noise_covariance(grid.points, grid.neighbors, 0.1))
    w = twist_edge_weights(twist, grid.neighbors, cov)
    same = left[:, None] == left[grid.neighbors]
    interior = np.array([all(left[j] == left[i] for j in grid.neighbors[i]) for i in range(grid.n)])
    within = w[interior].mean()
    assert within > 0.3
    # boundary nodes have wide covariances (the paper's known leak), but edges across the
    # motion boundary stay much weaker than edges within one motion
    assert w[~same].mean() < within / 3


def test_temporal_constraints_remove_and_add_edges():
    neighbors = np.array([[1], [0], [3], [2]])
    weights = np.array([[0.9], [0.9], [0.1], [0.1]])
    history = np.array([1, 2, 3, 3])  # 0-1 were apart once; 2-3 always together in a body
    past = np.array([[0.5], [0.5], [0.8], [0.8]])
    out = apply_temporal_constraints(weights, neighbors, history, past)
    np.testing.assert_allclose(out.ravel(), [0.0, 0.0, 0.8, 0.8])
    # never-moved nodes (class 0) keep their current weight
    out0 = apply_temporal_constraints(weights, neighbors, np.zeros(4, int), past)
    np.testing.assert_allclose(out0, weights)


def test_propagation_stays_inside_components():
    # two disconnected chains, one seed in each
    w = np.zeros((6, 6))
    for a, b in [(0, 1), (1, 2), (3, 4), (4, 5)]:
        w[a, b] = w[b, a] = 1.0
    import scipy.sparse as sp

    b = propagate_labels(sp.csr_matrix(w), np.array([0, 3]), iters=20, reseed_every=5)
    assert (b[:3, 1] == 0).all() and (b[3:, 0] == 0).all()
    assert (b[:3, 0] > 0).all() and (b[3:, 1] > 0).all()


def test_grid_seeds_density():
    seeds = grid_seeds(100, 100, 5)
    assert len(seeds) == 400  # C = 0.04 n at n = 10,000
    assert len(np.unique(seeds)) == 400


def test_mcl_finds_blocks_and_multiplicity_is_exact():
    rng = np.random.default_rng(0)
    emb = np.zeros((30, 3))
    emb[:10, 0] = 1
    emb[10:22, 1] = 1
    emb[22:, 2] = 1
    emb += rng.uniform(0, 0.05, emb.shape)
    x = normalized_similarity(emb)
    labels, _ = markov_cluster(x)
    assert len(np.unique(labels)) == 3
    assert len(np.unique(labels[:10])) == len(np.unique(labels[10:22])) == 1
    # duplicating rows == multiplicity
    reps = np.array([1, 3, 2] * 10)
    dup = np.repeat(emb, reps, axis=0)
    lab_dup, _ = markov_cluster(normalized_similarity(dup))
    lab_mult, _ = markov_cluster(x, multiplicity=reps)
    np.testing.assert_array_equal(np.repeat(lab_mult, reps), lab_dup)


def test_refine_history_is_the_meet():
    h = np.array([[0, 0, 1, 1]] * 3)
    lab = np.array([[0, 2, 2, 0]] * 3)
    out = refine_history(h, lab)
    assert out[0, 0] == 0  # background in both
    assert len(np.unique(out[0])) == 4


def test_match_ids_hungarian():
    cluster = np.array([1, 1, 1, 2, 2, 0, 3])
    prior = np.array([7, 7, 0, 9, 9, 0, 0])
    assert match_ids(cluster, prior, 3, 0.2) == {1: 7, 2: 9}


def test_sample_bilinear():
    field = np.arange(12, dtype=np.float32).reshape(3, 4, 1)
    out = sample_bilinear(field, np.array([[1.5, 1.0], [0.0, 0.0], [3.0, 2.0]]))
    np.testing.assert_allclose(out[:, 0], [5.5, 0.0, 11.0])


def test_symmetric_graph_induced_subgraph():
    neighbors = np.array([[1], [2], [1]])
    w = symmetric_graph(np.array([[0.5], [0.7], [0.2]]), neighbors, keep=np.array([False, True, True]))
    assert w.shape == (2, 2)
    assert w[0, 1] == w[1, 0] == pytest.approx(0.7)


@pytest.mark.parametrize("size,side", [((480, 640), 100), ((37, 91), 13), ((720, 1280), 50), ((10, 10), 7)])
def test_pixel_nodes_match_nearest_upsampling(size, side):
    grid = NodeGrid.build(size[0], size[1], side, 5)
    ys, xs = grid.pixel_nodes
    expected = ys[:, None] * grid.cols + xs[None, :]
    np.testing.assert_array_equal(grid.to_image(np.arange(grid.n, dtype=np.int32)), expected)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("stable_iters", [2, None])
def test_mcl_fast_variants_match_the_dense_reference(dtype, stable_iters):
    """The low-rank first expansion, float32 and multiplicities give the labels of the
    plain dense computation on an embedding with overlapping, noisy clusters."""
    rng = np.random.default_rng(1)
    centers = np.kron(np.eye(4), np.ones((1, 3)))
    emb = centers[rng.integers(0, 4, 120)] * rng.uniform(0.2, 1, (120, 12))
    emb += rng.uniform(0, 0.05, emb.shape)
    bh = normalize_rows(emb)
    x = bh @ bh.T
    ref, _ = markov_cluster(x, stable_iters=stable_iters)
    fast, _ = markov_cluster(x, stable_iters=stable_iters, dtype=dtype, factor=bh)
    assert len(np.unique(ref)) >= 2
    np.testing.assert_array_equal(fast, ref)
    reps = rng.integers(1, 4, 120)
    lab_dup, _ = markov_cluster(normalized_similarity(np.repeat(emb, reps, axis=0)),
                                stable_iters=stable_iters)
    lab_mult, _ = markov_cluster(x, multiplicity=reps, factor=bh, dtype=dtype,
                                 stable_iters=stable_iters)
    np.testing.assert_array_equal(np.repeat(lab_mult, reps), lab_dup)


def test_inv_sym3_matches_numpy():
    rng = np.random.default_rng(2)
    a = rng.normal(size=(50, 3, 3))
    spd = a @ a.transpose(0, 2, 1) + 0.1 * np.eye(3)
    np.testing.assert_allclose(inv_sym3(spd), np.linalg.inv(spd), rtol=1e-8, atol=1e-10)


def test_mcl_coarse_keeps_bodies_apart_and_is_plain_mcl_when_small():
    """Two bodies on a 40 x 40 grid, each painted by its own seeds with noise: clustering
    through <= 250 items (squares that straddle the boundary are split) gives the two
    bodies, like MCL on all 1,600 nodes."""
    rng = np.random.default_rng(3)
    rows, cols = np.divmod(np.arange(1600), 40)
    left = cols < 17  # a boundary that cuts through 4 x 4 groups
    emb = np.where(left[:, None], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0])
    emb = emb + np.roll(emb, 1, axis=1) * rng.uniform(0.9, 1, (1600, 1)) + rng.uniform(0, 0.01, (1600, 4))
    bh = normalize_rows(emb)
    cells = np.stack([rows, cols], axis=1)
    labels, _ = markov_cluster_coarse(bh, cells, 250)
    assert adjusted_rand_index(labels, left) == 1.0
    plain, _ = markov_cluster(bh @ bh.T)
    np.testing.assert_array_equal(labels, plain)
    small, _ = markov_cluster_coarse(bh[:50], cells[:50], 64)
    plain, _ = markov_cluster(bh[:50] @ bh[:50].T)
    np.testing.assert_array_equal(small, plain)
