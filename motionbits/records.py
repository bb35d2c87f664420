"""What a frame's segmentation returns: the label map and one record per MotionBit."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from motionbits.boxes import label_boxes, nonzero_box
from motionbits.nodes import NodeGrid
from motionbits.objects import Instance, encode_rle
from motionbits.twists import se2_log

__all__ = ["MotionBit", "MotionBitsResult", "MotionSpans", "moving_ids", "twist_sources",
           "group_map", "build_result"]

#: One MotionBit in one frame: the shared :class:`motionbits.Instance` with ``twist``,
#: ``moving``, ``first_moved`` and ``last_moved`` set (coordinates in input pixels; the
#: twist is zeros when it has no cluster this frame). ``update`` leaves ``mask`` unset
#: (the label map holds it): :meth:`MotionBitsResult.instances` attaches masks.
MotionBit = Instance


@dataclass
class MotionBitsResult:
    """Output of :meth:`MotionBitsSegmenter.update` for one frame.

    Attributes:
        frame_index: 0-based index of the frame in the stream.
        labels: (H, W) int32 at the input size; 0 = background, k > 0 = the mark
            numbered k (a body keeps its number from frame to frame:
            :mod:`motionbits.numbering`).
        motionbits: one record per id present in ``labels``, by id.
        node_labels: (rows, cols) int32 the number of the mark each grid node is in (0 =
            none, or a mark not shown).
        timings: milliseconds spent per stage (see ``STAGES``).
    """

    frame_index: int
    labels: np.ndarray
    motionbits: list[MotionBit]
    node_labels: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def ids(self) -> list[int]:
        return [mb.id for mb in self.motionbits]

    def instances(self, rle: bool = False) -> list[Instance]:
        """``motionbits`` with their (H, W) bool masks from ``labels`` (or COCO RLE when
        ``rle``; extra ``coco``); ``motionbits.to_supervision`` takes the result."""
        return [replace(mb, mask=None if rle else self.labels == mb.id,
                        rle=encode_rle(self.labels == mb.id) if rle else None)
                for mb in self.motionbits]


@dataclass
class MotionSpans:
    """First and last frame at which each MotionBit id moved.

    Attributes:
        first, last: id -> frame index.
    """

    first: dict[int, int] = field(default_factory=dict)
    last: dict[int, int] = field(default_factory=dict)

    def record(self, moving, frame_index: int) -> None:
        """The ids ``moving`` moved at ``frame_index``."""
        for i in moving:
            self.first.setdefault(int(i), frame_index)
            self.last[int(i)] = frame_index

    def inherit(self, child: int, parent: int, last: int) -> None:
        """``child`` (a piece of ``parent``) moved with ``parent`` until ``last``."""
        if parent in self.first:
            self.first.setdefault(child, self.first[parent])
            self.last.setdefault(child, min(last, self.last[parent]))


def moving_ids(points: np.ndarray, node_ids: np.ndarray, ids: np.ndarray, thetas: np.ndarray,
               trans: np.ndarray, threshold: float) -> set[int]:
    """Ids whose fitted motion moves their nodes by more than ``threshold`` px (mean).

    Args:
        points: (n, 2) node positions.
        node_ids: (n,) int MotionBit id of each node (0 = none).
        ids: (K,) ids with backward motions ``thetas`` (K,) and ``trans`` (K, 2).
        threshold: px/frame (config ``move_threshold``).
    """
    moving = set()
    for lab, th, t in zip(ids, thetas, trans):
        c, s = np.cos(th), np.sin(th)
        p = points[node_ids == lab]
        moved = p @ np.array([[c, s], [-s, c]]) + t - p
        if float(np.mean(np.linalg.norm(moved, axis=1))) > threshold:
            moving.add(int(lab))
    return moving


def twist_sources(node_ids: np.ndarray, ids: np.ndarray, rep: dict[int, int]) -> dict[int, int]:
    """The id whose twist each shown MotionBit reports: of its group's members with a motion
    this frame (``ids``), the one with the most nodes (the first of them on a tie).

    Args:
        node_ids: (n,) int MotionBit id of each grid node (0 = none).
        ids: (K,) ids with a cluster (and a motion) this frame.
        rep: id -> the id it is shown under (0 = not shown).

    Returns:
        shown id -> member id, for the shown MotionBits with a motion.
    """
    with_motion = {int(i) for i in ids}
    counts = np.bincount(node_ids, minlength=max([*rep.keys(), *with_motion, 0]) + 1)
    members: dict[int, list[int]] = {}
    for i, r in rep.items():
        if r and i in with_motion:
            members.setdefault(r, []).append(i)
    return {r: max(group, key=lambda i: counts[i]) for r, group in members.items()}


def group_map(labels: np.ndarray, rep: dict[int, int]) -> np.ndarray:
    """int32 label map (any shape) as shown: each id replaced by the id it is shown under
    (``rep``; 0 = not shown, and for ids not in ``rep``)."""
    lut = np.zeros(max([int(labels.max(initial=0)), *rep.keys(), 0]) + 1, np.int32)
    for i, r in rep.items():
        lut[i] = r
    if labels.ndim != 2 or lut[0]:
        return np.take(lut, labels)
    out = np.zeros(labels.shape, np.int32)  # background stays background: the labels' box
    box = nonzero_box(labels)
    out[box] = np.take(lut, labels[box])  # np.take: faster than lut[...] (int32)
    return out


def _area_centroid(mask: np.ndarray, corner: tuple[int, int]) -> tuple[int, tuple[float, float]]:
    """Pixel count and (x, y) mean position of an (h, w) bool ``mask`` whose top-left pixel
    is ``corner`` (y, x) of the image; the mask must not be empty. The coordinate sums are
    exact integers, so the means equal those of ``np.nonzero``'s coordinates, without
    building them."""
    per_col = np.count_nonzero(mask, axis=0)
    per_row = np.count_nonzero(mask, axis=1)
    area = int(per_col.sum())
    sum_x = int(per_col @ np.arange(corner[1], corner[1] + mask.shape[1]))
    sum_y = int(per_row @ np.arange(corner[0], corner[0] + mask.shape[0]))
    return area, (sum_x / area, sum_y / area)


def build_result(frame_index: int, shown: np.ndarray, node_ids: np.ndarray, ids: np.ndarray,
                 thetas: np.ndarray, trans: np.ndarray, moving: set[int], rep: dict[int, int],
                 source: dict[int, int], spans: MotionSpans, grid: NodeGrid,
                 input_size: tuple[int, int]) -> MotionBitsResult:
    """The records of the MotionBits shown: each group of merged ids under its
    representative, with the twist of its largest member that has a motion this frame.

    Args:
        frame_index: index of the frame.
        shown: (h, w) int32 working-resolution label map as shown (:func:`group_map`).
        node_ids: (n,) int MotionBit id of each grid node (0 = none).
        ids: (K,) ids with a cluster now, backward motions ``thetas`` (K,), ``trans`` (K, 2).
        moving: ids that moved this frame.
        rep: id -> the id it is shown under (0 = not shown), for the ids present.
        source: shown id -> the member whose twist it reports (:func:`twist_sources`).
        spans: first / last frame of motion of each id.
        grid: the node grid (its image size is the working resolution).
        input_size: (H, W) of the input frames.

    Returns:
        :class:`MotionBitsResult` with (H, W) labels at the input size (no timings).
    """
    h, w = input_size
    scale = w / grid.width, h / grid.height
    out = shown
    node_out = group_map(node_ids, rep)
    members: dict[int, list[int]] = {}
    for i, r in rep.items():
        members.setdefault(r, []).append(i)
    twists = {int(i): -se2_log(th, t) for i, th, t in zip(ids, thetas, trans)}
    if (h, w) != out.shape:
        out = cv2.resize(out, (w, h), interpolation=cv2.INTER_NEAREST)
    records = []
    for index, box in enumerate(label_boxes(out)):
        if box is None:
            continue
        lab = index + 1
        group = members.get(lab, [lab])
        tw = twists[source[lab]] if lab in source else np.zeros(3)
        first = [spans.first[i] for i in group if i in spans.first]
        last = [spans.last[i] for i in group if i in spans.last]
        area, centroid = _area_centroid(out[box] == lab, (box[0].start, box[1].start))
        records.append(MotionBit(
            id=lab, area=area,
            bbox=(box[1].start, box[0].start, box[1].stop, box[0].stop),
            centroid=centroid,
            twist=(float(tw[0]), float(tw[1] * scale[0]), float(tw[2] * scale[1])),
            moving=any(i in moving for i in group),
            first_moved=min(first, default=frame_index),
            last_moved=max(last, default=frame_index),
        ))
    return MotionBitsResult(frame_index, out, records,
                            node_out.reshape(grid.rows, grid.cols).astype(np.int32))
