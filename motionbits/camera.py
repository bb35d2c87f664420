"""Dominant (camera) motion compensation (ours; the paper assumes a static camera).

A handheld or shaking camera moves every pixel a little, so the whole image looks like it
moves. When one similarity transform (rotation, shift, scale; a
homography's extra freedom extrapolated badly to the image corners on real footage)
explains the flow of most nodes, that motion is taken as the
camera's and removed: the previous frame is re-expressed in the current frame's
coordinates (``prev_stab(p) = prev(H p)``) and the backward flow becomes
``H^-1(p + F(p)) - p``, which is 0 on the background.

What this does to twists: a body's image motion B (current -> previous) becomes
H^-1 o B. With H a similarity of scale ~1 (in-plane shake: small rotation + shift, little
zoom) the composition of two rigid motions is rigid, so all points of one
body still share one twist -- now relative to the camera-compensated frame. A strong
zoom or perspective change makes H^-1 o B only approximately rigid; this is the same
approximation the static-camera model makes for bodies moving in depth.

A static camera fits H ~ identity; below ``min_shift`` nothing is changed at all.
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.flow import pixel_grid, sample_maps

__all__ = ["fit_camera_motion", "compensate_flow", "stabilize_previous"]


def fit_camera_motion(points: np.ndarray, back_points: np.ndarray, reliable: np.ndarray, *,
                      support: float, threshold: float, min_shift: float) -> np.ndarray | None:
    """The 3x3 similarity H (current -> previous, ``q ~ H p``) of the dominant motion, or None.

    Args:
        points, back_points: (n, 2) node positions p and their backward-flow targets q.
        reliable: (n,) bool, nodes whose flow is trustworthy.
        support: fraction of all reliable nodes that must be RANSAC inliers of H.
        threshold: px, RANSAC reprojection threshold.
        min_shift: px; H is returned only if it moves the nodes by more than this (median).
    """
    p = points[reliable].astype(np.float32)
    q = back_points[reliable].astype(np.float32)
    if len(p) < max(8, support * len(points) * 0.5):
        return None
    h, inl = cv2.findHomography(p, q, cv2.RANSAC, threshold, maxIters=500)
    if h is None or inl is None or inl.mean() < support:
        return None
    moved = cv2.perspectiveTransform(points[None].astype(np.float64), h)[0]
    if np.median(np.linalg.norm(moved - points, axis=1)) <= min_shift:
        return None
    return h


def compensate_flow(flow_back: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(H, W, 2) backward flow relative to the camera: ``H^-1(p + F(p)) - p``."""
    ht, wd = flow_back.shape[:2]
    xs, ys = pixel_grid(ht, wd)
    q = np.stack(sample_maps(flow_back), -1).reshape(1, -1, 2)
    back = cv2.perspectiveTransform(q, np.linalg.inv(h))[0].reshape(ht, wd, 2)
    return np.stack([back[..., 0] - xs, back[..., 1] - ys], -1)


def stabilize_previous(prev: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The previous frame in the current frame's coordinates: ``out(p) = prev(H p)``."""
    ht, wd = prev.shape[:2]
    return cv2.warpPerspective(prev, h, (wd, ht), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                               borderMode=cv2.BORDER_REPLICATE)
