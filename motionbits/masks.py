"""Pixel-resolution MotionBit masks from node clusters (paper Sec. 5.2, last step).

The paper prompts SAM2 with each cluster. The weight-free default here: every cluster gets
one rigid motion fitted to its nodes; each pixel near a cluster takes the label whose
motion best explains the pixel's own backward flow -- the static background and last
frame's label compete too, the latter with a small credit so that a body that stops keeps
its mask -- and specks are removed.
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.nodes import NodeGrid
from motionbits.twists import kabsch_2d

__all__ = ["fit_cluster_motions", "assign_pixels", "remove_specks"]


def fit_cluster_motions(points: np.ndarray, back_points: np.ndarray, weights: np.ndarray,
                        node_labels: np.ndarray, labels: np.ndarray, inlier_threshold: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """One rigid backward motion q ~ R p + t per label, robust to a few stray nodes.

    Args:
        points, back_points: (n, 2) node positions and their backward-flow targets.
        weights: (n,) flow reliability of each node.
        node_labels: (n,) label of each node (0 = none).
        labels: (K,) the labels to fit.
        inlier_threshold: px; the refit keeps nodes within 3x this residual.

    Returns:
        theta (K,), t (K, 2) of the backward motion (current -> previous) of each label.
    """
    thetas = np.zeros(len(labels))
    trans = np.zeros((len(labels), 2))
    for i, lab in enumerate(labels):
        sel = node_labels == lab
        p = points[sel].astype(np.float64)
        q = back_points[sel].astype(np.float64)
        w = weights[sel].astype(np.float64) + 1e-6
        th, t = kabsch_2d(p, q, w)
        for _ in range(2):
            c, s = np.cos(th), np.sin(th)
            pred = p @ np.array([[c, s], [-s, c]]) + t
            r = np.linalg.norm(pred - q, axis=1)
            cut = max(3.0 * inlier_threshold, float(np.median(r)) * 3.0)
            th, t = kabsch_2d(p, q, w * (r < cut))
        thetas[i], trans[i] = th, t
    return thetas, trans


def _dilated_support(grid: NodeGrid, node_labels: np.ndarray, label: int) -> np.ndarray:
    m = (node_labels == label).reshape(grid.rows, grid.cols).astype(np.uint8)
    m = cv2.dilate(m, np.ones((3, 3), np.uint8))
    return cv2.resize(m, (grid.width, grid.height), interpolation=cv2.INTER_NEAREST) > 0


def assign_pixels(grid: NodeGrid, node_labels: np.ndarray, labels: np.ndarray, thetas: np.ndarray,
                  trans: np.ndarray, flow_back: np.ndarray, prior: np.ndarray,
                  prior_valid: np.ndarray, bonus: float, kept: np.ndarray,
                  ambiguous: float) -> np.ndarray:
    """Label every pixel by the motion that best explains its flow.

    Args:
        grid: the node grid (its image size is the working resolution).
        node_labels: (n,) id of each node's cluster (0 = none).
        labels: (K,) ids of the clusters, with backward motions ``thetas`` (K,), ``trans``
            (K, 2).
        flow_back: (H, W, 2) flow current -> previous.
        prior: (H, W) int32 last frame's label map carried to this frame.
        prior_valid: (H, W) bool, where ``prior`` is trustworthy (consistent flow).
        bonus: px of residual credited to the prior's label.
        kept: ids of earlier MotionBits without a cluster now (e.g. bodies that stopped);
            they compete with the static motion on their prior pixels.
        ambiguous: px; where a cluster's motion moves a pixel less than this, flow cannot
            tell it from the background (e.g. near a centre of rotation) and the node-level
            cluster label gets the same credit as the prior.

    Returns:
        (H, W) int32 label map.
    """
    h, w = flow_back.shape[:2]
    credit = np.where(prior_valid, bonus, 0.0).astype(np.float32)
    static_cost = np.linalg.norm(flow_back, axis=-1)
    best = static_cost - credit * (prior == 0)
    out = np.zeros((h, w), np.int32)
    node_map = grid.to_image(node_labels.astype(np.int32))
    for lab in kept:
        on = (prior == lab) & prior_valid
        cost = static_cost - credit
        better = on & (cost < best)
        best[better] = cost[better]
        out[better] = lab
    for lab, th, t in zip(labels, thetas, trans):
        ys, xs = np.nonzero(_dilated_support(grid, node_labels, lab))
        c, s = np.cos(th), np.sin(th)
        px = xs.astype(np.float32)
        py = ys.astype(np.float32)
        rx = c * px - s * py + t[0] - (px + flow_back[ys, xs, 0])
        ry = s * px + c * py + t[1] - (py + flow_back[ys, xs, 1])
        still = np.hypot(c * px - s * py + t[0] - px, s * px + c * py + t[1] - py) < ambiguous
        own = ((prior[ys, xs] == lab) & prior_valid[ys, xs]) | (still & (node_map[ys, xs] == lab))
        cost = np.sqrt(rx * rx + ry * ry) - bonus * own
        better = cost < best[ys, xs]
        best[ys[better], xs[better]] = cost[better]
        out[ys[better], xs[better]] = lab
    return out


def remove_specks(label_map: np.ndarray, min_area: int) -> np.ndarray:
    """Zero every connected piece of a label smaller than ``min_area`` px, except the
    largest piece of each label (a small body is still a body)."""
    out = label_map.copy()
    for lab in np.unique(label_map):
        if lab == 0:
            continue
        mask = (label_map == lab).astype(np.uint8)
        n, comp, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        if n <= 2:
            continue
        areas = stats[1:, cv2.CC_STAT_AREA]
        small = np.flatnonzero(areas < min_area) + 1
        small = small[small != np.argmax(areas) + 1]
        if len(small):
            out[np.isin(comp, small)] = 0
    return out
