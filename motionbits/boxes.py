"""Bounding boxes of the labels of a label map."""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

__all__ = ["grow_box", "label_areas", "label_boxes", "nonzero_box"]


def grow_box(box: tuple[slice, slice], reach: int, shape: tuple[int, ...]
             ) -> tuple[slice, slice]:
    """The image box ``box`` (rows, cols) grown by ``reach`` px on every side, clipped to
    an image of ``shape`` (H, W, ...)."""
    return (slice(max(box[0].start - reach, 0), min(box[0].stop + reach, shape[0])),
            slice(max(box[1].start - reach, 0), min(box[1].stop + reach, shape[1])))


def nonzero_box(label_map: np.ndarray) -> tuple[slice, slice]:
    """The (rows, cols) box of the non-zero pixels of an (H, W) map (empty if none)."""
    x, y, w, h = cv2.boundingRect((label_map != 0).view(np.uint8))
    return slice(y, y + h), slice(x, x + w)


def label_areas(label_map: np.ndarray) -> np.ndarray:
    """``np.bincount(label_map.ravel())`` of an (H, W) non-negative integer label map: px
    of each label, counted on the box of the non-zero pixels only (the zeros by
    difference)."""
    area = np.bincount(label_map[nonzero_box(label_map)].ravel(), minlength=1)
    area[0] = label_map.size - area[1:].sum()
    return area


def label_boxes(label_map: np.ndarray, max_label: int = 0) -> list[tuple[slice, slice] | None]:
    """``scipy.ndimage.find_objects(label_map, max_label)`` of an (H, W) integer label map
    (the same list: the (rows, cols) box of label i + 1 at index i, None where absent),
    read on the box of its non-zero pixels only (find_objects visits every pixel, and
    MotionBits often cover a small part of the frame)."""
    rows, cols = nonzero_box(label_map)
    if rows.start == rows.stop:  # no label at all
        return [None] * max_label
    y, x = rows.start, cols.start
    return [None if b is None else
            (slice(b[0].start + y, b[0].stop + y), slice(b[1].start + x, b[1].stop + x))
            for b in ndimage.find_objects(label_map[rows, cols], max_label)]
