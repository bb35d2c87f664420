"""Hand-computed cases for the MoRiBo-protocol metrics (motionbits.eval)."""

import numpy as np
import pytest

from motionbits.eval import (
    boundary_counts, boundary_map, boundary_tolerance, contingency, evaluate_frame,
    hungarian_match, summarize,
)


def square(shape, y0, x0, size, label=1, out=None):
    out = np.zeros(shape, np.int32) if out is None else out
    out[y0 : y0 + size, x0 : x0 + size] = label
    return out


def test_tolerance_matches_protocol():
    assert boundary_tolerance((480, 640)) == 3
    assert boundary_tolerance((40, 40)) == 1
    assert boundary_tolerance((1080, 1920)) == 7  # 0.003 * 2202.9 = 6.6


def test_boundary_is_seg2bmap_half_pixel_towards_origin():
    lab = square((8, 8), 2, 2, 4)  # rows and columns 2..5
    b = boundary_map(lab)
    expect = np.zeros((8, 8), bool)
    expect[1:6, 1] = expect[1:6, 5] = expect[1, 1:6] = expect[5, 1:6] = True
    np.testing.assert_array_equal(b, expect)  # background pixel on the left/top side
    full = np.ones((5, 5), np.int32)
    assert not boundary_map(full).any()  # the image border is not a boundary
    corner = square((6, 6), 3, 3, 3)  # touches the bottom and right border
    bc = boundary_map(corner)
    assert bc[2, 2:].all() and bc[2:, 2].all() and bc.sum() == 7
    two = np.zeros((4, 6), np.int32)
    two[:, :3], two[:, 3:] = 1, 2  # touching objects: one column of contour at the seam
    b2 = boundary_map(two)
    assert b2[:, 2].all() and b2.sum() == 4
    # Per object, the seam pixel belongs to both boundaries.
    np.testing.assert_array_equal(boundary_counts(two, 2), [4, 4])


def test_boundary_counts_equal_per_object_maps():
    rng = np.random.default_rng(3)
    lab = _blobs(rng, (30, 40), 6)
    lab[0:4, 30:40] = 6  # an object on the image border
    valid = rng.random(lab.shape) > 0.1
    for v in (None, valid):
        want = [boundary_map(lab == k, v).sum() for k in range(1, 7)]
        np.testing.assert_array_equal(boundary_counts(lab, 6, v), want)


def test_perfect_prediction_with_arbitrary_labels():
    gt = square((40, 40), 5, 5, 10, 1)
    square((40, 40), 20, 20, 8, 2, out=gt)
    pred = np.zeros_like(gt)
    pred[gt == 1], pred[gt == 2] = 700, 3  # labels are not 1..K, order swapped
    s = evaluate_frame(pred, gt)
    for arr in (s.iou, s.precision, s.recall, s.f1, s.bprecision, s.brecall, s.bf1):
        np.testing.assert_allclose(arr, 1.0)
    np.testing.assert_array_equal(s.matched_pred, [700, 3])
    assert all(v == 1.0 for v in s.pooled.values())


def test_empty_prediction():
    gt = square((40, 40), 5, 5, 10)
    s = evaluate_frame(np.zeros_like(gt), gt)
    assert s.n_gt == 1 and s.n_pred == 0
    assert s.f1.tolist() == [0.0] and s.iou.tolist() == [0.0] and s.bf1.tolist() == [0.0]
    assert s.pooled["P"] == 1.0 and s.pooled["R"] == 0.0 and s.pooled["F1"] == 0.0
    assert summarize([s])["macro"]["F1"] == 0.0


def test_empty_gt_and_both_empty():
    pred = square((40, 40), 5, 5, 10)
    s = evaluate_frame(pred, np.zeros_like(pred))
    assert s.n_gt == 0 and s.n_pred == 1
    assert s.pooled["P"] == 0.0 and s.pooled["R"] == 1.0 and s.pooled["F1"] == 0.0
    assert np.isnan(summarize([s])["macro"]["F1"])  # no instance to average
    e = evaluate_frame(np.zeros((9, 9), np.int32), np.zeros((9, 9), np.int32))
    assert all(v == 1.0 for v in e.pooled.values())


def test_one_gt_split_in_two():
    gt = square((40, 40), 10, 10, 10)  # 100 px
    pred = np.zeros_like(gt)
    pred[10:20, 10:16] = 1  # 60 px
    pred[10:20, 16:20] = 2  # 40 px
    s = evaluate_frame(pred, gt)
    # Matched to the larger piece: P = 1, R = 0.6, F = 0.75, IoU = 0.6.
    assert s.matched_pred.tolist() == [1]
    np.testing.assert_allclose([s.precision[0], s.recall[0], s.f1[0], s.iou[0]],
                               [1.0, 0.6, 0.75, 0.6])
    # Pooled: tp 60 over 100 predicted and 100 GT pixels.
    np.testing.assert_allclose([s.pooled["P"], s.pooled["R"]], [0.6, 0.6])
    assert s.pooled["pct75"] == 1.0  # F = 0.75 counts (>=)


def test_two_gts_merged():
    gt = np.zeros((40, 40), np.int32)
    gt[10:20, 10:15] = 1  # 50 px
    gt[10:20, 15:25] = 2  # 100 px
    pred = (gt > 0).astype(np.int32) * 9  # 150 px
    s = evaluate_frame(pred, gt)
    # F(1) = 2*(50/150)*1/(1/3+1) = 0.5, F(2) = 2*(2/3)/(5/3) = 0.8: GT 2 gets the match.
    assert s.matched_pred.tolist() == [0, 9]
    np.testing.assert_allclose(s.f1, [0.0, 0.8])
    np.testing.assert_allclose(s.iou, [0.0, 100 / 150])
    m = summarize([s])["macro"]
    np.testing.assert_allclose([m["F1"], m["mIoU"], m["P"], m["R"]], [0.4, 1 / 3, 1 / 3, 0.5])
    np.testing.assert_allclose([s.pooled["P"], s.pooled["R"]], [100 / 150, 100 / 150])


def test_shift_inside_and_outside_tolerance():
    gt = square((40, 40), 10, 10, 10)
    inside = square((40, 40), 10, 11, 10)  # 1 px right, tolerance is 1 px
    s = evaluate_frame(inside, gt)
    np.testing.assert_allclose([s.bprecision[0], s.brecall[0], s.bf1[0]], 1.0)
    np.testing.assert_allclose([s.f1[0], s.iou[0]], [0.9, 90 / 110])
    outside = square((40, 40), 10, 13, 10)  # 3 px right
    s = evaluate_frame(outside, gt)
    # seg2bmap contours are 11x11 outlines (40 px): GT rows/cols 9..19, prediction rows 9..19,
    # cols 12..22. Within 1 px of the GT contour: 9 px of the top row (cols 12..20), 9 of the
    # bottom row and 2 of the left side (rows 10 and 18): 20/40, and symmetrically for recall.
    np.testing.assert_allclose([s.bprecision[0], s.brecall[0], s.bf1[0]], 0.5)
    np.testing.assert_allclose([s.precision[0], s.recall[0], s.iou[0]], [0.7, 0.7, 70 / 130])
    s2 = evaluate_frame(outside, gt, tolerance=3)
    np.testing.assert_allclose(s2.bf1, 1.0)


def test_ignore_mask_removes_pixels_from_both_maps():
    gt = square((40, 40), 10, 10, 10)
    pred = gt.copy()
    pred[25:30, 25:30] = 2  # a false positive ...
    ignore = np.zeros(gt.shape, bool)
    ignore[24:31, 24:31] = True  # ... inside the ignored region
    ignore[10:20, 10:12] = True  # and part of the GT object ignored too
    pred[10:20, 10:12] = 0  # prediction misses the ignored part: no penalty
    s = evaluate_frame(pred, gt, ignore)
    assert s.n_pred == 1
    np.testing.assert_allclose([s.f1[0], s.iou[0]], 1.0)
    np.testing.assert_allclose(s.bf1, 1.0)  # no artificial contour along the ignore edge
    assert s.pooled["P"] == 1.0
    without = evaluate_frame(pred, gt)
    assert without.n_pred == 2 and without.f1[0] < 1.0 and without.pooled["P"] < 1.0


def test_unmatched_prediction_affects_pooled_not_macro():
    gt = square((40, 40), 5, 5, 10)
    pred = gt.copy()
    square((40, 40), 25, 25, 10, 2, out=pred)
    s = evaluate_frame(pred, gt)
    assert summarize([s])["macro"]["F1"] == 1.0
    assert s.pooled["P"] == 0.5 and s.pooled["R"] == 1.0


def test_macro_weights_instances_equally_across_images():
    gt_a = square((40, 40), 5, 5, 10)
    gt_b = square((40, 40), 5, 5, 10)
    square((40, 40), 25, 25, 10, 2, out=gt_b)
    s_a = evaluate_frame(gt_a, gt_a)  # 1 instance, F = 1
    s_b = evaluate_frame(np.zeros_like(gt_b), gt_b)  # 2 instances, F = 0
    out = summarize([s_a, s_b])
    assert out["n_instances"] == 3
    np.testing.assert_allclose(out["macro"]["F1"], 1 / 3)
    np.testing.assert_allclose(out["pooled"]["F1"], 0.5)  # per-image mean


def test_contingency_matches_brute_force():
    rng = np.random.default_rng(0)
    gt = rng.integers(0, 4, (30, 30)) * 3
    pred = rng.integers(0, 5, (30, 30)) + 100 * (rng.random((30, 30)) < 0.1)
    c = contingency(pred, gt)
    for i, g in enumerate(c.gt_ids):
        for j, p in enumerate(c.pred_ids):
            assert c.tp[i, j] == np.sum((gt == g) & (pred == p))
    assert c.gt_sizes.sum() == np.count_nonzero(gt)


def test_hungarian_drops_zero_pairs():
    rows, cols = hungarian_match(np.array([[0.0, 0.0], [0.2, 0.9]]))
    assert rows.tolist() == [1] and cols.tolist() == [1]


def test_bad_input_errors():
    with pytest.raises(ValueError, match="shape"):
        evaluate_frame(np.zeros((5, 6), np.int32), np.zeros((6, 5), np.int32))
    with pytest.raises(TypeError, match="integer"):
        evaluate_frame(np.zeros((5, 5), np.float32), np.zeros((5, 5), np.int32))
    with pytest.raises(ValueError, match="negative"):
        evaluate_frame(-np.ones((5, 5), np.int32), np.zeros((5, 5), np.int32))
    with pytest.raises(ValueError, match="ignore"):
        evaluate_frame(np.zeros((5, 5), np.int32), np.zeros((5, 5), np.int32),
                       np.zeros((4, 4), bool))


def _blobs(rng, shape, n):
    lab = np.zeros(shape, np.int32)
    for k in range(1, n + 1):
        y, x = rng.integers(0, shape[0] - 8), rng.integers(0, shape[1] - 8)
        h, w = rng.integers(4, 16, 2)
        lab[y : y + h, x : x + w] = k
    return lab


@pytest.mark.parametrize("seed", range(5))
def test_label_values_do_not_matter_and_self_match_is_perfect(seed):
    rng = np.random.default_rng(seed)
    gt, pred = _blobs(rng, (48, 64), 5), _blobs(rng, (48, 64), 6)
    perm = rng.permutation(1000)[: pred.max() + 1] + 1
    perm[0] = 0
    a, b = evaluate_frame(pred, gt), evaluate_frame(perm[pred], gt)
    huge = evaluate_frame(np.where(pred > 0, pred + (1 << 21), 0), gt)  # beyond lookup tables
    for other in (b, huge):
        for name in ("iou", "precision", "recall", "f1", "bprecision", "brecall", "bf1"):
            np.testing.assert_allclose(getattr(a, name), getattr(other, name))
        assert a.pooled == pytest.approx(other.pooled)
        assert (a.static_fp_pixels, a.spurious) == (other.static_fp_pixels, other.spurious)
    s = evaluate_frame(gt, gt)
    assert s.f1.size == 0 or (s.f1.min() == 1.0 and s.bf1.min() == 1.0)


@pytest.mark.parametrize("seed", range(3))
def test_boundary_hits_match_euclidean_distance_transform(seed):
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    gt = _blobs(rng, (40, 50), 1)
    pred = np.roll(gt, (int(rng.integers(-3, 4)), int(rng.integers(-3, 4))), axis=(0, 1))
    s = evaluate_frame(pred, gt, tolerance=2)
    bg, bp = boundary_map(gt), boundary_map(pred)
    dist_to_g = ndimage.distance_transform_edt(~bg)
    dist_to_p = ndimage.distance_transform_edt(~bp)
    np.testing.assert_allclose(s.bprecision[0], np.mean(dist_to_g[bp] <= 2))
    np.testing.assert_allclose(s.brecall[0], np.mean(dist_to_p[bg] <= 2))


def test_adjusted_rand_index_hand_computed():
    from motionbits.eval import adjusted_rand_index as ari

    a = np.array([0, 0, 0, 1, 1, 1])
    assert ari(a, a) == 1.0
    assert ari(a, 7 - a) == 1.0  # renumbering does not matter
    # one item moved: pairs 15; n_ij = [[2, 1], [0, 3]] -> index 1 + 3 = 4; a-sums 3 + 3 = 6;
    # b-sums C(2,2) + C(4,2) = 1 + 6 = 7; E = 6 * 7 / 15 = 2.8; top = 6.5 -> (4 - 2.8) / 3.7
    b = np.array([0, 0, 1, 1, 1, 1])
    assert ari(a, b) == pytest.approx(1.2 / 3.7)
    assert ari(np.zeros(5), np.zeros(5)) == 1.0
    assert ari(np.zeros(4), np.arange(4)) == 0.0
    with pytest.raises(ValueError, match="differ in shape"):
        ari(a, b[:4])
