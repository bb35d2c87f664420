"""MoRiBo-protocol scores of one frame and their aggregation over a dataset.

Protocol (paper section 6.1; docs/evaluation.md), on the final frame of each video:

1. Every (GT object g, predicted object p) pair gets the overlap F of
   P = tp/|P|, R = tp/|G| (``overlap.py``).
2. Hungarian assignment maximising the total F (``matching.py``); pairs with no common
   pixel are not matches.
3. **Per GT instance** (the paper's numbers): its matched pair gives IoU, P, R, F1 and, on the
   same assignment, Boundary P, R, F1 (``boundary.py``: DAVIS ``seg2bmap`` contours, a disk
   of ``ceil(0.003 * diagonal)`` px). An unmatched GT object scores 0 on everything.
4. **Macro average** ("each instance weighted equally"): the mean of each per-instance number
   over all GT instances of the dataset (or track). F1 is the mean of the per-instance F1,
   not the F1 of the mean P and R. Unmatched *predictions* add no instance and so do not
   lower the macro numbers; they show up in the pooled variant and as *spurious*. A video
   whose GT is empty contributes no instance to the macro average.
5. **Pooled per image** (UOIS/OCID, Xie et al. 2021), averaged over images:
   P = sum of matched tp / all predicted object pixels (unmatched predictions included),
   R = sum of matched tp / all GT object pixels, F1 = 2PR/(P+R); Boundary likewise with
   boundary-pixel hits over all predicted / GT boundary pixels; mIoU = mean IoU of the
   image's GT objects; pct75 = fraction of the image's GT objects with overlap F1 >= 0.75
   (UOIS uses > 0.75). Edge cases as in the UOIS code: no GT and no prediction -> all 1;
   GT but no prediction -> P = BP = 1, everything else 0; prediction but no GT ->
   R = BR = 1, everything else 0.
6. **%75** in the macro block: fraction of all GT instances with overlap F1 >= 0.75.
7. **False positives** of a frame: *static FP* = |static ∩ predicted| / |static|, where
   static = GT background (label 0) not ignored and predicted = any label > 0; *spurious* =
   number of predicted objects that the assignment of step 2 leaves unmatched (matched to
   no GT object, or only with zero overlap). Over a set of frames: ``static_fp`` pools the
   pixels (sum of static FP pixels / sum of static pixels), ``static_fp_scene`` is the mean
   of the per-frame shares (frames without static pixels left out), ``spurious`` the mean
   count per frame.

An optional ignore mask removes pixels from both maps: they count in no tp, |P|, |G| or
static pixel; a predicted object all of whose pixels are ignored does not exist (it is not
spurious); ignored pixels are no boundary pixels and a contour between a kept and an ignored
pixel is dropped in both maps (so the edge of the ignored region creates no artificial
contour). Without an ignore mask the Boundary numbers are those of the DAVIS / UOIS code,
except that a GT object and a prediction with no common pixel are never paired (UOIS's
Munkres may pair leftovers at F = 0, whose boundary hits it then counts).

F1 >= 0.75 is tested with a 1e-9 slack so that an exact 3/4 (e.g. P = 1, R = 0.6) counts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterable

import numpy as np
from scipy import ndimage

from motionbits.eval.boundary import (
    boundary_counts, boundary_map, boundary_tolerance, disk, pair_boundary_hits,
)
from motionbits.eval.matching import sparse_hungarian_match
from motionbits.eval.overlap import contingency, pair_scores
from motionbits.frames import whole_number

__all__ = ["FrameScores", "evaluate_frame", "summarize", "METRIC_KEYS", "INSTANCE_KEYS", "FP_KEYS"]

#: Keys of a summary block, in the paper's Table 2 column order (plus %75).
METRIC_KEYS = ("P", "R", "F1", "mIoU", "BP", "BR", "BF1", "pct75")
#: Keys of the false-positive block (see the module docstring, step 7).
FP_KEYS = ("static_fp", "static_fp_scene", "spurious")
#: Label maps with labels below this are indexed with a lookup table, larger ones by a sort.
_LUT_MAX = 1 << 20
#: Overlap F1 threshold of the %75 figure.
F75 = 0.75
#: Per-instance arrays of :class:`FrameScores` behind the macro keys.
INSTANCE_KEYS = {"P": "precision", "R": "recall", "F1": "f1", "mIoU": "iou",
                 "BP": "bprecision", "BR": "brecall", "BF1": "bf1"}


def _f1(p: np.ndarray | float, r: np.ndarray | float) -> np.ndarray:
    p, r = np.asarray(p, np.float64), np.asarray(r, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(p + r > 0, 2 * p * r / (p + r), 0.0)


@dataclass
class FrameScores:
    """Scores of one (prediction, GT) pair of label maps.

    Per-instance arrays have shape (K,) float64, one entry per GT object in ``gt_ids`` order;
    unmatched GT objects have 0 everywhere and ``matched_pred`` 0. ``static_pixels`` counts
    the non-ignored GT background pixels, ``static_fp_pixels`` those of them carrying a
    predicted label, ``spurious`` the predicted objects left unmatched.
    """

    gt_ids: np.ndarray
    pred_ids: np.ndarray
    matched_pred: np.ndarray
    iou: np.ndarray
    precision: np.ndarray
    recall: np.ndarray
    f1: np.ndarray
    bprecision: np.ndarray
    brecall: np.ndarray
    bf1: np.ndarray
    pooled: dict[str, float] = field(default_factory=dict)
    static_pixels: int = 0
    static_fp_pixels: int = 0
    spurious: int = 0

    @property
    def n_gt(self) -> int:
        return int(self.gt_ids.size)

    @property
    def n_pred(self) -> int:
        return int(self.pred_ids.size)

    @property
    def static_fp(self) -> float:
        """Share of static (non-ignored GT background) pixels carrying a predicted label;
        NaN when the frame has no static pixel."""
        return self.static_fp_pixels / self.static_pixels if self.static_pixels else float("nan")

    def macro(self) -> dict[str, float]:
        """Macro block of this frame alone (mean over its GT instances; NaN if none)."""
        return summarize([self])["macro"]

    def to_dict(self) -> dict:
        """JSON-ready summary: counts, this frame's macro, pooled and false-positive blocks,
        per instance."""
        return {
            "n_gt": self.n_gt,
            "n_pred": self.n_pred,
            "macro": self.macro(),
            "pooled": dict(self.pooled),
            "false_positives": {"static_fp": self.static_fp, "spurious": self.spurious,
                                "static_pixels": self.static_pixels,
                                "static_fp_pixels": self.static_fp_pixels},
            "instances": [
                {"gt": int(g), "pred": int(p), "P": float(a), "R": float(b), "F1": float(c),
                 "IoU": float(d), "BP": float(e), "BR": float(f), "BF1": float(h)}
                for g, p, a, b, c, d, e, f, h in zip(
                    self.gt_ids, self.matched_pred, self.precision, self.recall, self.f1,
                    self.iou, self.bprecision, self.brecall, self.bf1)
            ],
        }


def _pooled_edge_case(k: int, m: int) -> dict[str, float] | None:
    if k == 0 and m == 0:
        return {key: 1.0 for key in METRIC_KEYS}
    if m == 0:
        out = {key: 0.0 for key in METRIC_KEYS}
        out["P"] = out["BP"] = 1.0
        return out
    if k == 0:
        out = {key: 0.0 for key in METRIC_KEYS}
        out["R"] = out["BR"] = 1.0
        return out
    return None


def evaluate_frame(
    pred: np.ndarray,
    gt: np.ndarray,
    ignore: np.ndarray | None = None,
    *,
    tolerance: int | None = None,
) -> FrameScores:
    """Score a predicted label map against the ground truth (formulas: module docstring).

    Args:
        pred: (H, W) non-negative integer predicted labels, 0 = background; any label values.
        gt: (H, W) non-negative integer GT labels, 0 = background; any label values.
        ignore: optional (H, W) bool, True = pixel left out of both maps.
        tolerance: boundary match tolerance in px, a whole number >= 0 (one beyond the
            image's diagonal matches as the diagonal does); default ``ceil(0.003 * diagonal)``.

    Returns:
        :class:`FrameScores` with per-GT-instance arrays and the pooled block.

    Raises:
        ValueError / TypeError: shapes differ or a map is malformed.
    """
    if tolerance is not None:
        tolerance = whole_number("tolerance", tolerance)  # 1.5 and True were read as 1
        if tolerance < 0:  # else numpy's "negative dimensions are not allowed"
            raise ValueError(f"tolerance must be >= 0 px, got {tolerance}")
    c = contingency(pred, gt, ignore)
    pred = np.asarray(pred).astype(np.int64, copy=False)
    gt = np.asarray(gt).astype(np.int64, copy=False)
    k, m = c.gt_ids.size, c.pred_ids.size
    sc = pair_scores(c)  # only pairs that share a pixel: bounded by the image size
    rows, cols = sparse_hungarian_match(k, m, sc["gt"], sc["pred"], sc["F"])
    pair = _pair_index(sc, m, rows, cols)

    zeros = lambda: np.zeros(k, np.float64)  # noqa: E731
    iou, prec, rec, f1, bprec, brec = zeros(), zeros(), zeros(), zeros(), zeros(), zeros()
    matched = np.zeros(k, np.int64)
    iou[rows] = sc["IoU"][pair]
    prec[rows] = sc["P"][pair]
    rec[rows] = sc["R"][pair]
    f1[rows] = sc["F"][pair]
    matched[rows] = c.pred_ids[cols]

    # Boundaries (DAVIS seg2bmap of each object's mask), ignored pixels dropped.
    keep = None if ignore is None else ~np.asarray(ignore, bool)
    g_idx = _index_map(gt, c.gt_ids, keep)
    p_idx = _index_map(pred, c.pred_ids, keep)
    nb_gt = boundary_counts(g_idx, k, keep)
    nb_pred = boundary_counts(p_idx, m, keep)
    # a disk wider than the image's diagonal matches what the diagonal matches (every
    # pixel): the kernel is capped there, not built at any size (10**6 px: 58 TiB)
    tol = (boundary_tolerance(gt.shape) if tolerance is None
           else min(tolerance, math.ceil(math.hypot(*gt.shape[:2]))))
    kernel = disk(tol)
    g_sl = ndimage.find_objects(g_idx.astype(np.int32), max_label=k) if k else []
    p_sl = ndimage.find_objects(p_idx.astype(np.int32), max_label=m) if m else []
    hits_p = np.zeros(len(rows), np.int64)
    hits_r = np.zeros(len(rows), np.int64)
    for n, (r, col) in enumerate(zip(rows, cols)):
        # The window holds both objects plus a margin: their whole boundaries (which reach
        # 1 px up and left of the object) and no foreign contour at the crop's edge.
        win = _union_window(g_sl[r], p_sl[col], 2, gt.shape)
        valid = None if keep is None else keep[win]
        bg = boundary_map(g_idx[win] == r + 1, valid)
        bp = boundary_map(p_idx[win] == col + 1, valid)
        hits_p[n], hits_r[n] = pair_boundary_hits(bg, bp, tol, kernel)
        # DAVIS edge cases: no predicted contour -> BP = 1, no GT contour -> BR = 1.
        bprec[r] = hits_p[n] / nb_pred[col] if nb_pred[col] else 1.0
        brec[r] = hits_r[n] / nb_gt[r] if nb_gt[r] else 1.0
    bf1 = _f1(bprec, brec)

    pooled = _pooled_edge_case(k, m)
    if pooled is None:
        tp = float(sc["tp"][pair].sum())
        p_all = tp / float(c.pred_sizes.sum())
        r_all = tp / float(c.gt_sizes.sum())
        bp_all = hits_p.sum() / nb_pred.sum() if nb_pred.sum() else 1.0
        br_all = hits_r.sum() / nb_gt.sum() if nb_gt.sum() else 1.0
        pooled = {
            "P": p_all, "R": r_all, "F1": float(_f1(p_all, r_all)), "mIoU": float(iou.mean()),
            "BP": float(bp_all), "BR": float(br_all), "BF1": float(_f1(bp_all, br_all)),
            "pct75": float(np.mean(f1 >= F75 - 1e-9)),
        }
    static = c.background_row  # GT background: [unpredicted, predicted objects...]
    return FrameScores(
        gt_ids=c.gt_ids, pred_ids=c.pred_ids, matched_pred=matched, iou=iou, precision=prec,
        recall=rec, f1=f1, bprecision=bprec, brecall=brec, bf1=bf1,
        pooled={key: float(v) for key, v in pooled.items()},
        static_pixels=int(static.sum()), static_fp_pixels=int(static[1:].sum()),
        spurious=int(m - len(rows)),
    )


def _pair_index(sc: dict[str, np.ndarray], m: int, rows: np.ndarray,
                cols: np.ndarray) -> np.ndarray:
    """Positions in ``pair_scores`` arrays (sorted by (gt, pred)) of the pairs (rows, cols)."""
    return np.searchsorted(sc["gt"] * m + sc["pred"], rows * m + cols)


def _index_map(labels: np.ndarray, ids: np.ndarray, keep: np.ndarray | None) -> np.ndarray:
    """(H, W) int64 compact index (1..K for ``ids``, 0 elsewhere and at ignored pixels)."""
    if not ids.size:
        return np.zeros(labels.shape, np.int64)
    top = int(labels.max())
    if top < _LUT_MAX:
        lut = np.zeros(top + 1, np.int64)
        lut[ids] = np.arange(1, ids.size + 1)
        out = lut[labels]
    else:
        pos = np.minimum(np.searchsorted(ids, labels), ids.size - 1)
        out = np.where((ids[pos] == labels) & (labels > 0), pos + 1, 0)
    if keep is not None:
        out[~keep] = 0
    return out


def _union_window(a: tuple[slice, slice] | None, b: tuple[slice, slice] | None, margin: int,
                  shape: tuple[int, int]) -> tuple[slice, slice]:
    boxes = [s for s in (a, b) if s is not None]
    y0 = max(0, min(s[0].start for s in boxes) - margin)
    y1 = min(shape[0], max(s[0].stop for s in boxes) + margin)
    x0 = max(0, min(s[1].start for s in boxes) - margin)
    x1 = min(shape[1], max(s[1].stop for s in boxes) + margin)
    return slice(y0, y1), slice(x0, x1)


def summarize(frames: Iterable[FrameScores]) -> dict:
    """Aggregate frames into the macro (per GT instance) and pooled (per image) blocks.

    Returns:
        ``{"macro": {key: float}, "pooled": {key: float}, "false_positives": {key: float},
        "n_images": int, "n_instances": int}`` with keys ``METRIC_KEYS`` and ``FP_KEYS``;
        fractions in [0, 1] except ``spurious`` (a mean count per image). The macro block is
        NaN when there is no GT instance; the others when there is no image.

    Raises:
        TypeError: an item of ``frames`` is no :class:`FrameScores` (a dict gave an
            AttributeError traceback).
    """
    frames = list(frames)
    bad = next((i for i, f in enumerate(frames) if not isinstance(f, FrameScores)), None)
    if bad is not None:
        raise TypeError(f"frames must be FrameScores of evaluate_frame; frames[{bad}] is "
                        f"{type(frames[bad]).__name__} {frames[bad]!r:.40}")
    n_inst = sum(f.n_gt for f in frames)
    macro: dict[str, float] = {}
    for key, attr in INSTANCE_KEYS.items():
        vals = np.concatenate([getattr(f, attr) for f in frames]) if frames else np.zeros(0)
        macro[key] = float(vals.mean()) if vals.size else float("nan")
    f1s = np.concatenate([f.f1 for f in frames]) if frames else np.zeros(0)
    macro["pct75"] = float(np.mean(f1s >= F75 - 1e-9)) if f1s.size else float("nan")
    pooled = {
        key: (float(np.mean([f.pooled[key] for f in frames])) if frames else float("nan"))
        for key in METRIC_KEYS
    }
    static = sum(f.static_pixels for f in frames)
    shares = [f.static_fp for f in frames if f.static_pixels]
    fp = {
        "static_fp": sum(f.static_fp_pixels for f in frames) / static if static else float("nan"),
        "static_fp_scene": float(np.mean(shares)) if shares else float("nan"),
        "spurious": float(np.mean([f.spurious for f in frames])) if frames else float("nan"),
    }
    return {"macro": macro, "pooled": pooled, "false_positives": fp, "n_images": len(frames),
            "n_instances": n_inst}
