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

__all__ = ["Contingency", "contingency", "overlap_scores"]


@dataclass(frozen=True)
class Contingency:
    """Pixel counts of every (GT object, predicted object) pair of one frame.

    Attributes:
        table: (K + 1, M + 1) int64; ``table[i, j]`` = number of pixels with GT index i and
            predicted index j, index 0 = background. Ignored pixels are not counted.
        gt_ids: (K,) int64 original GT labels of rows 1..K.
        pred_ids: (M,) int64 original predicted labels of columns 1..M.
    """

    table: np.ndarray
    gt_ids: np.ndarray
    pred_ids: np.ndarray

    @property
    def tp(self) -> np.ndarray:
        """(K, M) int64 intersections of objects (background row and column dropped)."""
        return self.table[1:, 1:]

    @property
    def gt_sizes(self) -> np.ndarray:
        """(K,) int64 pixels of each GT object."""
        return self.table[1:, :].sum(axis=1)

    @property
    def pred_sizes(self) -> np.ndarray:
        """(M,) int64 pixels of each predicted object."""
        return self.table[:, 1:].sum(axis=0)


def contingency(pred: np.ndarray, gt: np.ndarray, ignore: np.ndarray | None = None) -> Contingency:
    """Count the pixels of every (GT label, predicted label) pair with one ``np.bincount``.

    Args:
        pred: (H, W) non-negative integer predicted labels (0 = background).
        gt: (H, W) non-negative integer ground-truth labels (0 = background).
        ignore: optional (H, W) bool; True pixels are left out of both maps. An object all of
            whose pixels are ignored does not exist for the evaluation.

    Raises:
        ValueError: shapes differ, or a map is malformed (see ``check_label_map``).
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
        ignore = np.asarray(ignore, dtype=bool)
        if ignore.shape != gt.shape:
            raise ValueError(f"ignore mask shape {ignore.shape} differs from ground truth {gt.shape}")
        keep = ~ignore.ravel()
        p, g = p[keep], g[keep]
    gi, gt_ids = compact_labels(g)
    pj, pred_ids = compact_labels(p)
    k, m = gt_ids.size, pred_ids.size
    table = np.bincount(gi * (m + 1) + pj, minlength=(k + 1) * (m + 1)).reshape(k + 1, m + 1)
    return Contingency(table=table.astype(np.int64), gt_ids=gt_ids, pred_ids=pred_ids)


def overlap_scores(c: Contingency) -> dict[str, np.ndarray]:
    """Precision, recall, F and IoU of every (GT, predicted) object pair.

    Returns:
        dict of (K, M) float64 arrays ``"P"``, ``"R"``, ``"F"``, ``"IoU"`` (formulas in the
        module docstring; all 0 where tp = 0).
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
