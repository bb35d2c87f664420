"""Marks of bodies at rest, held while nothing changes under them (ours).

A MotionBit at rest keeps its pixels in the segmenter's state, but the mark shown for it
is remade at every frame from those pixels: trimmed to the image's edges, cleared of flat
overhangs, hidden when small, completed by colour, hidden when only a stripe is left. On
a body that stands still under an unchanged image these steps should give the same mark
at every frame; they do not. Each
turns on the exact outline of the state's mask, which the flow frays by a pixel or two a
frame, so the mark of a block set down flickers between whole and gone (a block completed
to IoU 0.89 at one frame had its 303 px of state trimmed to 58 and hidden at the next).

:class:`RestingMarks` keeps the shown label map of the last frame and the frame under it.
The mark of a MotionBit (or shown group) at rest now takes its last frame's mark again,
where another mark has not taken those pixels, when

- its mark is hidden now (a mark that only shrank is left as the steps give it: holding
  the larger mark of the last frame held a spill onto the table as well, and pickplace
  lost 1.7 mIoU),
- the state still holds it mostly where that mark was (``WHERE_IT_WAS`` of its pixels):
  the body has not moved, and
- the image under that mark has not changed: at most ``CHANGED`` of its pixels differ
  by more than :data:`motionbits.completion.RECALL_LEVEL` grey levels (any channel) from
  every pixel within ``REACH`` px of theirs in the last frame (a hand passing in front, a
  shadow falling on it, the body lifted -- not the pixel of misalignment that a moving
  camera's model leaves at texture).

Under a moving camera the remembered map and frame follow the static world's model first
(as the arrivals' memory does), so "unchanged" is judged where the static world now is.

Measured in docs/results.md, "Marks at rest".
"""

from __future__ import annotations

from collections.abc import Collection

import cv2
import numpy as np

from motionbits.boxes import label_areas, label_boxes
from motionbits.completion import RECALL_LEVEL
from motionbits.masks import drop_labels, hide_edgeless, hide_thin
from motionbits.revealed import follow_ids, follow_look

__all__ = ["RestingMarks", "looks_tested", "WHERE_IT_WAS", "CHANGED", "REACH"]

#: Share of a resting MotionBit's state pixels that must lie within its last mark.
WHERE_IT_WAS = 0.5
#: Largest share of a mark's pixels that may have changed (a hand in front of a body, a
#: shadow falling on it, change most of it; a moving camera's model misaligns a few).
CHANGED = 0.1
#: px: a pixel has not changed if it lies within the range of the last frame's pixels
#: this near (+ ``RECALL_LEVEL``).
REACH = 1


class RestingMarks:
    """The marks shown at the last frame and the frame under them (one stream)."""

    def __init__(self) -> None:
        self._shown: np.ndarray | None = None  # (H, W) int32 last shown label map
        self._areas: np.ndarray | None = None  # its label_areas (None: to be counted)
        self._rgb: np.ndarray | None = None  # (H, W, 3) uint8 the frame under it

    def follow(self, world: np.ndarray) -> None:
        """Carry the memory to the current frame of a moving camera (``world``, (H, W, 2)
        float32, ``CameraMotion.world``)."""
        if self._shown is not None:
            self._shown, self._areas = follow_ids(self._shown, world), None
            self._rgb = follow_look(self._rgb, world)

    def hold(self, shown: np.ndarray, rgb: np.ndarray, state: np.ndarray,
             resting: Collection[int], min_area: float = 0.0
             ) -> tuple[np.ndarray, list[int]]:
        """The shown marks with each resting mark hidden since the last frame, on a body
        and an image that did not change, as it was (module docstring); then remembered
        for the next frame.

        Args:
            shown: (H, W) int32 shown label map of this frame.
            rgb: (H, W, 3) uint8 frame at the same size.
            state: (H, W) int32 the segmenter's labels as shown (group representatives).
            resting: shown labels whose MotionBits all stand still now.
            min_area: px; a mark is held only where it gets back at least this many
                pixels (others may have taken some of its last frame's): the segmenter
                shows no smaller mark (``MIN_SHOWN_CELLS``). Default: any size.

        Returns:
            (H, W) int32 label map (``shown`` itself where no mark is held), and the
            labels given back.
        """
        out = shown
        given = []
        now_shown = label_areas(shown)
        if self._shown is not None and self._shown.shape == shown.shape:
            before = self._shown
            was_shown = label_areas(before) if self._areas is None else self._areas
            hidden = sorted(i for i in resting if i < was_shown.size and was_shown[i]
                            and (i >= now_shown.size or not now_shown[i]))
            boxes = label_boxes(before) if hidden else []
            in_state = label_areas(state) if hidden else None
            for label in hidden:
                box = boxes[label - 1]
                was = before[box] == label
                size = was_shown[label]
                held_there = np.count_nonzero((state[box] == label) & was)
                if held_there == 0 or held_there < WHERE_IT_WAS * in_state[label]:
                    continue
                change = _change(rgb[box], self._rgb[box])[was]
                if np.count_nonzero(change > RECALL_LEVEL) > CHANGED * size:
                    continue
                back = was & (out[box] == 0)
                if np.count_nonzero(back) < min_area:
                    continue
                if out is shown:
                    out = shown.copy()
                out[box][back] = label
                given.append(label)
        self._shown, self._rgb = out, rgb.copy()
        self._areas = now_shown if out is shown else label_areas(out)
        return out, given


def looks_tested(held: np.ndarray, given: list[int], gradient: np.ndarray,
                 thin_side: int) -> np.ndarray:
    """``held`` without the marks :meth:`RestingMarks.hold` gave back (``given``) whose
    outline is no image edge (:func:`motionbits.masks.hide_edgeless`) or that are stripes
    (:func:`motionbits.masks.hide_thin`): the tests on a mark's own look, which the hold
    skips, taken by those marks alone (the others are as the steps gave them). A mark is
    given back only where other marks left room: what is left can be a sliver (round 60:
    a 79-px one on a static block's top edge, on a robot scene).

    Args:
        held, given: the marks and the labels given back that :meth:`RestingMarks.hold`
            returned.
        gradient: (H, W) float32 image gradient (grey levels per px).
        thin_side: px, :func:`motionbits.masks.hide_thin`'s square.

    Returns:
        (H, W) int32 label map.
    """
    alone = np.where(np.isin(held, given), held, 0)
    kept = np.flatnonzero(label_areas(hide_thin(hide_edgeless(alone, gradient), thin_side)))
    return drop_labels(held, np.setdiff1d(given, kept))


def _change(now: np.ndarray, then: np.ndarray) -> np.ndarray:
    """(h, w) float32: by how many grey levels (largest channel) each pixel of ``now``
    (h, w, 3) uint8 lies outside the range of ``then``'s pixels within ``REACH`` px."""
    square = np.ones((2 * REACH + 1, 2 * REACH + 1), np.uint8)
    lo = cv2.subtract(cv2.erode(then, square), now)  # saturates at 0
    hi = cv2.subtract(now, cv2.dilate(then, square))
    return cv2.max(lo, hi).max(axis=2)
