"""Top-down grasp proposals from segmentation masks (paper Supplement B).

The tower-stacking controller of Supplement B "identifies the centroid and principal
axes of the largest mask, determined by pixel area, to calculate the grasp point and
orientation". This module is that step, in image space and nothing else: no camera, no
robot. A parallel gripper closes across the mask's *minor* principal axis (the narrow
direction), centred on the mask's centroid.

Conventions (all in pixels of the mask's own image):

- points are ``(x, y)`` with ``x`` to the right (column) and ``y`` down (row);
- angles are radians measured from the ``+x`` axis towards ``+y`` (clockwise on
  screen), wrapped to ``(-pi/2, pi/2]`` since a principal axis has no sign;
- ``width`` is the mask's extent along the closing direction (the opening the gripper
  needs), ``length`` its extent along the major axis, both ``max - min`` of the pixel
  centres' projections plus one pixel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from motionbits.frames import whole_number
from motionbits.objects import check_mask

__all__ = ["GraspProposal", "grasp_from_mask", "grasp_proposals"]


@dataclass(frozen=True)
class GraspProposal:
    """A top-down parallel-jaw grasp read off one binary mask.

    Attributes:
        centroid: ``(x, y)`` mean of the mask's pixel centres: the grasp point. For a
            non-convex mask it may fall outside the mask.
        major_axis: unit ``(dx, dy)`` of the largest principal axis (the object's length).
        minor_axis: unit ``(dx, dy)`` perpendicular to it: the direction the jaws close.
        angle: radians of ``minor_axis`` from ``+x`` towards ``+y``, in ``(-pi/2, pi/2]``.
        width: opening width in pixels (extent of the mask along ``minor_axis``).
        length: extent in pixels along ``major_axis``.
        area: number of mask pixels.
    """

    centroid: tuple[float, float]
    major_axis: tuple[float, float]
    minor_axis: tuple[float, float]
    angle: float
    width: float
    length: float
    area: int


def _wrap_axis_angle(angle: float) -> float:
    """Wrap an undirected axis angle to ``(-pi/2, pi/2]``."""
    wrapped = math.remainder(angle, math.pi)  # in [-pi/2, pi/2]
    return math.pi / 2 if wrapped <= -math.pi / 2 else wrapped


def _canonical(axis: np.ndarray) -> np.ndarray:
    """Fix an eigenvector's arbitrary sign: point to ``+x`` (to ``+y`` when vertical)."""
    if axis[0] < -1e-12 or (abs(axis[0]) <= 1e-12 and axis[1] < 0):
        return -axis
    return axis


def grasp_from_mask(mask: np.ndarray) -> GraspProposal:
    """Grasp proposal of one mask: centroid, principal axes, closing angle and width.

    Args:
        mask: ``(H, W)`` array, non-zero = object (bool or any numeric dtype).

    Returns:
        The :class:`GraspProposal`. A round mask has no preferred axis; its axes are
        then whatever the eigen-decomposition returns (deterministic for one input).

    Raises:
        ValueError: ``mask`` is not 2-D, holds NaN or has no pixel set.
        TypeError: ``mask`` is not a bool or numeric array.
    """
    mask = check_mask(mask)  # NaN is non-zero: "object"
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        raise ValueError("mask is empty: no pixel to grasp")
    pts = np.stack([xs, ys], axis=1).astype(np.float64)
    centroid = pts.mean(axis=0)
    centred = pts - centroid
    cov = centred.T @ centred / pts.shape[0]
    _, vecs = np.linalg.eigh(cov)  # ascending eigenvalues: column 0 = minor, 1 = major
    minor, major = vecs[:, 0], vecs[:, 1]
    minor, major = _canonical(minor), _canonical(major)
    proj_minor = centred @ minor
    proj_major = centred @ major
    return GraspProposal(
        centroid=(float(centroid[0]), float(centroid[1])),
        major_axis=(float(major[0]), float(major[1])),
        minor_axis=(float(minor[0]), float(minor[1])),
        angle=_wrap_axis_angle(math.atan2(minor[1], minor[0])),
        width=float(proj_minor.max() - proj_minor.min() + 1.0),
        length=float(proj_major.max() - proj_major.min() + 1.0),
        area=int(xs.size),
    )


def grasp_proposals(labels: np.ndarray, min_area: int = 1) -> list[tuple[int, GraspProposal]]:
    """Grasp proposals for every labelled region, largest pixel area first.

    Args:
        labels: ``(H, W)`` integer label map, ``0`` = background.
        min_area: regions with fewer pixels are left out.

    Returns:
        ``[(label, proposal), ...]`` sorted by decreasing area (ties: smaller label
        first) -- the greedy order of Supplement B's stacking controller.

    Raises:
        ValueError: ``labels`` is not a 2-D integer array or holds negative ids, or
            ``min_area < 1``.
        TypeError: ``min_area`` is not a whole number.
    """
    labels = np.asarray(labels)
    if labels.ndim != 2 or not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"labels must be a 2-D integer (H, W) array, got {labels.dtype} {labels.shape}")
    if labels.size and labels.min() < 0:  # else a grasp of "object" -1
        raise ValueError(f"labels holds negative ids (min {labels.min()}); ids must be >= 0 "
                         "(0 = background)")
    min_area = whole_number("min_area", min_area)  # NaN kept no region, 1.5 and True passed
    if min_area < 1:
        raise ValueError(f"min_area must be >= 1, got {min_area}")
    ids, counts = np.unique(labels[labels != 0], return_counts=True)
    order = sorted((int(-c), int(i)) for i, c in zip(ids, counts) if c >= min_area)
    return [(i, grasp_from_mask(labels == i)) for _, i in order]
