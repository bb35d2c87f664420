"""Boundary maps and tolerant boundary matching: the DAVIS ``f_measure`` / UOIS Boundary measure.

Boundary map (``seg2bmap`` of the DAVIS and UOIS code, D. Martin's BSDS definition): a pixel
is a boundary pixel of a segmentation if its east, south or south-east neighbour *inside the
image* carries a different label. The contour therefore sits half a pixel towards the
origin: on an object's left and top sides it is the background pixel next to the object, on
its right and bottom sides the object's own pixel. The image border is not a contour.

The boundary of one object k is the ``seg2bmap`` of its binary mask ``labels == k``: the
pixels whose 2x2 block (the pixel and its in-image E, S, SE neighbours) contains k and
another label. A pixel between two objects belongs to both boundaries.

Ignore-aware variant (a ``valid`` mask, the complement of a scene's ``ignore.png``): an
ignored pixel is no boundary pixel, and a neighbour that is ignored is not compared, so a
contour against an ignored region is unknown and dropped in both maps. Without ignored
pixels the two definitions coincide.

Tolerance: ``tol = ceil(0.003 * image diagonal)`` px (3 px at 480x640, as in the UOIS code).
A boundary pixel of one object matches if it lies within Euclidean distance ``tol`` of the
other object's boundary (dilation by the disk ``x^2 + y^2 <= tol^2``, as
``skimage.morphology.disk``). For a matched pair (g, p) with boundaries B_g, B_p:

    BP(g, p) = |B_p ∩ dilate(B_g)| / |B_p|     BR(g, p) = |B_g ∩ dilate(B_p)| / |B_g|
    BF(g, p) = 2 BP BR / (BP + BR)

with the DAVIS edge cases (no B_p: BP = 1; no B_g: BR = 1, so both empty scores 1).
"""

from __future__ import annotations

import math
import numbers

import cv2
import numpy as np

__all__ = ["boundary_map", "boundary_counts", "boundary_tolerance", "disk", "pair_boundary_hits"]


def boundary_tolerance(shape: tuple[int, ...], fraction: float = 0.003) -> int:
    """Match tolerance in pixels: ``ceil(fraction * sqrt(H^2 + W^2))`` (3 at 480x640).

    Raises:
        ValueError: ``fraction`` is not a finite number >= 0 (-0.01 gave a negative tolerance).
    """
    if (isinstance(fraction, bool) or not isinstance(fraction, numbers.Real)
            or not (math.isfinite(fraction) and fraction >= 0)):
        raise ValueError(f"fraction must be a finite number >= 0, got {fraction!r:.40}")
    if len(shape) < 2:  # else IndexError "tuple index out of range"
        raise ValueError(f"shape must be (H, W, ...), got {tuple(shape)!r}")
    h, w = int(shape[0]), int(shape[1])
    return int(math.ceil(fraction * math.hypot(h, w)))


def disk(radius: int) -> np.ndarray:
    """(2r+1, 2r+1) uint8 structuring element: 1 where x^2 + y^2 <= r^2."""
    r = int(radius)
    y, x = np.mgrid[-r : r + 1, -r : r + 1]
    return ((x * x + y * y) <= r * r).astype(np.uint8)


#: (dy, dx) of the neighbours a pixel is compared with: east, south, south-east.
_STEPS = ((0, 1), (1, 0), (1, 1))


def _differs(labels: np.ndarray, valid: np.ndarray | None, dy: int, dx: int) -> np.ndarray:
    """(H - dy, W - dx) bool: pixel differs from its (dy, dx) neighbour, both valid."""
    h, w = labels.shape
    here, there = labels[: h - dy, : w - dx], labels[dy:, dx:]
    out = here != there
    if valid is not None:
        out &= valid[: h - dy, : w - dx] & valid[dy:, dx:]
    return out


def _edges(labels: np.ndarray, valid: np.ndarray | None) -> np.ndarray:
    if valid is not None and valid.shape != labels.shape:  # else a numpy broadcast error
        raise ValueError(f"valid has shape {valid.shape}, the label map {labels.shape}; "
                         "they must be the same")
    edge = np.zeros(labels.shape, dtype=bool)
    h, w = labels.shape
    for dy, dx in _STEPS:
        edge[: h - dy, : w - dx] |= _differs(labels, valid, dy, dx)
    return edge


def boundary_map(labels: np.ndarray, valid: np.ndarray | None = None) -> np.ndarray:
    """``seg2bmap`` of a segmentation: pixels whose E, S or SE neighbour has another label.

    Args:
        labels: (H, W) integer or bool segmentation (a binary mask gives one object's
            boundary, exactly DAVIS ``seg2bmap``).
        valid: optional (H, W) bool; False pixels are no boundary pixels and are not
            compared with their neighbours.

    Returns:
        (H, W) bool boundary map (background pixels next to an object included).
    """
    lab = np.asarray(labels)
    return _edges(lab, None if valid is None else np.asarray(valid, dtype=bool))


def boundary_counts(index: np.ndarray, n: int, valid: np.ndarray | None = None) -> np.ndarray:
    """Boundary size of every object of a compact index map, all objects at once.

    Equal to ``[boundary_map(index == k, valid).sum() for k in 1..n]``: a pixel counts for
    every object present in its 2x2 block (itself and its in-image, valid E, S, SE
    neighbours) when that block holds more than one label.

    Args:
        index: (H, W) int64 labels in 0..n (0 = background, not counted).
        n: number of objects.
        valid: optional (H, W) bool as in :func:`boundary_map`.

    Returns:
        (n,) int64 boundary pixels of objects 1..n.
    """
    idx = np.asarray(index, dtype=np.int64)
    v = None if valid is None else np.asarray(valid, dtype=bool)
    h, w = idx.shape
    ys, xs = np.nonzero(_edges(idx, v))
    own = idx[ys, xs]
    block = [own]
    for dy, dx in _STEPS:
        # Out-of-image neighbours clamp to the pixel itself or to its E / S neighbour, whose
        # label is in the block already; invalid ones take the pixel's own label.
        ny, nx = np.minimum(ys + dy, h - 1), np.minimum(xs + dx, w - 1)
        lab = idx[ny, nx]
        block.append(lab if v is None else np.where(v[ny, nx], lab, own))
    block = np.sort(np.stack(block, axis=1), axis=1)
    first = np.ones(block.shape, dtype=bool)
    first[:, 1:] = block[:, 1:] != block[:, :-1]  # each distinct label of a block once
    return np.bincount(block[first], minlength=n + 1)[1 : n + 1].astype(np.int64)


def pair_boundary_hits(
    b_gt: np.ndarray, b_pred: np.ndarray, tol: int, kernel: np.ndarray | None = None
) -> tuple[int, int]:
    """Tolerant boundary hits of one (GT, predicted) pair.

    Args:
        b_gt: (h, w) bool boundary of the GT object (a crop is fine if it holds both
            boundaries whole).
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
