"""Revealed background: the static world seen again where a moving body uncovers it (ours).

Optical flow is smooth across motion boundaries, so the table a hand or an arm has just
uncovered gets the hand's flow (the flow "smears" into its wake), and both of the
segmenter's hypotheses fail there: the hand's motion pulls back the hand, "nothing moved"
the hand too -- it covered the pixel a frame ago. The wake then becomes part of the hand's
MotionBit or a new one (a ghost). What explains such a pixel is the static world as it was
*before* the body covered it. :class:`StaticMemory` keeps, for each pixel, its grey level
when it was last seen standing still, and whether something with another look has covered
it since; a pixel that looks as remembered again after being covered is *revealed*
background (:meth:`StaticMemory.revealed`), which "nothing moved" explains.

The memory holds only while the camera stands still (a moving camera clears it: the
stabilised frames would have to carry it, which they do not yet). A body that stood still
at first and moves away reveals what it hid, which the memory never saw: nothing changes
there. A body that comes to rest is remembered as it is once it is seen still, so a
stopped body is never "revealed" away.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["StaticMemory"]

#: px, side of the square over which grey-level differences are averaged.
WINDOW = 5


def _mean_abs_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(H, W) float32 ``WINDOW``-mean absolute difference of two (H, W) or (H, W, C)
    float32 images, the largest over the channels (a red block on a green table of the
    same grey level differs)."""
    diff = cv2.blur(cv2.absdiff(a, b), (WINDOW, WINDOW))
    return diff if diff.ndim == 2 else diff.max(axis=2)


class StaticMemory:
    """Per-pixel look of the static world where it was last seen still (static camera).

    Args:
        shape: (H, W) of the working frames.
        tolerance: grey levels (``WINDOW`` mean): a pixel looks as remembered within this;
            a pixel whose grey level changed less than this over a frame, under reliable
            flow that moves it less than the move threshold, is seen standing still.
        covered: grey levels (``WINDOW`` mean): a pixel that differs from its memory by
            more than this was covered by something else.
    """

    def __init__(self, shape: tuple[int, int], tolerance: float, covered: float) -> None:
        self.tolerance, self.covered = tolerance, covered
        self.color = np.zeros((*shape, 3), np.float32)  # remembered RGB
        self.gray = np.zeros(shape, np.float32)  # remembered grey level
        self.known = np.zeros(shape, bool)  # seen standing still at some frame
        self.was_covered = np.zeros(shape, bool)  # looked otherwise since

    def revealed(self, cur: np.ndarray, camera_moved: bool) -> np.ndarray | None:
        """(H, W) bool: pixels covered since they were last seen still that look as they
        did then (every colour channel); None when the memory does not hold (camera
        moving, or ``tolerance`` 0).

        Args:
            cur: (H, W, 3) float32 current RGB frame.
            camera_moved: the camera moved between the last frame and this one.
        """
        if camera_moved or self.tolerance <= 0:
            return None
        return self.known & self.was_covered & (
            _mean_abs_diff(cur, self.color) < self.tolerance)

    def update(self, cur: np.ndarray, cur_gray: np.ndarray, prev_gray: np.ndarray,
               still: np.ndarray, camera_moved: bool) -> None:
        """Fold in the current frame.

        Args:
            cur: (H, W, 3) float32 current RGB frame.
            cur_gray, prev_gray: (H, W) float32 grey frames.
            still: (H, W) bool, reliable flow moving the pixel less than the move threshold.
            camera_moved: the camera moved: the memory is cleared.
        """
        if camera_moved:
            self.known[:] = False
            self.was_covered[:] = False
            return
        self.was_covered |= _mean_abs_diff(cur, self.color) > self.covered
        calm = still & (_mean_abs_diff(cur_gray, prev_gray) < self.tolerance)
        self.color[calm] = cur[calm]
        self.gray[calm] = cur_gray[calm]
        self.known |= calm
        self.was_covered &= ~calm
