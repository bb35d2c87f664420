"""Boundary maps and tolerant boundary matching (the DAVIS/UOIS Boundary measure).

Boundary of an object: its pixels with at least one 4-neighbour *inside the image* that
carries a different label (a 1-px inner contour). The image border is not a boundary: an
object cut by the frame edge has no contour there. With a ``valid`` mask (the complement of
an ignore mask), only pairs of valid neighbours are compared and only valid pixels are
boundary pixels: a contour against an ignored pixel is unknown and dropped in both maps.

Tolerance: ``tol = ceil(0.003 * image diagonal)`` px (3 px at 480x640, as in the DAVIS and
UOIS code). A boundary pixel of one mask matches if it lies inside the other mask's boundary
dilated by a disk of radius ``tol`` (Euclidean distance <= tol).

For a matched pair (g, p) with boundaries B_g, B_p:

    BP(g, p) = |B_p ∩ dilate(B_g)| / |B_p|     BR(g, p) = |B_g ∩ dilate(B_p)| / |B_g|
    BF(g, p) = 2 BP BR / (BP + BR)
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["boundary_map", "boundary_tolerance", "disk", "pair_boundary_hits"]


def boundary_tolerance(shape: tuple[int, ...], fraction: float = 0.003) -> int:
    """Match tolerance in pixels: ``ceil(fraction * sqrt(H^2 + W^2))`` (3 at 480x640)."""
    h, w = int(shape[0]), int(shape[1])
    return int(math.ceil(fraction * math.hypot(h, w)))


def disk(radius: int) -> np.ndarray:
    """(2r+1, 2r+1) uint8 structuring element: 1 where x^2 + y^2 <= r^2."""
    r = int(radius)
    y, x = np.mgrid[-r : r + 1, -r : r + 1]
    return ((x * x + y * y) <= r * r).astype(np.uint8)


def boundary_map(labels: np.ndarray, valid: np.ndarray | None = None) -> np.ndarray:
    """1-px inner boundaries of all objects of a label map at once.

    Args:
        labels: (H, W) integer labels, 0 = background.
        valid: optional (H, W) bool; False pixels are neither boundary pixels nor compared.

    Returns:
        (H, W) bool: True at object pixels (label > 0) having a 4-neighbour within the image
        with a different label. Each boundary pixel belongs to the boundary of its own label,
        so ``labels[boundary]`` splits it into the per-object boundaries.
    """
    lab = np.asarray(labels)
    edge = np.zeros(lab.shape, dtype=bool)
    diff_v = lab[1:, :] != lab[:-1, :]
    diff_h = lab[:, 1:] != lab[:, :-1]
    if valid is not None:
        valid = np.asarray(valid, dtype=bool)
        diff_v &= valid[1:, :] & valid[:-1, :]
        diff_h &= valid[:, 1:] & valid[:, :-1]
    edge[1:, :] |= diff_v
    edge[:-1, :] |= diff_v
    edge[:, 1:] |= diff_h
    edge[:, :-1] |= diff_h
    edge &= lab > 0
    return edge if valid is None else edge & valid


def pair_boundary_hits(
    b_gt: np.ndarray, b_pred: np.ndarray, tol: int, kernel: np.ndarray | None = None
) -> tuple[int, int]:
    """Tolerant boundary hits of one (GT, predicted) pair.

    Args:
        b_gt: (h, w) bool boundary of the GT object (a crop is fine if it keeps ``tol`` px of
            margin around both boundaries).
        b_pred: (h, w) bool boundary of the predicted object, same frame.
        tol: match tolerance in px.
        kernel: optional ``disk(tol)`` (pass it to avoid rebuilding it).

    Returns:
        ``(precision_hits, recall_hits)``: |B_p ∩ dilate(B_g)| and |B_g ∩ dilate(B_p)|.
    """
    if kernel is None:
        kernel = disk(tol)
    dil_g = cv2.dilate(b_gt.astype(np.uint8), kernel) > 0
    dil_p = cv2.dilate(b_pred.astype(np.uint8), kernel) > 0
    return int(np.count_nonzero(b_pred & dil_g)), int(np.count_nonzero(b_gt & dil_p))
