"""Where to put each mark's number: pure functions over masks and label maps.

The number of a mark sits at the pixel of its mask that is farthest from the mask's
edge (the maximum of the distance transform, as Set-of-Mark does), which lies inside
the mask for any shape: thin lines, rings, C-shapes, masks with holes or touching the
image border. The centroid is never used (it can fall outside a concave mask).

Label boxes of different marks must not overlap. :func:`place_labels` settles them
greedily, masks with the least room first; the rule, in order of preference:

1. the mask's distance-transform maximum (or the previous frame's point, see
   ``prefer``) when the label box placed there is free;
2. another pixel of the same mask whose box is free, preferring pixels where the box
   fits inside the mask, then pixels close to the maximum;
3. a free spot outside the mask, on rings of growing radius around the maximum; the
   label is then linked to its point by a leader line (``LabelPlacement.leader``);
4. if the image has no free spot at all, the maximum, overlapping (``overlaps=True``).

In every case ``LabelPlacement.point`` is a pixel of the mask. The box is centred on
the point unless that would cross the image border, in which case it is shifted just
enough to stay inside the image (it then still covers the point whenever the box fits).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import cv2
import numpy as np

from motionbits.frames import whole_number
from motionbits.objects import check_mask

from .regions import LabelRegions, Region

__all__ = ["distance_to_edge", "mask_anchor", "LabelPlacement", "place_labels"]


def distance_to_edge(mask: np.ndarray) -> np.ndarray:
    """Euclidean distance of each mask pixel to the nearest pixel outside the mask.

    The image border counts as outside (the mask is zero-padded first), so a mask that
    touches the border gets its anchor away from it.

    Args:
        mask: (H, W) bool, or numbers where non-zero is the object (NaN is an error).

    Returns:
        (H, W) float32; 0 outside the mask, >= 1 inside.
    """
    # else OpenCV's "src.type() == CV_8UC1" (3-D) or an empty result (1-D); NaN, 0.5 and 256
    # were cast to uint8 0 (outside) while mask_anchor read them as inside
    mask = check_mask(mask)
    m = np.pad(mask, 1).astype(np.uint8)
    dt = cv2.distanceTransform(m, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    return dt[1:-1, 1:-1]


def _best_pixel(dt: np.ndarray) -> tuple[int, int]:
    """(row, col) of the distance maximum; ties go to the maximum pixel nearest the mean
    of all maximum pixels (the middle of a 1-px line, not its end)."""
    peak = dt.max()
    rows, cols = np.nonzero(dt >= peak - 1e-4)
    cr, cc = rows.mean(), cols.mean()
    k = int(np.argmin((rows - cr) ** 2 + (cols - cc) ** 2))
    return int(rows[k]), int(cols[k])


def mask_anchor(mask: np.ndarray) -> tuple[int, int]:
    """The point of a mask farthest from its edge: where its number goes.

    Args:
        mask: (H, W) bool mask with at least one True pixel (or numbers, non-zero = object).

    Returns:
        ``(x, y)`` pixel coordinates; ``mask[y, x]`` is always True.

    Example:
        >>> import numpy as np
        >>> ring = np.zeros((9, 9), bool); ring[1:8, 1:8] = True; ring[3:6, 3:6] = False
        >>> x, y = mask_anchor(ring); bool(ring[y, x])
        True
    """
    mask = check_mask(mask)  # NaN was read as inside
    if not mask.any():
        raise ValueError("mask is empty: an anchor needs at least one pixel")
    r, c = _best_pixel(distance_to_edge(mask))
    return c, r


@dataclass(frozen=True)
class LabelPlacement:
    """Where one mark's label goes.

    Attributes:
        obj_id: object id.
        point: ``(x, y)``, a pixel of the object's mask; the number's reference point.
        box: ``(x0, y0, x1, y1)`` of the label box, max exclusive, inside the image when
            the box fits in it.
        leader: True when the box could not be placed on the mask and sits beside it;
            draw a line from the box to ``point``.
        overlaps: True when no free place existed and the box overlaps another label.
    """

    obj_id: int
    point: tuple[int, int]
    box: tuple[int, int, int, int]
    leader: bool = False
    overlaps: bool = False


def _box_at(cx: np.ndarray, cy: np.ndarray, w: int, h: int, W: int, H: int) -> np.ndarray:
    """(N, 4) boxes of size (w, h) centred on (cx, cy), shifted to stay inside the image."""
    x0 = np.clip(cx - w // 2, 0, max(W - w, 0))
    y0 = np.clip(cy - h // 2, 0, max(H - h, 0))
    return np.stack([x0, y0, x0 + w, y0 + h], axis=-1)


def _free(boxes: np.ndarray, placed: np.ndarray, gap: int) -> np.ndarray:
    """(N,) bool: which of ``boxes`` (N, 4) is at least ``gap`` px from all ``placed`` (M, 4)."""
    if placed.shape[0] == 0:
        return np.ones(boxes.shape[0], dtype=bool)
    b = boxes[:, None, :]
    p = placed[None, :, :]
    sep = (
        (b[..., 2] + gap <= p[..., 0]) | (p[..., 2] + gap <= b[..., 0])
        | (b[..., 3] + gap <= p[..., 1]) | (p[..., 3] + gap <= b[..., 1])
    )
    return sep.all(axis=1)


def _first_free(boxes: np.ndarray, placed: np.ndarray, gap: int, chunk: int = 1024) -> int | None:
    for start in range(0, boxes.shape[0], chunk):
        ok = np.flatnonzero(_free(boxes[start:start + chunk], placed, gap))
        if ok.size:
            return start + int(ok[0])
    return None


def _ring_offsets(radius: int, step: int) -> np.ndarray:
    """Integer (dx, dy) offsets spaced ~``step`` apart on a square ring of ``radius``."""
    n = max(1, (2 * radius) // max(step, 1))
    t = np.linspace(-radius, radius, n + 1).round().astype(int)
    top = np.stack([t, np.full_like(t, -radius)], 1)
    bot = np.stack([t, np.full_like(t, radius)], 1)
    left = np.stack([np.full_like(t, -radius), t], 1)
    right = np.stack([np.full_like(t, radius), t], 1)
    offs = np.unique(np.concatenate([top, bot, left, right]), axis=0)
    return offs[np.argsort(np.hypot(offs[:, 0], offs[:, 1]), kind="stable")]


def _points(name: str, pairs: Mapping, low: int | None) -> dict[int, tuple[int, int]]:
    """``pairs`` (object id -> two whole numbers, each >= ``low``) as a dict of int pairs."""
    if not isinstance(pairs, Mapping):  # a list of sizes placed nothing
        raise TypeError(f"{name} must be a mapping of object id -> (a, b), got {type(pairs).__name__} {pairs!r:.40}")
    out = {}
    for k, v in pairs.items():
        if isinstance(v, (str, bytes)) or np.shape(v) != (2,):
            raise ValueError(f"{name}[{k!r}] must be two whole numbers, got {v!r:.40}")
        a, b = (whole_number(f"{name}[{k!r}]", x) for x in v)
        if low is not None and min(a, b) < low:
            raise ValueError(f"{name}[{k!r}] must be two whole numbers >= {low}, got {v!r:.40}")
        out[k] = (a, b)
    return out


def place_labels(
    regions: LabelRegions,
    sizes: Mapping[int, tuple[int, int]],
    *,
    prefer: Mapping[int, tuple[int, int]] | None = None,
    gap: int = 1,
) -> dict[int, LabelPlacement]:
    """Place one label box per object so that boxes do not overlap (rule in module doc).

    Args:
        regions: the label map's regions (``LabelRegions(label_map)``).
        sizes: object id -> ``(w, h)`` of its label box in pixels; ids missing here are
            not placed.
        prefer: object id -> ``(x, y)`` to keep if it is still well inside the mask (at
            least half the maximum distance to the edge) and free, e.g. last frame's
            point, so labels do not jitter in a video.
        gap: minimum free pixels between two boxes.

    Returns:
        object id -> :class:`LabelPlacement`, for every id in both ``regions`` and
        ``sizes``.
    """
    if not isinstance(regions, LabelRegions):  # else "'numpy.ndarray' object has no attribute 'obj_id'"
        raise TypeError(f"regions must be a somprompt.LabelRegions (LabelRegions(label_map)), got {type(regions).__name__}")
    sizes = _points("sizes", sizes, low=1)  # else (-4, 4) gave an inverted box, NaN "cannot convert float NaN"
    prefer = _points("prefer", prefer or {}, low=None)
    if whole_number("gap", gap) < 0:  # else NaN and -1 were taken as no gap
        raise ValueError(f"gap must be >= 0 pixels, got {gap!r}")
    H, W = regions.shape
    todo: list[tuple[Region, np.ndarray]] = []
    for reg in regions:
        if reg.obj_id in sizes:
            todo.append((reg, distance_to_edge(reg.crop)))
    # least room first: those have the fewest alternatives
    todo.sort(key=lambda rd: (float(rd[1].max()), rd[0].area, rd[0].obj_id))

    placed = np.zeros((0, 4), dtype=np.int64)
    out: dict[int, LabelPlacement] = {}
    for reg, dt in todo:
        w, h = (int(v) for v in sizes[reg.obj_id])
        x_off, y_off = reg.bbox[0], reg.bbox[1]
        pr, pc = _best_pixel(dt)
        best = (pc + x_off, pr + y_off)

        candidates = [best]
        if reg.obj_id in prefer:
            px, py = (int(v) for v in prefer[reg.obj_id])
            r, c = py - y_off, px - x_off
            if 0 <= r < dt.shape[0] and 0 <= c < dt.shape[1] and dt[r, c] >= 0.5 * dt.max():
                candidates.insert(0, (px, py))
        cand = np.asarray(candidates, dtype=np.int64)
        boxes = _box_at(cand[:, 0], cand[:, 1], w, h, W, H)
        k = _first_free(boxes, placed, gap)
        leader = overlaps = False
        if k is None:
            # every pixel of the mask, best first: box fits in the mask, then near the max
            rows, cols = np.nonzero(reg.crop)
            fit = min(float(np.hypot(w, h)) / 2.0, float(dt.max()))
            d = dt[rows, cols]
            order = np.lexsort((np.hypot(rows - pr, cols - pc), -np.minimum(d, fit)))
            cand = np.stack([cols[order] + x_off, rows[order] + y_off], axis=1)
            boxes = _box_at(cand[:, 0], cand[:, 1], w, h, W, H)
            k = _first_free(boxes, placed, gap)
        if k is None:
            # beside the mask, on rings of growing radius around the maximum
            step = max(2, min(w, h) // 2)
            for radius in range(step, max(H, W) + max(w, h), step):
                offs = _ring_offsets(radius, step)
                cx, cy = best[0] + offs[:, 0], best[1] + offs[:, 1]
                keep = (cx >= 0) & (cx < W) & (cy >= 0) & (cy < H)
                if not keep.any():
                    continue
                rb = _box_at(cx[keep], cy[keep], w, h, W, H)
                j = _first_free(rb, placed, gap)
                if j is not None:
                    boxes, k, leader = rb, j, True
                    cand = np.repeat(np.asarray([best]), rb.shape[0], axis=0)
                    break
        if k is None:
            cand = np.asarray([best])
            boxes = _box_at(cand[:, 0], cand[:, 1], w, h, W, H)
            k, overlaps = 0, True
        box = tuple(int(v) for v in boxes[k])
        point = (int(cand[k][0]), int(cand[k][1]))
        placed = np.concatenate([placed, np.asarray([box], dtype=np.int64)])
        out[reg.obj_id] = LabelPlacement(reg.obj_id, point, box, leader, overlaps)  # type: ignore[arg-type]
    return out
