"""Pixel overlap between predicted and ground-truth objects: contingency table and scores.

For ground-truth object g and predicted object p (masks G and P, ignored pixels removed):

    tp(g, p) = |G ∩ P|
    precision P(g, p) = tp / |P|        recall R(g, p) = tp / |G|
    F(g, p) = 2 P R / (P + R)           (0 when tp = 0)
    IoU(g, p) = tp / (|G| + |P| - tp)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motionbits.eval.labelmaps import check_label_map, compact_labels

__all__ = ["Contingency", "contingency", "overlap_scores", "pair_scores"]


@dataclass(frozen=True)
class Contingency:
    """Pixel counts of every (GT object, predicted object) pair of one frame, stored
    sparsely: only pairs that share a pixel (at most one per pixel), so the cost is
    bounded by the image size, whatever the number of ids.

    Attributes:
        gt_ids: (K,) int64 original GT labels of indices 1..K.
        pred_ids: (M,) int64 original predicted labels of indices 1..M.
        rows, cols, counts: (nnz,) int64: GT index (0 = background), predicted index
            (0 = background) and pixel count of each pair that occurs. Ignored pixels are
            not counted.
    """

    gt_ids: np.ndarray
    pred_ids: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    counts: np.ndarray

    @property
    def table(self) -> np.ndarray:
        """Dense (K + 1, M + 1) int64 table, index 0 = background (O(K M) memory)."""
        out = np.zeros((self.gt_ids.size + 1, self.pred_ids.size + 1), np.int64)
        out[self.rows, self.cols] = self.counts
        return out

    @property
    def tp(self) -> np.ndarray:
        """Dense (K, M) int64 intersections of objects (background row and column dropped)."""
        return self.table[1:, 1:]

    @property
    def background_row(self) -> np.ndarray:
        """(M + 1,) int64 pixels of GT background per predicted index (0 = background)."""
        bg = self.rows == 0
        return np.bincount(self.cols[bg], self.counts[bg],
                           minlength=self.pred_ids.size + 1).astype(np.int64)

    @property
    def gt_sizes(self) -> np.ndarray:
        """(K,) int64 pixels of each GT object."""
        return np.bincount(self.rows, self.counts, minlength=self.gt_ids.size + 1)[1:].astype(np.int64)

    @property
    def pred_sizes(self) -> np.ndarray:
        """(M,) int64 pixels of each predicted object."""
        return np.bincount(self.cols, self.counts, minlength=self.pred_ids.size + 1)[1:].astype(np.int64)


def contingency(pred: np.ndarray, gt: np.ndarray, ignore: np.ndarray | None = None) -> Contingency:
    """Count the pixels of every (GT label, predicted label) pair that occurs.

    Args:
        pred: (H, W) non-negative integer predicted labels (0 = background).
        gt: (H, W) non-negative integer ground-truth labels (0 = background).
        ignore: optional (H, W) bool; True pixels are left out of both maps. An object all of
            whose pixels are ignored does not exist for the evaluation.

    Raises:
        ValueError: shapes differ, a map is malformed (see ``check_label_map``), or the ignore
            mask holds NaN.
    """
    pred = check_label_map(pred, name="prediction")
    gt = check_label_map(gt, name="ground truth")
    if pred.shape != gt.shape:
        raise ValueError(
            f"prediction shape {pred.shape} differs from ground-truth shape {gt.shape}; "
            "predict at the ground truth's resolution (or resize with nearest-neighbour)"
        )
    p, g = pred.ravel(), gt.ravel()
    if ignore is not None:
        ignore = np.asarray(ignore)
        if ignore.dtype.kind in "fc" and not np.isfinite(ignore).all():  # NaN is True: ignored
            raise ValueError("ignore mask holds NaN or infinite values; it must be bool (True = "
                             "pixel left out) or 0/1")
        ignore = ignore.astype(bool)
        if ignore.shape != gt.shape:
            raise ValueError(f"ignore mask shape {ignore.shape} differs from ground truth {gt.shape}")
        keep = ~ignore.ravel()
        p, g = p[keep], g[keep]
    gi, gt_ids = compact_labels(g)
    pj, pred_ids = compact_labels(p)
    pairs, counts = np.unique(gi * (pred_ids.size + 1) + pj, return_counts=True)
    rows, cols = np.divmod(pairs, pred_ids.size + 1)
    return Contingency(gt_ids=gt_ids, pred_ids=pred_ids, rows=rows.astype(np.int64),
                       cols=cols.astype(np.int64), counts=counts.astype(np.int64))


def pair_scores(c: Contingency) -> dict[str, np.ndarray]:
    """Scores of the object pairs that share a pixel (the only ones that can match).

    Returns:
        dict of (L,) arrays: ``"gt"`` and ``"pred"`` (int64, 0-based object indices),
        ``"tp"`` (int64) and ``"P"``, ``"R"``, ``"F"``, ``"IoU"`` (float64; formulas in the
        module docstring).
    """
    obj = (c.rows > 0) & (c.cols > 0)
    i, j, tp = c.rows[obj] - 1, c.cols[obj] - 1, c.counts[obj]
    gs = c.gt_sizes.astype(np.float64)[i]
    ps = c.pred_sizes.astype(np.float64)[j]
    t = tp.astype(np.float64)
    prec, rec = t / ps, t / gs
    return {"gt": i, "pred": j, "tp": tp, "P": prec, "R": rec, "F": 2 * prec * rec / (prec + rec),
            "IoU": t / (gs + ps - t)}


def overlap_scores(c: Contingency) -> dict[str, np.ndarray]:
    """Precision, recall, F and IoU of every (GT, predicted) object pair.

    Returns:
        dict of dense (K, M) float64 arrays ``"P"``, ``"R"``, ``"F"``, ``"IoU"`` (formulas in
        the module docstring; all 0 where tp = 0). O(K M) memory: for many ids use
        :func:`pair_scores`.
    """
    tp = c.tp.astype(np.float64)
    gs = c.gt_sizes.astype(np.float64)[:, None]
    ps = c.pred_sizes.astype(np.float64)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        prec = np.where(tp > 0, tp / ps, 0.0)
        rec = np.where(tp > 0, tp / gs, 0.0)
        f = np.where(tp > 0, 2 * prec * rec / (prec + rec), 0.0)
        iou = np.where(tp > 0, tp / (gs + ps - tp), 0.0)
    return {"P": prec, "R": rec, "F": f, "IoU": iou}
