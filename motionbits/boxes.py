"""Bounding boxes of the labels of a label map."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import NamedTuple

import cv2
import numpy as np

__all__ = ["at_border", "grow_box", "label_areas", "label_boxes", "label_pieces", "nonzero_box",
           "pieces_holding", "run_counts", "run_starts", "LabelPieces"]


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


def run_starts(values: np.ndarray) -> np.ndarray:
    """(k,) int64 index of the first element of each run of one value in (n,) ``values``
    (a label map's pixels, row by row, come in long runs)."""
    first = np.empty(values.size, bool)
    first[:1] = True
    np.not_equal(values[1:], values[:-1], out=first[1:])
    return np.flatnonzero(first)


def run_counts(values: np.ndarray, minlength: int = 0) -> np.ndarray:
    """``np.bincount(values, minlength=minlength)`` of (n,) non-negative integers, counted
    by runs of one value: bincount's one-by-one count stalls on the long runs of a label
    map's pixels (several times slower)."""
    start = run_starts(values)
    # run lengths summed per value: exact integers in float64
    return np.bincount(values[start], weights=np.diff(start, append=values.size),
                       minlength=minlength).astype(np.intp)


def at_border(label_map: np.ndarray) -> np.ndarray:
    """(max label + 1,) bool: which labels of an (H, W) non-negative integer label map
    have pixels on the image's border (index 0, the background, included)."""
    touch = np.zeros(int(label_map.max()) + 1, bool)
    for edge in (label_map[0], label_map[-1], label_map[:, 0], label_map[:, -1]):
        touch[edge] = True
    return touch


def pieces_holding(mask: np.ndarray, seeds: np.ndarray) -> np.ndarray:
    """(H, W) bool: the 8-connected pieces of the (H, W) bool ``mask`` that hold a pixel of
    the (H, W) bool ``seeds``."""
    n, pieces = cv2.connectedComponents(np.ascontiguousarray(mask).view(np.uint8),
                                        connectivity=8)
    held = np.zeros(n, bool)
    held[pieces[seeds & mask]] = True
    held[0] = False  # outside the mask
    return held[pieces]


def label_areas(label_map: np.ndarray) -> np.ndarray:
    """``np.bincount(label_map.ravel())`` of an (H, W) non-negative integer label map: px
    of each label, counted on the box of the non-zero pixels only (the zeros by
    difference), by runs (:func:`run_counts`)."""
    area = run_counts(label_map[nonzero_box(label_map)].ravel(), minlength=1)
    area[0] = label_map.size - area[1:].sum()
    return area


def label_boxes(label_map: np.ndarray, max_label: int = 0) -> list[tuple[slice, slice] | None]:
    """``scipy.ndimage.find_objects(label_map, max_label)`` of an (H, W) non-negative
    integer label map (the same list: the (rows, cols) box of label i + 1 at index i, None
    where absent), read on the box of its non-zero pixels only and from the runs of one
    label along each row (find_objects visits every pixel; MotionBits often cover a small
    part of the frame, and a row crosses few outlines)."""
    rows, cols = nonzero_box(label_map)
    if rows.start == rows.stop:  # no label at all
        return [None] * max_label
    sub = label_map[rows, cols]
    w = sub.shape[1]
    first = np.empty(sub.shape, bool)  # the first pixel of each run (each row starts one)
    first[:, 0] = True
    np.not_equal(sub[:, 1:], sub[:, :-1], out=first[:, 1:])
    start = np.flatnonzero(first)
    row, col0 = np.divmod(start, w)
    col1 = (np.append(start[1:], sub.size) - 1) % w  # a run ends where the next starts
    lab = sub[row, col0]
    n = max_label or int(lab.max())
    out: list[tuple[slice, slice] | None] = [None] * n
    run = (lab > 0) & (lab <= n)
    if not run.any():
        return out
    # runs grouped by label, each group in row-major order: its first and last runs hold
    # the label's top and bottom rows
    order = np.flatnonzero(run)[np.argsort(lab[run], kind="stable")]
    lab, row, col0, col1 = lab[order], row[order], col0[order], col1[order]
    ids, at = np.unique(lab, return_index=True)
    end = np.append(at[1:], len(lab)) - 1
    y, x = rows.start, cols.start
    for i, top, bottom, left, right in zip(
            ids.tolist(), row[at].tolist(), row[end].tolist(),
            np.minimum.reduceat(col0, at).tolist(), np.maximum.reduceat(col1, at).tolist()):
        out[i - 1] = (slice(top + y, bottom + y + 1), slice(left + x, right + x + 1))
    return out


class LabelPieces(NamedTuple):
    """The connected pieces of one label of a label map, on the label's box."""

    #: the label.
    label: int
    #: (rows, cols) box of the label in the map.
    box: tuple[slice, slice]
    #: (h, w) bool: the label's pixels in its box.
    mark: np.ndarray
    #: (h, w) int32: 0 outside ``mark``, k on the pixels of its k-th piece (k >= 1).
    pieces: np.ndarray
    #: (n,) px of each piece (index 0, outside the mark: 0).
    areas: np.ndarray

    @property
    def largest(self) -> int:
        """The index of the largest piece (the first of equals)."""
        return int(np.argmax(self.areas[1:])) + 1


def label_pieces(label_map: np.ndarray, labels: Iterable[int] | None = None, *,
                 gap: int = 0) -> Iterator[LabelPieces]:
    """The 8-connected pieces of each label of an (H, W) non-negative integer label map,
    one :class:`LabelPieces` per label present (in ``labels``' order; all labels, in
    order, if None). With ``gap`` > 0, pixels of a label closer than about ``gap`` px
    (a dilation by a ``gap + 1`` square) are one piece."""
    boxes = label_boxes(label_map)
    square = np.ones((gap + 1, gap + 1), np.uint8) if gap else None
    for i in range(1, len(boxes) + 1) if labels is None else labels:
        box = boxes[i - 1] if 0 < i <= len(boxes) else None
        if box is None:
            continue
        mark = label_map[box] == i
        if gap:
            n, pieces = cv2.connectedComponents(cv2.dilate(mark.view(np.uint8), square),
                                                connectivity=8)
            pieces[~mark] = 0
            areas = np.bincount(pieces.ravel(), minlength=n)
        else:
            n, pieces, stats, _ = cv2.connectedComponentsWithStats(mark.view(np.uint8),
                                                                   connectivity=8)
            areas = stats[:, cv2.CC_STAT_AREA].copy()
        areas[0] = 0
        yield LabelPieces(int(i), box, mark, pieces, areas)
