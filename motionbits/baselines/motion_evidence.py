"""Motion evidence of a clip, carried to its last frame with dense optical flow.

For t = 1..T-1, with the backward flow b_t = flow(I_t -> I_{t-1}):

    moved_t(p) = moved_{t-1}(p + b_t(p))  or  |b_t(p)| > threshold
    D_t(p)     = b_t(p) + D_{t-1}(p + b_t(p))        (D_0 = 0, bilinear lookup)

``moved_T-1`` marks last-frame pixels that moved at some time during the clip (the MotionBit
definition); ``D_T-1(p)`` is where pixel p of the last frame was in the first frame, minus p.
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.flow import FlowBackend, warp_nearest

__all__ = ["motion_evidence"]


def motion_evidence(frames: list[np.ndarray], flow: FlowBackend, threshold: float = 1.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Moved mask and displacement to the first frame, for the last frame's pixels.

    Args:
        frames: T >= 2 (H, W, 3) uint8 RGB frames.
        flow: backend ``flow(prev, next) -> (H, W, 2) float32``.
        threshold: px per frame above which a pixel counts as moving.

    Returns:
        ``(moved, disp)``: (H, W) bool and (H, W, 2) float32 (dx, dy) to the first frame.
    """
    if len(frames) < 2:
        raise ValueError(f"need at least 2 frames to see motion, got {len(frames)}")
    h, w = frames[0].shape[:2]
    for i, f in enumerate(frames):
        if f.shape[:2] != (h, w):
            raise ValueError(f"frame {i} is {f.shape[:2]}, frame 0 is {(h, w)}")
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    moved = np.zeros((h, w), np.uint8)
    disp = np.zeros((h, w, 2), np.float32)
    for t in range(1, len(frames)):
        back = flow(frames[t], frames[t - 1]).astype(np.float32)
        moved = warp_nearest(moved, back, fill=0)
        moved |= (np.linalg.norm(back, axis=-1) > threshold).astype(np.uint8)
        carried = cv2.remap(disp, xs + back[..., 0], ys + back[..., 1], cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
        disp = back + carried
    return moved.astype(bool), disp
