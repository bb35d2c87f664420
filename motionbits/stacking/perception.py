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
from dataclasses import dataclass

import cv2
import numpy as np

from motionbits.grasp import grasp_from_mask

__all__ = ["PinholeCamera", "WorldGrasp", "world_grasp"]

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
        top: height of the object's top (95th percentile of its points' z), metres.
        area_px: the image mask's pixel count (the greedy order).
    """

    xy: tuple[float, float]
    yaw: float
    width: float
    top: float
    area_px: int


def world_grasp(mask: np.ndarray, points: np.ndarray) -> WorldGrasp | None:
    """Grasp for one image mask, or None if the mask has no valid 3-D point.

    Args:
        mask: (H, W) bool, the object in the image.
        points: (H, W, 3) world coordinates of every pixel (:meth:`PinholeCamera.backproject`).
    """
    pts = points[mask]
    pts = pts[np.all(np.isfinite(pts), axis=1)]
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
    # BEV rows grow with y, so the raster's angle convention is the world's (x towards y).
    return WorldGrasp(xy=(float(xy[0]), float(xy[1])), yaw=float(g.angle),
                      width=float(g.width * BEV_RES), top=float(np.percentile(pts[:, 2], 95)),
                      area_px=int(mask.sum()))
