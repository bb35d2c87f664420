"""The speed-ups of the per-frame steps give the same numbers as the plain computations
they replace (whole image, scipy, a search over the neighbour lists)."""

import cv2
import numpy as np
from scipy import ndimage

from motionbits.aperture import flat_regions, half_colour_gradient
from motionbits.boxes import (label_areas, label_boxes, label_pieces, nonzero_box, pieces_holding,
                              run_counts)
from motionbits.flow import nearest_maps, sample_maps, warp_nearest
from motionbits.graph import project_past_max
from motionbits.identity import refine_history
from motionbits.masks import _support_box, static_cost
from motionbits.merging import touching_pairs
from motionbits.nodes import NodeGrid, binary_fill_holes
from motionbits.records import twist_sources
from motionbits.revealed import brightness, light_change


def _blobs(rng, shape=(90, 120), n=4):
    labels = np.zeros(shape, np.int32)
    for k in range(n):
        y, x = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        labels[y:y + rng.integers(2, 30), x:x + rng.integers(2, 30)] = k + 1
    return labels


def test_binary_fill_holes_is_scipys():
    rng = np.random.default_rng(0)
    for density in (0.05, 0.3, 0.6):
        for _ in range(10):
            mask = ndimage.binary_dilation(rng.random((40, 50)) < density / 4, np.ones((3, 3)))
            np.testing.assert_array_equal(binary_fill_holes(mask),
                                          ndimage.binary_fill_holes(mask))
    ring = np.zeros((7, 7), bool)
    ring[1:6, 1:6] = True
    ring[3, 3] = False
    assert binary_fill_holes(ring)[3, 3] and not binary_fill_holes(np.zeros((3, 3), bool)).any()


def test_label_boxes_are_find_objects():
    rng = np.random.default_rng(2)
    maps = [_blobs(rng, n=n) for n in (1, 4, 9) for _ in range(5)]
    maps += [np.zeros((20, 30), np.int32), np.pad(np.ones((1, 1), np.int32), ((19, 0), (29, 0)))]
    # scattered pixels: many runs per row, labels beyond max_label, other dtypes, views
    maps += [(rng.integers(0, 7, (h, w)) * (rng.random((h, w)) < 0.4)).astype(dtype)
             for h, w in ((1, 1), (1, 9), (9, 1), (23, 31)) for dtype in (np.int32, np.uint16)]
    maps += [m[3:15, 5:] for m in maps[:5]]
    for labels in maps:
        for max_label in (0, 2, 12):
            assert label_boxes(labels, max_label) == ndimage.find_objects(labels, max_label)


def test_pieces_holding_keeps_the_8_connected_pieces_with_a_seed():
    mask = np.zeros((8, 10), bool)
    mask[1:3, 1:3] = True  # seeded
    mask[3, 3] = True  # touches it diagonally: the same piece
    mask[5:7, 6:9] = True  # no seed
    seeds = np.zeros_like(mask)
    seeds[1, 1] = seeds[0, 9] = True  # the second seed lies outside the mask
    out = pieces_holding(mask, seeds)
    assert out[1:3, 1:3].all() and out[3, 3] and not out[5:7, 6:9].any()
    assert out.sum() == 5


def test_label_pieces_are_scipys_connected_pieces_of_each_label():
    rng = np.random.default_rng(5)
    maps = [_blobs(rng, n=n) for n in (1, 4, 9) for _ in range(5)]
    maps += [(rng.integers(0, 5, (23, 31)) * (rng.random((23, 31)) < 0.3)).astype(np.int32)]
    eight = np.ones((3, 3), bool)
    for labels in maps:
        for gap in (0, 2):
            seen = []
            for p in label_pieces(labels, gap=gap):
                seen.append(p.label)
                assert p.box == ndimage.find_objects(labels)[p.label - 1]
                np.testing.assert_array_equal(p.mark, labels[p.box] == p.label)
                # (a dilation's pieces do not depend on where its square is anchored)
                joined = (ndimage.binary_dilation(p.mark, np.ones((gap + 1, gap + 1), bool))
                          if gap else p.mark)
                expected, n = ndimage.label(joined, eight)
                expected[~p.mark] = 0
                assert len(p.areas) == n + 1 and p.areas[0] == 0
                # the same pieces, up to their numbering
                pairs = set(zip(p.pieces[p.mark].tolist(), expected[p.mark].tolist()))
                assert len(pairs) == n == len({a for a, _ in pairs})
                np.testing.assert_array_equal(p.areas, np.bincount(p.pieces[p.mark], minlength=n + 1)
                                              * (np.arange(n + 1) > 0))
                assert p.areas[p.largest] == p.areas.max()
            assert seen == [i for i in range(1, labels.max() + 1) if (labels == i).any()]
    some = maps[1]
    present = [int(i) for i in np.unique(some) if i]
    order = present[::-1] + [some.max() + 5]  # in the order asked; a label not present: none
    assert [p.label for p in label_pieces(some, order)] == present[::-1]


def test_label_areas_are_bincount():
    rng = np.random.default_rng(4)
    maps = [_blobs(rng, n=n) for n in (1, 4, 9) for _ in range(5)]
    maps += [np.zeros((20, 30), np.int32), np.pad(np.ones((1, 1), np.int32), ((19, 0), (29, 0)))]
    for labels in maps:
        area = label_areas(labels)
        np.testing.assert_array_equal(area, np.bincount(labels.ravel()))
        assert area.dtype == np.bincount(labels.ravel()).dtype
        rows, cols = nonzero_box(labels)
        assert np.count_nonzero(labels[rows, cols]) == np.count_nonzero(labels)
        values = labels[labels % 3 != 1]  # runs broken up
        for minlength in (0, 1, 20):
            want = np.bincount(values, minlength=minlength)
            got = run_counts(values, minlength)
            assert got.dtype == want.dtype
            np.testing.assert_array_equal(got, want)


def _light_change_along_last_axis(now, then):
    """:func:`light_change` as numpy's reductions along the colour axis compute it."""
    now, then = now.astype(np.float32), then.astype(np.float32)
    sum_now, sum_then = now.sum(axis=-1), then.sum(axis=-1)
    chroma = np.abs(now / (sum_now[..., None] + 1) - then / (sum_then[..., None] + 1))
    return chroma.max(axis=-1), (sum_now + 8) / (sum_then + 8), sum_now, sum_then


def test_light_change_is_the_reduction_along_the_colour_axis():
    rng = np.random.default_rng(5)
    now, then = rng.integers(0, 256, (2, 40, 50, 3), dtype=np.uint8)
    then[:5] = 0  # dark: the +1 and +8 matter
    mask = rng.random((40, 50)) < 0.3
    for a, b in ((now, then), (now[mask], then[mask]), (now[:0], then[:0])):
        for got, want in zip(light_change(a, b), _light_change_along_last_axis(a, b)):
            assert got.dtype == want.dtype and got.shape == want.shape
            np.testing.assert_array_equal(got, want)


def test_flat_regions_from_a_shared_gradient():
    rng = np.random.default_rng(6)
    rgb = cv2.resize(rng.integers(0, 256, (12, 15, 3), dtype=np.uint8), (61, 47),
                     interpolation=cv2.INTER_NEAREST)  # odd sides, flat patches
    half = half_colour_gradient(rgb)
    for max_gradient in (3.0, 6.0):
        for got, want in zip(flat_regions(rgb, max_gradient, half), flat_regions(rgb, max_gradient)):
            np.testing.assert_array_equal(got, want)


def test_flat_regions_stats_box_each_region():
    # trim_flat_background reads the faces on the box of their stats
    rng = np.random.default_rng(7)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(5, 90, 2))
        blocks = rng.integers(0, 256, (rng.integers(2, 9), rng.integers(2, 9), 3), dtype=np.uint8)
        rgb = cv2.resize(blocks, (w, h), interpolation=cv2.INTER_NEAREST)
        _, regions, stats = flat_regions(rgb, 3.0)
        for i, box in enumerate(ndimage.find_objects(regions)):
            if box is not None:
                x, y, bw, bh = stats[i + 1, :4]
                assert y <= box[0].start and box[0].stop <= y + bh
                assert x <= box[1].start and box[1].stop <= x + bw


def test_nearest_maps_remap_as_the_float_maps():
    rng = np.random.default_rng(3)
    values = rng.integers(0, 1000, (30, 40)).astype(np.int32)
    # half-pixel, far out of the image, non-finite: every rounding and border case
    flow = np.round(rng.standard_normal((30, 40, 2)) * 8).astype(np.float32) / 2
    flow[0, :5] = (1e6, -1e6)
    flow[1, :5] = np.inf
    flow[2, :5] = np.nan
    maps = sample_maps(flow)
    np.testing.assert_array_equal(warp_nearest(values, flow, maps=nearest_maps(*maps)),
                                  warp_nearest(values, flow, maps=maps))


def test_edge_slot_finds_each_neighbour_and_nothing_else():
    grid = NodeGrid.build(48, 64, 9, 6)
    rng = np.random.default_rng(1)
    src = rng.integers(0, grid.n, 400)
    dst = np.where(rng.random(400) < 0.5, grid.neighbors[src, rng.integers(0, 6, 400)],
                   rng.integers(0, grid.n, 400))
    slot = grid.edge_slot(src, dst)
    for s, d, t in zip(src, dst, slot):
        where = np.flatnonzero(grid.neighbors[s] == d)
        assert t == (where[0] if len(where) else -1)


def test_project_past_max_equals_the_search_over_neighbour_lists():
    grid = NodeGrid.build(60, 80, 10, 6)
    rng = np.random.default_rng(2)
    past = rng.uniform(size=(2, *grid.neighbors.shape))
    source = np.clip(np.arange(grid.n) + rng.integers(-12, 13, grid.n), 0, grid.n - 1)
    # the definition: the weight of the edge between the two source nodes, 0 if none
    hit = grid.neighbors[source][:, None, :] == source[grid.neighbors][:, :, None]
    expected = np.where(hit, past[:, source, None, :], 0.0).max(axis=-1)
    np.testing.assert_array_equal(project_past_max(past, grid, source), expected)


def _refine_history_whole_image(history, labels, margin):
    key = history.astype(np.int64) * (int(labels.max()) + 1) + labels.astype(np.int64)
    lab = labels.astype(np.float32)
    box = np.ones((2 * margin + 1, 2 * margin + 1), np.uint8)
    interior = cv2.dilate(lab, box) == cv2.erode(lab, box)
    if interior.any() and not interior.all():
        _, nearest = cv2.distanceTransformWithLabels(
            np.where(interior, 0, 1).astype(np.uint8), cv2.DIST_L2, 3,
            labelType=cv2.DIST_LABEL_PIXEL)
        key = key.ravel()[np.flatnonzero(interior.ravel())[nearest.ravel() - 1]]
    _, inv = np.unique(key.ravel(), return_inverse=True)
    return inv.reshape(labels.shape)


def test_refine_history_on_the_labelled_box_equals_the_whole_image():
    rng = np.random.default_rng(3)
    for trial in range(30):
        labels = _blobs(rng, n=int(rng.integers(1, 5)))
        history = rng.integers(0, 3, labels.shape).astype(np.int32)
        margin = int(rng.integers(1, 6))
        got = refine_history(history, labels, margin)
        want = _refine_history_whole_image(history, labels, margin)
        # the same partition (class numbers are a compact renumbering of the same keys)
        pairs = np.unique(np.stack([got.ravel(), want.ravel()]), axis=1)
        assert pairs.shape[1] == len(np.unique(got)) == len(np.unique(want))


def test_touching_pairs_on_the_labelled_box():
    labels = np.zeros((60, 80), np.int32)
    labels[10:20, 10:20], labels[10:20, 22:30], labels[40:50, 60:70] = 1, 2, 3
    assert touching_pairs(labels, reach=3) == {(1, 2)}  # columns 19 and 22
    assert touching_pairs(labels, reach=2) == set()
    assert touching_pairs(np.zeros((5, 5), np.int32), reach=1) == set()
    # ids beyond uint16 (float32 morphology)
    assert touching_pairs(np.where(labels > 0, labels + 70_000, 0), reach=3) == {(70_001, 70_002)}


def test_twist_sources_are_the_largest_members_with_motion():
    node_ids = np.array([0, 1, 1, 2, 2, 2, 3, 4, 4, 4, 4, 5])
    rep = {1: 1, 2: 1, 3: 3, 4: 0, 5: 5}  # 2 joins 1; 4 is not shown
    # 2 has the most nodes of group 1; 5 has no motion this frame (no cluster)
    assert twist_sources(node_ids, np.array([1, 2, 3, 4]), rep) == {1: 2, 3: 3}
    assert twist_sources(node_ids, np.array([1, 3]), rep) == {1: 1, 3: 3}


def test_support_box_is_the_dilated_node_mask_upsampled():
    grid = NodeGrid.build(48, 64, 10, 4)  # 4.8 x 6.4 px cells: uneven pixel rows per node
    rng = np.random.default_rng(6)
    for _ in range(30):
        node_labels = np.where(rng.random(grid.n) < rng.uniform(0, 0.1), 2, 0)
        full = grid.to_image(cv2.dilate((node_labels == 2).reshape(10, 10).astype(np.uint8),
                                        np.ones((3, 3), np.uint8)))
        support = _support_box(grid, node_labels, 2)
        if not full.any():
            assert support is None
            continue
        rows, cols, inside = support
        ys, xs = np.nonzero(full)
        assert (rows, cols) == (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
        np.testing.assert_array_equal(inside, full[rows, cols] > 0)


def test_brightness_is_the_channel_sum_on_images_views_and_pixel_lists():
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, (60, 80, 3), np.uint8)
    for a in (image, image[5:50, 7:71], image[:, :1], image[4:5], image[image[..., 0] > 100]):
        expected = a.astype(np.float32).sum(axis=-1)
        got = brightness(a)
        assert got.dtype == np.float32 and got.shape == a.shape[:-1]
        np.testing.assert_array_equal(got, expected)
    floats = image.astype(np.float32) / 7
    np.testing.assert_array_equal(brightness(floats),
                                  floats[..., 0] + floats[..., 1] + floats[..., 2])


def test_static_cost_weighs_the_flow_by_texture_and_credits_the_background():
    """"Nothing moved" costs a textured pixel the flow's full length, a flat one none of it,
    and a revealed one only its photometric term; the background keeps the prior's credit
    where no carried label, or one its motion never earned, holds the pixel."""
    shape = (20, 40)
    speed = np.full(shape, 5.0, np.float32)
    gradient = np.zeros(shape, np.float32)
    gradient[:, 20:] = 8.0  # the right half textured (over flow_texture)
    still = np.full(shape, 10.0, np.float32)
    revealed = np.zeros(shape, bool)
    revealed[:, 30:] = True
    prior = np.zeros(shape, np.int32)
    prior[:10] = 3  # the top half carried a label ...
    valid = np.ones(shape, bool)
    earned = np.zeros(shape, bool)
    earned[:10, :10] = True  # ... which its motion earned at the top left only
    cost = static_cost(speed, gradient, still, prior, valid, earned, flow_texture=4.0,
                       bonus=0.35, photo_weight=0.1, revealed=revealed)
    np.testing.assert_allclose(cost.cost[:, :20], 1.0)  # flat: the photometric term only
    np.testing.assert_allclose(cost.cost[:, 20:30], 6.0)  # textured: + the flow's 5 px
    np.testing.assert_allclose(cost.cost[:, 30:], 1.0)  # revealed: no flow term
    np.testing.assert_allclose(cost.credit, 0.35)
    np.testing.assert_allclose(cost.best[:10, :10], cost.cost[:10, :10])  # earned: no credit
    np.testing.assert_allclose(cost.best[:10, 10:], cost.cost[:10, 10:] - 0.35)
    np.testing.assert_allclose(cost.best[10:], cost.cost[10:] - 0.35)  # no carried label
