"""From an image mask to a grasp in the world, through the camera's intrinsics and depth.

The controller of Supplement B grasps at "the centroid and principal axes" of a mask. Read
straight off a 60-degree oblique image, those are distorted by perspective (depth is
foreshortened by cos 60 = 0.5), so the mask's pixels are first lifted to 3-D with the
depth render and the camera's known pose and intrinsics, rasterised top-down on the
table plane, and the same image-space function the agent tool uses
(:func:`motionbits.grasp.grasp_from_mask`) is applied to that bird's-eye mask.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import cv2
import numpy as np

from motionbits.grasp import grasp_from_mask

__all__ = ["HeightMap", "PinholeCamera", "WorldGrasp", "finger_clearance", "world_grasp"]

BEV_RES = 0.002  # m per pixel of the bird's-eye raster


@dataclass(frozen=True)
class PinholeCamera:
    """A MuJoCo camera's intrinsics and pose.

    Attributes:
        width, height: image size in pixels.
        fovy_deg: vertical field of view.
        pos: (3,) camera centre in the world.
        rot: (3, 3) camera-to-world rotation (columns: camera x right, y up, z backwards).
    """

    width: int
    height: int
    fovy_deg: float
    pos: np.ndarray
    rot: np.ndarray

    @property
    def focal(self) -> float:
        """Focal length in pixels (square pixels)."""
        return 0.5 * self.height / math.tan(math.radians(self.fovy_deg) / 2)

    def backproject(self, depth: np.ndarray) -> np.ndarray:
        """World points of every pixel.

        Args:
            depth: (H, W) float, distance along the optical axis in metres (MuJoCo's
                depth render).

        Returns:
            (H, W, 3) float64 world coordinates.
        """
        h, w = depth.shape
        u = np.arange(w) + 0.5 - self.width / 2
        v = np.arange(h) + 0.5 - self.height / 2
        d = depth.astype(np.float64)
        cam = np.stack([u[None, :] * d / self.focal, -v[:, None] * d / self.focal, -d], axis=-1)
        return cam @ self.rot.T + self.pos

    def project(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) world points -> (N, 2) pixel coordinates ``(x, y)``."""
        cam = (np.asarray(points, float) - self.pos) @ self.rot
        z = -cam[:, 2]
        return np.stack([cam[:, 0] / z * self.focal + self.width / 2,
                         -cam[:, 1] / z * self.focal + self.height / 2], axis=1)


@dataclass(frozen=True)
class WorldGrasp:
    """A top-down parallel-jaw grasp on the table.

    Attributes:
        xy: (x, y) grasp centre in metres.
        yaw: radians of the closing direction from the world x axis, in (-pi/2, pi/2].
        width: object extent along the closing direction, metres.
        length: object extent along the perpendicular (major) axis, metres.
        reach: farthest extent of the object from ``xy`` along the closing direction
            (either side), metres: the opening each finger needs.
        reach_major: the same along the major axis.
        top: height of the object's top (95th percentile of its points' z), metres.
        area_px: the image mask's pixel count (the greedy order).
    """

    xy: tuple[float, float]
    yaw: float
    width: float
    length: float
    reach: float
    reach_major: float
    top: float
    area_px: int


def world_grasp(mask: np.ndarray, points: np.ndarray, min_height: float = 0.005) -> WorldGrasp | None:
    """Grasp for one image mask, or None if nothing in it stands on the table.

    The mask's points on the table plane (lower than ``min_height``) are left out first,
    as grasp planners remove the support surface: only what stands up can be grasped.

    Args:
        mask: (H, W) bool, the object in the image.
        points: (H, W, 3) world coordinates of every pixel (:meth:`PinholeCamera.backproject`).
        min_height: metres above the table (z = 0) a point must be to count.
    """
    mask, points = np.asarray(mask), np.asarray(points)
    if mask.dtype != np.bool_:  # else IndexError (float) or a gather of rows 0 and 1 (int)
        raise TypeError(f"mask must be an (H, W) bool array, got dtype {mask.dtype}")
    if points.ndim != 3 or points.shape[2] != 3 or mask.shape != points.shape[:2]:
        raise ValueError(f"mask {mask.shape} and points {points.shape} must be (H, W) and (H, W, 3)")
    if not math.isfinite(min_height):  # NaN: no point counted, None returned
        raise ValueError(f"min_height must be a finite number of metres, got {min_height!r}")
    pts = points[mask]
    pts = pts[np.all(np.isfinite(pts), axis=1) & (pts[:, 2] > min_height)]
    if len(pts) == 0:
        return None
    lo = pts[:, :2].min(axis=0) - 4 * BEV_RES
    ij = np.floor((pts[:, :2] - lo) / BEV_RES).astype(np.int64)
    size = ij.max(axis=0) + 5
    bev = np.zeros((int(size[1]), int(size[0])), np.uint8)  # rows = y, cols = x
    bev[ij[:, 1], ij[:, 0]] = 1
    # Pixels are sparser than the raster far from the camera: close the gaps.
    bev = cv2.morphologyEx(bev, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7)))
    g = grasp_from_mask(bev)
    cx, cy = g.centroid
    xy = lo + (np.array([cx, cy]) + 0.5) * BEV_RES
    rel = pts[:, :2] - xy
    d = np.array([math.cos(g.angle), math.sin(g.angle)])
    reach = float(np.abs(rel @ d).max())
    reach_major = float(np.abs(rel @ np.array([-d[1], d[0]])).max())
    # BEV rows grow with y, so the raster's angle convention is the world's (x towards y).
    return WorldGrasp(xy=(float(xy[0]), float(xy[1])), yaw=float(g.angle),
                      width=float(g.width * BEV_RES), length=float(g.length * BEV_RES), reach=reach,
                      reach_major=reach_major, top=float(np.percentile(pts[:, 2], 95)),
                      area_px=int(mask.sum()))


class HeightMap:
    """Top-down height map of what the camera sees, for checking where fingers can go.

    Args:
        points: (H, W, 3) world points of the depth render.
        bounds: ``(x0, x1, y0, y1)`` of the mapped table area, metres.
        res: cell size, metres.

    Cells no pixel falls in (hidden behind objects at this oblique view) are unknown.
    """

    def __init__(self, points: np.ndarray, bounds=(-0.5, 0.5, -0.4, 0.4), res: float = 0.004) -> None:
        x0, x1, y0, y1 = bounds
        if not (isinstance(res, numbers.Real) and not isinstance(res, bool) and math.isfinite(res) and res > 0):
            # else ZeroDivisionError (0), "cannot convert float NaN to integer", or numpy's
            # "negative dimensions are not allowed" (-0.01)
            raise ValueError(f"res must be a finite number of metres > 0, got {res!r}")
        if not (x0 < x1 and y0 < y1):
            raise ValueError(f"bounds must be (x0, x1, y0, y1) with x0 < x1 and y0 < y1, got {bounds!r}")
        points = np.asarray(points)
        if points.ndim < 2 or points.shape[-1] != 3:  # else (H, W) read as 3-vectors
            raise ValueError(f"points must be (H, W, 3) world coordinates, got shape {points.shape}")
        self.bounds, self.res = bounds, res
        self.shape = (int(math.ceil((y1 - y0) / res)), int(math.ceil((x1 - x0) / res)))
        pts = points.reshape(-1, 3)
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        col = np.floor((pts[:, 0] - x0) / res).astype(np.int64)
        row = np.floor((pts[:, 1] - y0) / res).astype(np.int64)
        ok = (col >= 0) & (col < self.shape[1]) & (row >= 0) & (row < self.shape[0])
        self.height = np.full(self.shape, -np.inf)
        np.maximum.at(self.height, (row[ok], col[ok]), pts[ok, 2])

    def footprint(self, centre, axis: float, half_len: float, half_wid: float) -> np.ndarray:
        """Heights of the cells inside a rectangle (``-inf`` = unseen)."""
        d = np.array([math.cos(axis), math.sin(axis)])
        n = np.array([-d[1], d[0]])
        s = np.arange(-half_len, half_len + 1e-9, self.res / 2)
        t = np.arange(-half_wid, half_wid + 1e-9, self.res / 2)
        xy = np.asarray(centre, float) + s[:, None, None] * d + t[None, :, None] * n
        col = np.floor((xy[..., 0] - self.bounds[0]) / self.res).astype(np.int64).ravel()
        row = np.floor((xy[..., 1] - self.bounds[2]) / self.res).astype(np.int64).ravel()
        ok = (col >= 0) & (col < self.shape[1]) & (row >= 0) & (row < self.shape[0])
        return self.height[row[ok], col[ok]]


def finger_clearance(heights: HeightMap, xy, yaw: float, half_open: float,
                     finger: tuple[float, float] = (0.006, 0.013), min_seen: float = 0.7) -> float:
    """Height of the highest thing under either finger of an open gripper, metres.

    Args:
        heights: the scene's :class:`HeightMap`.
        xy: gripper centre; ``yaw``: closing direction (radians from +x).
        half_open: distance of each finger's inner face from the centre, metres.
        finger: finger half thickness (along the closing direction) and half width.
        min_seen: below this fraction of seen cells under a finger (plus a 3 mm margin),
            the footprint counts as blocked (``inf``): it is hidden behind something.

    Returns:
        The maximum seen height under the fingers (0 if only table), or ``inf``.
    """
    worst = 0.0
    for side in (-1.0, 1.0):
        c = np.asarray(xy, float) + side * (half_open + finger[0]) * np.array([math.cos(yaw), math.sin(yaw)])
        h = heights.footprint(c, yaw, finger[0] + 0.003, finger[1] + 0.003)
        seen = np.isfinite(h)
        if not h.size or seen.mean() < min_seen:
            return math.inf
        worst = max(worst, float(h[seen].max()))
    return worst
