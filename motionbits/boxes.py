"""Bounding boxes of the labels of a label map."""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

__all__ = ["grow_box", "label_boxes"]


def grow_box(box: tuple[slice, slice], reach: int, shape: tuple[int, ...]
             ) -> tuple[slice, slice]:
    """The image box ``box`` (rows, cols) grown by ``reach`` px on every side, clipped to
    an image of ``shape`` (H, W, ...)."""
    return (slice(max(box[0].start - reach, 0), min(box[0].stop + reach, shape[0])),
            slice(max(box[1].start - reach, 0), min(box[1].stop + reach, shape[1])))


def label_boxes(label_map: np.ndarray, max_label: int = 0) -> list[tuple[slice, slice] | None]:
    """``scipy.ndimage.find_objects(label_map, max_label)`` of an (H, W) integer label map
    (the same list: the (rows, cols) box of label i + 1 at index i, None where absent),
    read on the box of its non-zero pixels only (find_objects visits every pixel, and
    MotionBits often cover a small part of the frame)."""
    x, y, w, h = cv2.boundingRect((label_map != 0).view(np.uint8))
    if w == 0:  # no label at all
        return [None] * max_label
    return [None if b is None else
            (slice(b[0].start + y, b[0].stop + y), slice(b[1].start + x, b[1].stop + x))
            for b in ndimage.find_objects(label_map[y:y + h, x:x + w], max_label)]
