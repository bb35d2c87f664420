"""Top-down grasp proposal from one object mask (paper Supplement B).

The paper's tower-stacking controller "identifies the centroid and principal axes of the
largest mask ... to calculate the grasp point and orientation". A parallel gripper seen
from above closes across the object's narrow side: the jaws close along the minor
principal axis, through the centroid, opened as wide as the mask is along that axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Grasp", "principal_axes", "top_down_grasp"]


@dataclass(frozen=True)
class Grasp:
    """A top-down parallel-jaw grasp in image coordinates (pixels, x right, y down).

    Attributes:
        center: (x, y) grasp point: the mask's centroid.
        angle: radians in (-pi/2, pi/2], direction in which the jaws close (the minor
            principal axis), measured from the +x axis towards +y.
        width: opening width in pixels: the mask's extent along the closing direction
            through all its pixels (max - min projection), plus one pixel.
        major_axis, minor_axis: unit (x, y) vectors of the principal axes.
        major_length, minor_length: the mask's extent along each axis, in pixels.
    """

    center: tuple[float, float]
    angle: float
    width: float
    major_axis: tuple[float, float]
    minor_axis: tuple[float, float]
    major_length: float
    minor_length: float


def principal_axes(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centroid and principal axes of a binary mask.

    Args:
        mask: (H, W) bool or integer array; nonzero pixels belong to the object.

    Returns:
        centroid (2,) float64 (x, y); axes (2, 2) float64, rows = unit major then minor
        axis (x, y); variances (2,) float64 along them (major >= minor).

    Raises:
        ValueError: the mask is not 2-D or has no pixel.
    """
    mask = np.asarray(mask)
    if mask.ndim != 2:
        raise ValueError(f"mask must be a 2-D (H, W) array, got shape {mask.shape}")
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        raise ValueError("mask is empty: no pixel to grasp")
    pts = np.stack([xs, ys], axis=1).astype(np.float64)
    centroid = pts.mean(axis=0)
    cov = np.cov(pts - centroid, rowvar=False) if len(pts) > 1 else np.zeros((2, 2))
    var, vec = np.linalg.eigh(cov)  # ascending eigenvalues
    order = [1, 0]
    axes = vec[:, order].T
    # a fixed sign convention, so the same mask always gives the same axes
    for k in range(2):
        if axes[k, 0] < 0 or (axes[k, 0] == 0 and axes[k, 1] < 0):
            axes[k] = -axes[k]
    return centroid, axes, var[order]


def top_down_grasp(mask: np.ndarray) -> Grasp:
    """The grasp of Supplement B: at the centroid, jaws closing along the minor axis.

    Args:
        mask: (H, W) bool or integer array; nonzero pixels belong to the object.

    Returns:
        :class:`Grasp`.

    Example:
        >>> m = np.zeros((40, 60), bool); m[10:20, 5:55] = True   # a bar 50 wide, 10 high
        >>> g = top_down_grasp(m)
        >>> g.center, round(g.angle, 3), g.width
        ((29.5, 14.5), 1.571, 10.0)
    """
    centroid, axes, _ = principal_axes(mask)
    ys, xs = np.nonzero(np.asarray(mask))
    pts = np.stack([xs, ys], axis=1).astype(np.float64) - centroid
    proj = pts @ axes.T
    lengths = proj.max(axis=0) - proj.min(axis=0) + 1.0
    minor = axes[1]
    angle = float(np.arctan2(minor[1], minor[0]))
    if angle <= -np.pi / 2:
        angle += np.pi
    elif angle > np.pi / 2:
        angle -= np.pi
    return Grasp(
        center=(float(centroid[0]), float(centroid[1])),
        angle=angle,
        width=float(lengths[1]),
        major_axis=(float(axes[0, 0]), float(axes[0, 1])),
        minor_axis=(float(minor[0]), float(minor[1])),
        major_length=float(lengths[0]),
        minor_length=float(lengths[1]),
    )
