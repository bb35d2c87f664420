"""Label anchors: always inside their mask, never overlapping, for adversarial shapes."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from somprompt import LabelRegions, NumberAnnotator, mask_anchor, place_labels
from somprompt.anchors import distance_to_edge


def ring(h=80, w=80, cy=40, cx=40, r_out=30, r_in=22):
    yy, xx = np.mgrid[:h, :w]
    d = np.hypot(yy - cy, xx - cx)
    return (d <= r_out) & (d >= r_in)


def c_shape(h=80, w=80):
    m = np.zeros((h, w), bool)
    m[10:70, 10:70] = True
    m[22:58, 22:80] = False  # opening to the right: the centroid falls in the gap
    return m


def boxes_disjoint(boxes):
    for a, b in itertools.combinations(boxes, 2):
        if not (a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]):
            return False
    return True


@pytest.mark.parametrize(
    "name, mask",
    [
        ("ring", ring()),
        ("c_shape", c_shape()),
        ("horizontal 1-px line", np.pad(np.ones((1, 50), bool), ((30, 49), (10, 20)))),
        ("vertical 1-px line", np.pad(np.ones((60, 1), bool), ((10, 10), (33, 46)))),
        ("diagonal 1-px line", np.pad(np.eye(40, dtype=bool), 20)),
        ("single pixel", np.pad(np.ones((1, 1), bool), ((5, 74), (70, 9)))),
        ("touching top-left corner", np.pad(np.ones((12, 30), bool), ((0, 68), (0, 50)))),
        ("full image", np.ones((40, 40), bool)),
        ("1-px line on the border", np.pad(np.ones((1, 80), bool), ((0, 79), (0, 0)))),
    ],
)
def test_anchor_inside_adversarial_masks(name, mask):
    x, y = mask_anchor(mask)
    assert mask[y, x], f"{name}: anchor {x, y} outside the mask"
    # it is a distance maximum
    dt = distance_to_edge(mask)
    assert dt[y, x] == pytest.approx(dt.max())
    # and the placed label keeps its point inside the mask too
    labels = mask.astype(np.int32) * 7
    pl = NumberAnnotator(text_scale=0.4).place(labels)[7]
    assert mask[pl.point[1], pl.point[0]]


def test_centroid_would_be_outside_but_anchor_is_not():
    for m in (ring(), c_shape()):
        ys, xs = np.nonzero(m)
        assert not m[int(round(ys.mean())), int(round(xs.mean()))]  # the trap is real
        x, y = mask_anchor(m)
        assert m[y, x]


def test_anchor_of_line_is_in_its_middle():
    m = np.zeros((20, 100), bool)
    m[10, 20:81] = True
    x, y = mask_anchor(m)
    assert (y, x) == (10, 50)


def test_border_mask_anchor_moves_away_from_border():
    m = np.zeros((50, 50), bool)
    m[:20, :20] = True  # touches top and left border
    x, y = mask_anchor(m)
    assert 8 <= x <= 11 and 8 <= y <= 11


def test_label_box_centred_on_point_when_mask_is_large():
    labels = ring().astype(np.int32)
    pl = NumberAnnotator(text_scale=0.4).place(labels)[1]
    x0, y0, x1, y1 = pl.box
    assert not pl.leader and not pl.overlaps
    assert x0 <= pl.point[0] < x1 and y0 <= pl.point[1] < y1
    assert abs((x0 + x1) / 2 - pl.point[0]) <= 1 and abs((y0 + y1) / 2 - pl.point[1]) <= 1


def grid_of_squares(n_rows, n_cols, size, pitch, shape):
    labels = np.zeros(shape, np.int32)
    k = 0
    for r in range(n_rows):
        for c in range(n_cols):
            k += 1
            y, x = 5 + r * pitch, 5 + c * pitch
            labels[y:y + size, x:x + size] = k
    return labels


def test_64_small_masks_with_room_get_disjoint_labels_on_their_masks():
    labels = grid_of_squares(8, 8, 6, 32, (270, 270))
    placements = NumberAnnotator(text_scale=0.4).place(labels)
    assert len(placements) == 64
    for i, pl in placements.items():
        assert labels[pl.point[1], pl.point[0]] == i
        assert not pl.leader and not pl.overlaps
    assert boxes_disjoint([p.box for p in placements.values()])


def test_crowded_small_masks_labels_move_but_never_overlap():
    # 56 masks of 3x3 px, 7 px apart: far less room than a label box needs
    labels = grid_of_squares(7, 8, 3, 7, (240, 320))
    placements = NumberAnnotator(text_scale=0.4).place(labels)
    assert len(placements) == 56
    assert not any(p.overlaps for p in placements.values())
    assert boxes_disjoint([p.box for p in placements.values()])
    for i, pl in placements.items():
        assert labels[pl.point[1], pl.point[0]] == i
        x0, y0, x1, y1 = pl.box
        on_point = x0 <= pl.point[0] < x1 and y0 <= pl.point[1] < y1
        assert on_point or pl.leader  # either on its mask or linked to it


def test_close_masks_labels_stay_inside_masks_when_possible():
    # two long 12-px bars side by side: both labels fit, on their own masks, no overlap
    labels = np.zeros((100, 100), np.int32)
    labels[10:90, 40:52] = 1
    labels[10:90, 52:64] = 2
    placements = NumberAnnotator(text_scale=0.35, text_padding=1).place(labels)
    for i, pl in placements.items():
        assert labels[pl.point[1], pl.point[0]] == i
        assert not pl.leader
    assert boxes_disjoint([p.box for p in placements.values()])


def test_no_room_anywhere_sets_overlaps_flag_but_points_stay_in_masks():
    labels = np.arange(1, 26, dtype=np.int32).reshape(5, 5).repeat(2, 0).repeat(2, 1)  # 10x10, 25 ids
    placements = NumberAnnotator(text_scale=0.5).place(labels)
    assert len(placements) == 25
    assert any(p.overlaps for p in placements.values())
    for i, pl in placements.items():
        assert labels[pl.point[1], pl.point[0]] == i


def test_prefer_keeps_previous_point_when_still_inside():
    labels = np.zeros((80, 80), np.int32)
    labels[10:70, 10:70] = 3
    ann = NumberAnnotator(text_scale=0.4)
    assert ann.place(labels, prefer={3: (30, 35)})[3].point == (30, 35)
    # a preferred point outside the mask (or near its edge) is ignored
    assert ann.place(labels, prefer={3: (75, 75)})[3].point == ann.place(labels)[3].point
    assert ann.place(labels, prefer={3: (11, 11)})[3].point == ann.place(labels)[3].point


def test_mask_anchor_rejects_bad_input():
    with pytest.raises(ValueError, match="empty"):
        mask_anchor(np.zeros((5, 5), bool))
    with pytest.raises(ValueError, match="H, W"):
        mask_anchor(np.ones((5, 5, 3), bool))


@settings(max_examples=30, deadline=None)
@given(
    st.integers(min_value=8, max_value=60),
    st.integers(min_value=8, max_value=60),
    st.integers(min_value=1, max_value=12),
    st.integers(min_value=0, max_value=2**31 - 1),
)
def test_random_label_maps_points_in_masks_boxes_disjoint_unless_flagged(h, w, k, seed):
    rng = np.random.default_rng(seed)
    labels = np.zeros((h, w), np.int32)
    for i in range(1, k + 1):  # random rectangles and scattered pixels, overwriting each other
        y0, x0 = rng.integers(0, h), rng.integers(0, w)
        labels[y0:y0 + rng.integers(1, h), x0:x0 + rng.integers(1, w)] = i
        labels[rng.integers(0, h, 3), rng.integers(0, w, 3)] = i
    regions = LabelRegions(labels)
    placements = place_labels(regions, {i: (12, 10) for i in regions.ids})
    assert set(placements) == set(regions.ids)
    for i, pl in placements.items():
        assert labels[pl.point[1], pl.point[0]] == i
    free = [p.box for p in placements.values() if not p.overlaps]
    assert boxes_disjoint(free)
