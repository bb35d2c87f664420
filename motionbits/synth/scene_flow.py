"""Exact optical flow of a rendered clip from depth, per-pixel geoms and body poses.

For a pixel ``u`` of frame ``a``: back-project it with frame ``a``'s depth and camera to a
world point, express that point in the frame of the body its geom belongs to (pose at
``a``), move it with the body to its pose at ``b``, project it with frame ``b``'s camera:
``flow_ab(u) = u_b - u``. This is the displacement *from frame a to frame b, defined on
frame a's pixels* -- the convention of :mod:`motionbits.flow` (``flow(prev, next)``).

Validity: the point is seen in frame ``b`` -- it projects inside the image, in front of
the camera, onto a pixel of the same rigid body whose rendered depth agrees with the
projected depth (occluded and out-of-view points are invalid). The flow is still given
where it is invalid (the true motion of the surface point, as in MPI-Sintel).

Pixel convention: pixel (col, row) has its centre at image coordinates (col + 0.5, row +
0.5); the camera is MuJoCo's OpenGL camera (``mjvGLCamera``: position, forward, up and a
symmetric frustum), row 0 at the top of the image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FrameGeometry", "GLCamera", "flow_between", "gl_camera"]


@dataclass(frozen=True)
class GLCamera:
    """A pinhole camera: world position, orthonormal axes and focal length in pixels.

    Attributes:
        pos, forward, up, right: (3,) float64; ``right = forward x up``.
        focal: pixels per unit of normalized image coordinate (square pixels).
        width, height: image size in pixels.
    """

    pos: np.ndarray
    forward: np.ndarray
    up: np.ndarray
    right: np.ndarray
    focal: float
    width: int
    height: int

    def project(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(..., 3) world points -> (col, row, z): pixel coordinates (index units) and depth."""
        d = pts - self.pos
        z = d @ self.forward
        zs = np.where(np.abs(z) < 1e-9, 1e-9, z)
        col = self.width / 2 + self.focal * (d @ self.right) / zs - 0.5
        row = self.height / 2 - self.focal * (d @ self.up) / zs - 0.5
        return col, row, z

    def backproject(self, depth: np.ndarray) -> np.ndarray:
        """(H, W) z-depth (along ``forward``) -> (H, W, 3) world points of the pixel centres."""
        h, w = depth.shape
        xn = (np.arange(w) + 0.5 - w / 2) / self.focal
        yn = (h / 2 - (np.arange(h) + 0.5)) / self.focal
        ray = (self.forward[None, None] + xn[None, :, None] * self.right[None, None]
               + yn[:, None, None] * self.up[None, None])
        return self.pos + depth[..., None] * ray


def gl_camera(glcam, width: int, height: int) -> GLCamera:
    """:class:`GLCamera` from MuJoCo's ``mjvGLCamera`` (``renderer.scene.camera[0]`` after
    ``update_scene``); the frustum must be symmetric (free and fixed perspective cameras)."""
    fwd = np.asarray(glcam.forward, float)
    fwd = fwd / np.linalg.norm(fwd)
    up = np.asarray(glcam.up, float)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    if abs(glcam.frustum_center) > 1e-9 or abs(glcam.frustum_top + glcam.frustum_bottom) > 1e-9:
        raise ValueError("oracle flow needs a symmetric frustum (a perspective camera)")
    focal = (height / 2) * glcam.frustum_near / glcam.frustum_top
    return GLCamera(np.asarray(glcam.pos, float).copy(), fwd, up, right, float(focal),
                    int(width), int(height))


@dataclass(frozen=True)
class FrameGeometry:
    """What the flow needs of one rendered frame.

    Attributes:
        depth: (H, W) float32 z-depth in metres.
        geom_ids: (H, W) int32 geom per pixel, -1 where no geom.
        xpos: (nbody, 3) float64 body positions.
        xmat: (nbody, 3, 3) float64 body rotations.
        camera: the frame's camera.
    """

    depth: np.ndarray
    geom_ids: np.ndarray
    xpos: np.ndarray
    xmat: np.ndarray
    camera: GLCamera


def flow_between(a: FrameGeometry, b: FrameGeometry, geom_body: np.ndarray,
                 body_root: np.ndarray, depth_tol: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Exact flow from frame ``a`` to frame ``b`` on ``a``'s pixels.

    Args:
        a, b: the two frames' geometry.
        geom_body: (ngeom,) body of every geom (``model.geom_bodyid``).
        body_root: (nbody,) rigid-body root of every body (``model.body_weldid``).
        depth_tol: relative depth difference allowed for "visible in b" (plus 3 mm).

    Returns:
        ``(flow, valid)``: (H, W, 2) float32 displacement (dx, dy) in pixels, and (H, W)
        bool, True where the point is visible in ``b``.
    """
    h, w = a.depth.shape
    has = a.geom_ids >= 0
    body = np.where(has, geom_body[np.maximum(a.geom_ids, 0)], 0)
    world = a.camera.backproject(a.depth.astype(np.float64))
    local = np.einsum("hwji,hwj->hwi", a.xmat[body], world - a.xpos[body])
    moved = np.einsum("hwij,hwj->hwi", b.xmat[body], local) + b.xpos[body]
    col, row, z = b.camera.project(moved)
    cols, rows = np.meshgrid(np.arange(w), np.arange(h))
    flow = np.stack([col - cols, row - rows], -1).astype(np.float32)
    flow[~has] = 0.0
    ci, ri = np.rint(col).astype(np.int64), np.rint(row).astype(np.int64)
    inside = has & (z > 1e-6) & (ci >= 0) & (ci < w) & (ri >= 0) & (ri < h)
    ci, ri = np.clip(ci, 0, w - 1), np.clip(ri, 0, h - 1)
    gb = b.geom_ids[ri, ci]
    same = (gb >= 0) & (body_root[geom_body[np.maximum(gb, 0)]] == body_root[body])
    seen = np.abs(b.depth[ri, ci] - z) <= depth_tol * z + 0.003
    return flow, inside & same & seen
