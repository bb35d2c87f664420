"""Boundary scores against the reference DAVIS ``f_measure`` / UOIS boundary measure, and the
false-positive numbers (static FP, spurious), on hand-made label maps.

The reference is re-implemented here from its published description, as plainly as possible
and independently of ``motionbits.eval.boundary`` (no dilation, no shared helper):

* ``seg2bmap`` (BSDS / DAVIS): a pixel of a binary mask is a boundary pixel when its east,
  south or south-east neighbour inside the image has the other value.
* tolerance ``ceil(0.003 * sqrt(H^2 + W^2))`` px (or a number of px when given >= 1); a
  boundary pixel is matched when a boundary pixel of the other mask lies within Euclidean
  distance of the tolerance (DAVIS dilates with ``skimage.morphology.disk``, x^2+y^2 <= r^2).
* precision = matched predicted boundary / predicted boundary, recall likewise; no predicted
  boundary -> P = 1 (R = 0 unless no GT boundary), no GT boundary -> R = 1.
* UOIS pooled Boundary P / R: sum of precision / recall hits over the matched pairs, divided
  by the sum of the boundary sizes of all predicted / all GT objects.
"""

import math

import numpy as np
import pytest
from scipy import ndimage

from motionbits.eval import evaluate_frame, summarize


def ref_seg2bmap(mask):
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    out = np.zeros((h, w), bool)
    for y in range(h):
        for x in range(w):
            for dy, dx in ((0, 1), (1, 0), (1, 1)):
                if y + dy < h and x + dx < w and mask[y + dy, x + dx] != mask[y, x]:
                    out[y, x] = True
    return out


def ref_hits(a, b, tol):
    """Pixels of boundary ``a`` within Euclidean distance ``tol`` of boundary ``b``."""
    if not b.any():
        return 0
    dist = ndimage.distance_transform_edt(~b)
    return int(np.count_nonzero(a & (dist <= tol)))


def ref_f_measure(pred_mask, gt_mask, bound_th=0.003):
    """(precision, recall, F, precision hits, recall hits, |B_pred|, |B_gt|)."""
    tol = bound_th if bound_th >= 1 else math.ceil(bound_th * math.hypot(*gt_mask.shape))
    bp, bg = ref_seg2bmap(pred_mask), ref_seg2bmap(gt_mask)
    n_p, n_g = int(bp.sum()), int(bg.sum())
    hp, hr = ref_hits(bp, bg, tol), ref_hits(bg, bp, tol)
    if n_p == 0 and n_g > 0:
        p, r = 1.0, 0.0
    elif n_p > 0 and n_g == 0:
        p, r = 0.0, 1.0
    elif n_p == 0 and n_g == 0:
        p, r = 1.0, 1.0
    else:
        p, r = hp / n_p, hr / n_g
    f = 0.0 if p + r == 0 else 2 * p * r / (p + r)
    return p, r, f, hp, hr, n_p, n_g


def check_against_reference(pred, gt, bound_th=0.003):
    s = evaluate_frame(pred, gt, tolerance=None if bound_th < 1 else int(bound_th))
    hp_sum = hr_sum = 0
    for i, (g, p) in enumerate(zip(s.gt_ids, s.matched_pred)):
        if p == 0:
            continue
        rp, rr, rf, hp, hr, _, _ = ref_f_measure(pred == p, gt == g, bound_th)
        assert s.bprecision[i] == pytest.approx(rp, abs=1e-12)
        assert s.brecall[i] == pytest.approx(rr, abs=1e-12)
        assert s.bf1[i] == pytest.approx(rf, abs=1e-12)
        hp_sum, hr_sum = hp_sum + hp, hr_sum + hr
    n_pred = sum(ref_seg2bmap(pred == p).sum() for p in s.pred_ids)
    n_gt = sum(ref_seg2bmap(gt == g).sum() for g in s.gt_ids)
    if s.n_pred and s.n_gt:
        assert s.pooled["BP"] == pytest.approx(hp_sum / n_pred, abs=1e-12)
        assert s.pooled["BR"] == pytest.approx(hr_sum / n_gt, abs=1e-12)
    return s


def rect(lab, y, x, h, w, k):
    lab[y : y + h, x : x + w] = k
    return lab


def hand_made_maps():
    """(pred, gt) pairs: touching objects, the image border, thin and 1-px objects, splits."""
    out = []
    gt = rect(rect(np.zeros((30, 40), np.int32), 5, 5, 10, 8, 1), 5, 13, 10, 6, 2)  # touching
    pred = rect(rect(np.zeros_like(gt), 6, 4, 9, 9, 7), 5, 14, 11, 5, 3)
    out.append((pred, gt))
    gt = rect(rect(np.zeros((30, 40), np.int32), 0, 0, 8, 12, 1), 20, 30, 10, 10, 2)  # borders
    pred = rect(rect(np.zeros_like(gt), 0, 1, 9, 10, 1), 22, 29, 8, 11, 2)
    out.append((pred, gt))
    gt = rect(rect(np.zeros((24, 24), np.int32), 3, 3, 1, 15, 1), 12, 12, 1, 1, 2)  # thin, 1 px
    pred = rect(rect(np.zeros_like(gt), 3, 4, 2, 14, 5), 12, 12, 2, 2, 6)
    out.append((pred, gt))
    gt = rect(np.zeros((32, 32), np.int32), 8, 8, 14, 14, 1)  # one body split + a spurious piece
    pred = rect(rect(rect(np.zeros_like(gt), 8, 8, 14, 6, 1), 8, 14, 14, 8, 2), 26, 2, 4, 4, 3)
    out.append((pred, gt))
    rng = np.random.default_rng(0)
    for _ in range(3):
        gt, pred = np.zeros((36, 48), np.int32), np.zeros((36, 48), np.int32)
        for k in range(1, 5):
            y, x = rng.integers(0, 30), rng.integers(0, 42)
            h, w = rng.integers(2, 14, 2)
            rect(gt, y, x, h, w, k)
            rect(pred, y + rng.integers(-2, 3), x + rng.integers(-2, 3), h, w, 10 + k)
        out.append((pred, gt))
    return out


@pytest.mark.parametrize("case", range(7))
@pytest.mark.parametrize("bound_th", [0.003, 1, 2, 3])
def test_boundary_equals_reference_f_measure(case, bound_th):
    pred, gt = hand_made_maps()[case]
    s = check_against_reference(pred, gt, bound_th)
    assert s.n_gt > 0


def test_boundary_equals_reference_at_full_size():
    # 480x640: the default tolerance is ceil(0.003 * 800) = 3 px.
    gt = np.zeros((480, 640), np.int32)
    ys, xs = np.mgrid[:480, :640]
    gt[(ys - 200) ** 2 + (xs - 300) ** 2 < 80**2] = 1
    gt[100:180, 450:600] = 2
    pred = np.zeros_like(gt)
    pred[(ys - 204) ** 2 + (xs - 297) ** 2 < 77**2] = 4
    pred[103:176, 452:605] = 9
    pred[400:430, 10:60] = 5
    s = evaluate_frame(pred, gt)
    for i, (g, p) in enumerate([(1, 4), (2, 9)]):
        bp, bg = pred == p, gt == g
        # seg2bmap of a 480x640 mask, vectorised: pad right/bottom with a copy of the last
        # column/row so that out-of-image neighbours never differ.
        pad_p, pad_g = np.pad(bp, ((0, 1), (0, 1)), mode="edge"), np.pad(bg, ((0, 1), (0, 1)), mode="edge")
        edge_p = (pad_p[:-1, 1:] != bp) | (pad_p[1:, :-1] != bp) | (pad_p[1:, 1:] != bp)
        edge_g = (pad_g[:-1, 1:] != bg) | (pad_g[1:, :-1] != bg) | (pad_g[1:, 1:] != bg)
        prec = ref_hits(edge_p, edge_g, 3) / edge_p.sum()
        rec = ref_hits(edge_g, edge_p, 3) / edge_g.sum()
        assert s.bprecision[i] == pytest.approx(prec, abs=1e-12)
        assert s.brecall[i] == pytest.approx(rec, abs=1e-12)
        assert 0.3 < prec < 1.0 and 0.3 < rec < 1.0  # the case is not trivial


def test_ignore_mask_keeps_its_own_boundary_handling():
    # Without ignored pixels the ignore-aware path is the reference; with them, a contour
    # against ignored pixels is dropped (the reference DAVIS code would count it).
    gt = rect(np.zeros((30, 30), np.int32), 5, 5, 12, 12, 1)
    pred = rect(np.zeros_like(gt), 5, 5, 12, 8, 1)  # misses the right third ...
    ignore = np.zeros(gt.shape, bool)
    ignore[:, 13:] = True  # ... which is ignored
    none = evaluate_frame(pred, gt, np.zeros(gt.shape, bool))
    ref = check_against_reference(pred, gt, 1)
    np.testing.assert_allclose([none.bprecision, none.brecall], [ref.bprecision, ref.brecall])
    assert ref.bf1[0] < 1.0
    s = evaluate_frame(pred, gt, ignore)
    np.testing.assert_allclose([s.bprecision[0], s.brecall[0], s.f1[0]], 1.0)


def test_static_fp_and_spurious_hand_computed():
    gt = rect(rect(np.zeros((40, 40), np.int32), 5, 5, 10, 10, 1), 25, 25, 10, 10, 2)  # 1400 static
    pred = np.zeros_like(gt)
    rect(pred, 5, 5, 10, 12, 3)  # body 1 plus a 20 px halo
    rect(pred, 20, 0, 5, 4, 4)  # a free-standing false MotionBit: 20 px
    rect(pred, 25, 25, 10, 5, 5)  # body 2 in two pieces: one matched, one spurious
    rect(pred, 25, 30, 10, 5, 6)
    s = evaluate_frame(pred, gt)
    assert s.static_pixels == 1400 and s.static_fp_pixels == 40
    assert s.static_fp == pytest.approx(40 / 1400)
    assert s.spurious == 2  # the free MotionBit and the second piece
    d = s.to_dict()["false_positives"]
    assert d["spurious"] == 2 and d["static_fp"] == pytest.approx(40 / 1400)
    # Ignoring the free MotionBit's pixels removes it from both numbers.
    ignore = np.zeros(gt.shape, bool)
    ignore[20:25, 0:4] = True
    s2 = evaluate_frame(pred, gt, ignore)
    assert s2.static_pixels == 1380 and s2.static_fp_pixels == 20 and s2.spurious == 1


def test_zero_overlap_prediction_is_spurious():
    gt = rect(np.zeros((20, 20), np.int32), 2, 2, 5, 5, 1)
    pred = rect(np.zeros_like(gt), 12, 12, 5, 5, 1)  # same label, no common pixel
    s = evaluate_frame(pred, gt)
    assert s.spurious == 1 and s.matched_pred.tolist() == [0]
    empty = evaluate_frame(np.zeros_like(gt), gt)
    assert empty.spurious == 0 and empty.static_fp == 0.0
    full = evaluate_frame(np.ones((4, 4), np.int32), np.ones((4, 4), np.int32))
    assert np.isnan(full.static_fp)  # no static pixel


def test_summarize_pools_static_pixels_and_averages_scenes():
    a = evaluate_frame(rect(np.zeros((10, 10), np.int32), 0, 0, 10, 1, 1), np.zeros((10, 10), np.int32))
    b = evaluate_frame(np.zeros((10, 30), np.int32), np.zeros((10, 30), np.int32))
    assert (a.static_fp, b.static_fp, a.spurious, b.spurious) == (0.1, 0.0, 1, 0)
    fp = summarize([a, b])["false_positives"]
    assert fp["static_fp"] == pytest.approx(10 / 400)  # pooled over pixels
    assert fp["static_fp_scene"] == pytest.approx(0.05)  # mean of per-scene shares
    assert fp["spurious"] == pytest.approx(0.5)
