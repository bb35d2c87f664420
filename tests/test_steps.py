"""Unit tests of the per-frame step functions that the segmenter calls in order."""

import numpy as np
import pytest
import scipy.sparse as sp

from motionbits.camera import compensate_camera
from motionbits.graph import project_past_max
from motionbits.identity import identify_clusters
from motionbits.mcl import cluster_components
from motionbits.nodes import NodeGrid
from motionbits.propagation import propagate_components
from motionbits.records import (MotionSpans, _area_centroid, build_result, group_map, moving_ids,
                                twist_sources)
from motionbits.retirement import Origin, moved_marks, moved_once, origin_residuals, retire
from motionbits.twists import nodes_to_fit


def test_nodes_to_fit_grows_two_rings_and_keeps_prior_nodes():
    rows = cols = 12
    flow = np.zeros((rows * cols, 2))
    prior = np.zeros(rows * cols, np.int64)
    assert len(nodes_to_fit(flow, prior, (rows, cols), move_threshold=0.6)) == 0
    flow[5 * cols + 5] = (0.4, 0.0)  # above half the threshold
    got = nodes_to_fit(flow, prior, (rows, cols), move_threshold=0.6)
    r, c = np.divmod(got, cols)
    assert len(got) == 25 and r.min() == 3 and r.max() == 7 and c.min() == 3 and c.max() == 7
    flow[5 * cols + 5] = (0.2, 0.0)  # below it: only a node of an earlier MotionBit seeds
    prior[0] = 4
    assert list(nodes_to_fit(flow, prior, (rows, cols), move_threshold=0.6)) == [
        0, 1, 2, cols, cols + 1, cols + 2, 2 * cols, 2 * cols + 1, 2 * cols + 2]


def test_project_past_max_follows_the_nodes():
    grid = NodeGrid.build(60, 60, 6, 4)
    past = np.random.default_rng(0).uniform(size=grid.neighbors.shape)
    still = project_past_max(past, grid, np.arange(grid.n))
    np.testing.assert_array_equal(still, past)
    # every node came from the node one column to its left: an interior node reads the
    # weights of that node's edges (its neighbour lists are the same, shifted)
    src = np.arange(grid.n) - 1
    shifted = project_past_max(past, grid, src)
    i = 2 * grid.cols + 3
    order_i = np.argsort(grid.neighbors[i] - i)
    order_s = np.argsort(grid.neighbors[i - 1] - (i - 1))
    np.testing.assert_array_equal(shifted[i, order_i], past[i - 1, order_s])


def test_propagate_and_cluster_components():
    # two disconnected triangles, each with one seed, and a pair without seeds
    edges = [(0, 1), (1, 2), (0, 2), (3, 4), (4, 5), (3, 5), (6, 7)]
    r, c = zip(*edges)
    w = sp.csr_matrix((np.ones(len(edges)), (r, c)), shape=(8, 8))
    w = w.maximum(w.T).tocsr()
    b, comp, n_seeds = propagate_components(w, np.array([0, 3]), iters=10, reseed_every=5)
    assert b.shape == (8, 1)  # the seeds share the column of their components
    assert list(n_seeds) == [1, 1, 0]
    nodes = np.arange(10, 18)
    cluster = cluster_components(b, w, comp, n_seeds, nodes, 20, 5, max_items=None,
                                 expansion=2, inflation=1.15, prune=0.6, max_iters=100,
                                 stable_iters=None, dtype=np.float64)
    assert cluster.shape == (20,) and not cluster[:10].any() and not cluster[18:].any()
    got = cluster[10:18]
    assert len(set(got[:3])) == len(set(got[3:6])) == len(set(got[6:])) == 1
    assert len({got[0], got[3], got[6]}) == 3


def test_identify_clusters_ids_births_and_tentative():
    rows, cols = 6, 6
    cluster = np.zeros((rows, cols), np.int64)
    cluster[:3, :3] = 1  # continues MotionBit 7
    cluster[3:, 3:] = 2  # new and moving
    cluster[0, 5] = 3  # a single node: noise
    cluster = cluster.ravel()
    prior = np.where(cluster == 1, 7, 0)
    disp = np.where(cluster == 2, 2.0, 0.1)
    calls = []

    def evidence():
        calls.append(1)
        return np.full(rows * cols, 5.0)

    opts = dict(min_nodes=4, match_iou=0.2, move_threshold=0.6, motion_evidence=1.0)
    node_ids, ids, born, next_id = identify_clusters(
        cluster, disp, prior, evidence, (rows, cols), 10, set(), **opts)
    assert list(ids) == [7, 10] and born == {10} and next_id == 11
    assert set(node_ids[cluster == 1]) == {7} and set(node_ids[cluster == 2]) == {10}
    assert node_ids[5] == 0 and len(calls) >= 1
    # a MotionBit born last frame stands only if it moves again with evidence
    _, ids, born, next_id = identify_clusters(
        cluster, disp, prior, evidence, (rows, cols), 11, {7}, **opts)
    assert list(ids) == [11] and born == {11} and next_id == 12
    # without a candidate birth the evidence is never computed
    calls.clear()
    _, ids, born, _ = identify_clusters(cluster, np.zeros(rows * cols), prior, evidence,
                                        (rows, cols), 11, set(), **opts)
    assert list(ids) == [7] and born == set() and not calls
    # a MotionBit born last frame that moves but whose flow explains nothing (a body
    # tumbling in 3D) stands where most of it looks new where it stands, not otherwise
    moving = np.where(cluster == 1, 2.0, disp)
    for novel, kept in ((np.zeros(rows * cols, bool), []), (cluster == 1, [7])):
        _, ids, _, _ = identify_clusters(
            cluster, moving, prior, lambda: np.zeros(rows * cols), (rows, cols), 11, {7},
            novel=lambda: novel, **opts)
        assert [i for i in ids if i == 7] == kept


def test_retire_drops_a_motionbit_whose_pixels_did_not_move():
    rng = np.random.default_rng(1)
    prev = rng.uniform(0, 255, (80, 80)).astype(np.float32)
    labels = np.zeros((80, 80), np.int32)
    labels[30:50, 30:50] = 1
    ids, thetas, trans = np.array([1]), np.zeros(1), np.array([[5.0, 0.0]])
    # the world is static: the claimed 5 px motion does not explain the pixels
    out, origins = retire(labels, {}, ids, thetas, trans, 1, None, prev, prev.copy(), 5.0)
    assert not out.any() and origins == {}
    # the pixels really came from 5 px to the right: kept, with its origin
    moved = np.roll(prev, -5, axis=1)
    out, origins = retire(labels, {}, ids, thetas, trans, 1, None, prev, moved, 5.0)
    np.testing.assert_array_equal(out, labels)
    assert set(origins) == {1}
    # ... and its own motion explains it where the world's does not: it moved
    out, origins = retire(labels, {}, ids, thetas, trans, 1, None, prev, moved, 5.0,
                          explained=12.0)
    assert set(origins) == {1} and origins[1].moved
    # the next frame it stands still: its origin still tells it moved since its birth
    out, origins = retire(labels, origins, np.zeros(0, np.int64), np.zeros(0),
                          np.zeros((0, 2)), 2, None, moved, moved.copy(), 5.0, explained=12.0)
    assert set(origins) == {1} and origins[1].moved
    # a MotionBit whose claimed motion neither the pixels nor the world tell apart (a
    # flat patch) is kept, and not said to have moved; nor one that the world explains
    # hardly worse than the bound (a birth frame with an occluder's edge)
    flat = np.full((80, 80), 100, np.float32)
    out, origins = retire(labels, {}, ids, thetas, trans, 1, None, flat, flat.copy(), 5.0,
                          explained=12.0)
    assert set(origins) == {1} and not origins[1].moved
    faint = flat + np.roll(prev - prev.mean(), -5, axis=1) * 0.1  # texture of ~8 levels
    out, origins = retire(labels, {}, ids, thetas, trans, 1, None, flat + (prev - prev.mean())
                          * 0.1, faint, 5.0, explained=12.0)
    assert set(origins) == {1} and not origins[1].moved


def test_moved_marks_are_those_mostly_held_by_bodies_at_rest_that_moved():
    labels = np.zeros((40, 60), np.int32)
    labels[5:25, 5:25] = 1  # a block nudged, at rest now
    labels[5:25, 30:55] = 2  # an arm that moved and moves now
    labels[28:38, 5:25] = 3  # a static patch
    shown = np.where(labels == 3, 1, labels)  # the patch shown in the block's mark ...
    shown[5:25, 25:30] = 2  # ... and the arm's mark with the table it left
    origins = {i: Origin(np.zeros((40, 60), np.float32), np.eye(3), np.eye(3), moved=i < 3)
               for i in (1, 2, 3)}
    assert moved_marks(shown, labels, origins, moving={2}) == {1}
    assert moved_marks(shown, labels, origins, moving=set()) == {1, 2}
    shown[26:40, :] = 1  # the block's mark, mostly the static table now
    assert moved_marks(shown, labels, origins, moving={2}) == set()


#: A newborn (id 4, rows and columns 30-50 of an 80 x 80 frame) born at the last frame
#: with a 6 px motion (current -> previous: 6 px to the left).
NEWBORN = (slice(30, 50), slice(30, 50))
SIX_LEFT = np.array([[1.0, 0, -6.0], [0, 1.0, 0], [0, 0, 1.0]])


def _moved_once(before: np.ndarray, now: np.ndarray, busy: slice | None) -> set[int]:
    """moved_once on the newborn, with a MotionBit moving over the columns ``busy`` of its
    rows (reach 12 px, margin 5, explained 12 grey levels)."""
    labels = np.zeros((80, 80), np.int32)
    labels[NEWBORN] = 4
    near = np.zeros((80, 80), bool)
    if busy is not None:
        near[NEWBORN[0], busy] = True
    origin = Origin(before, SIX_LEFT, np.eye(3))
    return moved_once({4: origin}, [4], labels, np.ones((80, 80), bool), near, None, now,
                      reach=12, margin=5.0, explained=12.0)


@pytest.mark.parametrize("moved, busy, stands", [
    (True, None, True),            # its one frame of motion explains what stands there now
    (False, None, False),          # nothing moved there: a flicker of the flow
    (True, slice(40, 60), False),  # a MotionBit moves over half of it: a piece left behind
    (True, slice(60, 70), True),   # ... 10 px beside it: its pixels beyond reach (90%) judged
])
def test_moved_once_keeps_a_newborn_whose_one_frame_of_motion_was_real(moved, busy, stands):
    before = np.random.default_rng(2).uniform(0, 255, (80, 80)).astype(np.float32)
    now = np.roll(before, 6, axis=1) if moved else before.copy()  # 6 px to the right
    assert _moved_once(before, now, busy) == ({4} if stands else set())


@pytest.mark.parametrize("busy, stands", [(None, True), (slice(60, 70), False)])
def test_moved_once_beside_a_moving_motionbit_the_world_must_explain_it_clearly_worse(
        busy, stands):
    """A faint texture (the world explains it within 12-24 grey levels): alone it stands;
    beside a moving MotionBit that is not enough (retirement.NEAR_WORLD)."""
    before = np.random.default_rng(2).uniform(100, 140, (80, 80)).astype(np.float32)
    now = np.roll(before, 6, axis=1)
    mask = np.zeros((80, 80), bool)
    mask[NEWBORN] = True
    world, body = origin_residuals(Origin(before, SIX_LEFT, np.eye(3)), now, mask, 2.0)
    assert 12.0 < world < 2 * 12.0 and body < 1.0  # what the case is about
    assert _moved_once(before, now, busy) == ({4} if stands else set())


def test_compensate_camera_removes_a_global_shift():
    grid = NodeGrid.build(64, 64, 16, 5)
    flow = np.zeros((64, 64, 2), np.float32)
    prev = np.zeros((64, 64, 3), np.uint8)
    back = grid.points + 0.0
    off = compensate_camera(grid.points, back, np.ones(grid.n), flow, prev, support=1.0,
                            threshold=1.0, min_shift=0.25)
    assert off[0] is flow and off[1] is prev and off[2] is back and off[3] is None
    flow[...] = (3.0, -2.0)
    back = grid.points + np.array([3.0, -2.0], np.float32)
    flow_m, prev_m, back_m, cam, world, epipole = compensate_camera(
        grid.points, back, np.ones(grid.n), flow, prev, support=0.5, threshold=1.0,
        min_shift=0.25)
    assert cam is not None and prev_m.shape == prev.shape
    assert world is not None  # the static world's map (a pure shift: no parallax)
    assert epipole is None
    assert np.abs(flow_m).max() < 1e-3 and np.abs(back_m - grid.points).max() < 1e-3


def test_moving_ids_spans_and_records():
    grid = NodeGrid.build(40, 40, 4, 4)
    node_ids = np.zeros(grid.n, np.int64)
    node_ids[:4], node_ids[4:8] = 1, 2
    ids, thetas, trans = np.array([1, 2]), np.zeros(2), np.array([[-1.0, 0.0], [0.1, 0.0]])
    moving = moving_ids(grid.points, node_ids, ids, thetas, trans, threshold=0.6)
    assert moving == {1}
    spans = MotionSpans()
    spans.record(moving, 3)
    spans.record(moving, 5)
    assert spans.first == {1: 3} and spans.last == {1: 5}
    labels = np.zeros((40, 40), np.int32)
    labels[:10], labels[10:20] = 1, 2
    rep = {1: 1, 2: 1}
    res = build_result(5, group_map(labels, rep), node_ids, ids, thetas, trans, moving, rep,
                       twist_sources(node_ids, ids, rep), spans, grid, (80, 80))
    assert res.labels.shape == (80, 80) and res.ids == [1]  # 2 merged into 1
    mb = res.motionbits[0]
    assert mb.area == 40 * 80 and mb.moving and (mb.first_moved, mb.last_moved) == (3, 5)
    # the twist of the larger member, forward, in input pixels (2x the working size)
    assert mb.twist == (0.0, 2.0, 0.0)
    assert res.node_labels.shape == (4, 4) and set(res.node_labels.ravel()) == {0, 1}


def test_area_centroid_equals_the_mean_of_the_pixel_coordinates():
    rng = np.random.default_rng(4)
    for _ in range(50):
        mask = rng.random(rng.integers(1, 60, 2)) < rng.random()
        mask[rng.integers(mask.shape[0]), rng.integers(mask.shape[1])] = True
        corner = tuple(int(c) for c in rng.integers(0, 400, 2))
        ys, xs = np.nonzero(mask)
        area, (cx, cy) = _area_centroid(mask, corner)
        # bit-identical to the means of np.nonzero's coordinates (not just close)
        assert (area, cx, cy) == (len(xs), float((xs + corner[1]).mean()),
                                  float((ys + corner[0]).mean()))


def test_project_past_max_projects_stacked_graphs_alike():
    grid = NodeGrid.build(60, 60, 6, 4)
    past = np.random.default_rng(2).uniform(size=(3, *grid.neighbors.shape))
    src = np.roll(np.arange(grid.n), 7)
    stacked = project_past_max(past, grid, src)
    for g in range(3):
        np.testing.assert_array_equal(stacked[g], project_past_max(past[g], grid, src))
