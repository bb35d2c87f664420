"""MotionBit identities across frames and the incremental temporal state.

The temporal constraints of the paper need every earlier label map carried to the current
frame. Two nodes were together at every earlier frame iff they fall in the same class of
the *meet* (common refinement) of all earlier label partitions, so one integer map of
that meet, carried by the flow and refined by each new label map, holds all the
information at constant memory.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

__all__ = ["refine_history", "match_ids"]


def refine_history(history: np.ndarray, labels: np.ndarray, margin: int = 0) -> np.ndarray:
    """Meet of a history partition with a new label map, compactly renumbered.

    Mask boundaries are uncertain by a few pixels (flow is smooth across motion
    boundaries), and the meet of many maps would turn that uncertainty into a band of
    tiny classes around every body, cutting its edge nodes off for good. So only pixels
    farther than ``margin`` px from a label boundary refine the partition; the others
    take the class of the nearest such interior pixel.

    Args:
        history: (H, W) int class map (0 = background at every earlier frame).
        labels: (H, W) int label map of the new frame (0 = background).
        margin: half-width in px of the uncertain band around label boundaries.

    Returns:
        (H, W) int32 classes; 0 marks pixels background in every map.
    """
    key = history.astype(np.int64) * (int(labels.max()) + 1) + labels.astype(np.int64)
    if margin > 0:
        lab = labels.astype(np.float32)
        box = np.ones((2 * margin + 1, 2 * margin + 1), np.uint8)
        interior = cv2.dilate(lab, box) == cv2.erode(lab, box)
        if interior.any() and not interior.all():
            src = np.where(interior, 0, 1).astype(np.uint8)
            _, nearest = cv2.distanceTransformWithLabels(
                src, cv2.DIST_L2, 3, labelType=cv2.DIST_LABEL_PIXEL)
            interior_flat = np.flatnonzero(interior.ravel())
            key = key.ravel()[interior_flat[nearest.ravel() - 1]].reshape(labels.shape)
    # compact renumbering by rank; class 0 stays "background in every map"
    if key.max() < 4 * key.size:  # a table lookup, without np.unique's sort
        present = np.zeros(int(key.max()) + 1, np.int64)
        present[key.ravel()] = 1
        rank = np.cumsum(present) - (1 if present[0] else 0)
        return rank[key].astype(np.int32)
    uniq, inv = np.unique(key.ravel(), return_inverse=True)
    inv = inv + (0 if uniq[0] == 0 else 1)
    return inv.reshape(labels.shape).astype(np.int32)


def match_ids(cluster_of_node: np.ndarray, prior_of_node: np.ndarray, n_clusters: int,
              min_iou: float) -> dict[int, int]:
    """Give clusters the ids of the earlier MotionBits they overlap most (Hungarian on IoU).

    Args:
        cluster_of_node: (n,) cluster index 1..K per node (0 = none).
        prior_of_node: (n,) earlier MotionBit id per node (0 = none), carried to this frame.
        n_clusters: K.
        min_iou: a match needs at least this node-level IoU.

    Returns:
        cluster index -> earlier id, for the matched clusters only.
    """
    old_ids = np.unique(prior_of_node[prior_of_node > 0])
    if n_clusters == 0 or len(old_ids) == 0:
        return {}
    old_index = np.searchsorted(old_ids, prior_of_node)
    old_index = np.where(prior_of_node > 0, old_index + 1, 0)
    table = np.zeros((n_clusters + 1, len(old_ids) + 1), np.int64)
    np.add.at(table, (cluster_of_node, old_index), 1)
    inter = table[1:, 1:].astype(np.float64)
    size_c = table[1:, :].sum(1, keepdims=True)
    size_o = table[:, 1:].sum(0, keepdims=True)
    iou = inter / np.maximum(size_c + size_o - inter, 1)
    rows, cols = linear_sum_assignment(-iou)
    return {int(r) + 1: int(old_ids[c]) for r, c in zip(rows, cols) if iou[r, c] >= min_iou}
