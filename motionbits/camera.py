"""Dominant (camera) motion compensation (ours; the paper assumes a static camera).

A handheld, panning or shaking camera moves every pixel, so the whole image looks like it
moves. When one homography explains the flow of most nodes (RANSAC), that motion is taken
as the camera's and removed -- a homography is exact for a camera that rotates (pans,
tilts, shakes) and for a planar scene; a similarity is not (on the DAVIS car-roundabout
pan, a similarity left 35% of the static background labelled, a homography 7%): the
previous frame is re-expressed in the current frame's coordinates (``prev_stab(p) = prev(H p)``) and the backward flow becomes
``H^-1(p + F(p)) - p``, which is 0 on the background.

What this does to twists: a body's image motion B (current -> previous) becomes
H^-1 o B, relative to the camera-compensated frame. Where H is close to a rigid motion
(in-plane shake) that is rigid again; under a strong perspective change it is only
approximately rigid -- the same approximation the static-camera model makes for bodies
moving in depth. A camera that translates through a 3D scene sees parallax, which no
homography removes by itself: where the homography's residual lines up with one epipole
over enough of the image, that residual is the static world's parallax
(``motionbits/parallax.py``, plane + parallax) and is removed as well.

A static camera fits H ~ identity; below ``min_shift`` nothing is changed at all.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import cv2
import numpy as np
from scipy import ndimage

from motionbits.boxes import at_border
from motionbits.flow import pixel_grid, sample_maps
from motionbits.nodes import sample_bilinear
from motionbits.parallax import fit_epipole, parallax_field

__all__ = ["dominant_homography", "compensate_flow", "world_maps", "stabilize_previous",
           "fit_parallax", "compensate_camera", "CameraMotion"]

#: A node's flow is trusted for the camera fit above this forward-backward reliability
#: (``exp(-(err / fb_sigma)^2)``: 0.5 at err ~ 0.83 fb_sigma).
RELIABLE = 0.5
#: Unreliable nodes within this fraction of the grid's longer side from its border are
#: the view's blurred edge: the static world's parallax reaches the border through them.
EDGE_BAND = 0.06


def dominant_homography(points: np.ndarray, back_points: np.ndarray, reliable: np.ndarray,
                        *, threshold: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The 3x3 homography H (current -> previous, ``q ~ H p``) most nodes follow (RANSAC).

    Args:
        points, back_points: (n, 2) node positions p and their backward-flow targets q.
        reliable: (n,) bool, nodes whose flow is trustworthy (only they vote).
        threshold: px, RANSAC reprojection threshold.

    Returns:
        (H, inliers): H and the (n,) bool reliable nodes it explains; None with fewer than
        8 reliable nodes or no fit.
    """
    p = points[reliable].astype(np.float32)
    q = back_points[reliable].astype(np.float32)
    if len(p) < 8:
        return None
    h, inl = cv2.findHomography(p, q, cv2.RANSAC, threshold, maxIters=500)
    if h is None or inl is None:
        return None
    inliers = np.zeros(len(points), bool)
    inliers[reliable] = inl.ravel() > 0
    return h, inliers


def _shift(points: np.ndarray, h: np.ndarray) -> float:
    """Median px displacement of the points under h."""
    moved = cv2.perspectiveTransform(points[None].astype(np.float64), h)[0]
    return float(np.median(np.linalg.norm(moved - points, axis=1)))


def compensate_flow(flow_back: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(H, W, 2) backward flow relative to the camera: ``H^-1(p + F(p)) - p``."""
    ht, wd = flow_back.shape[:2]
    xs, ys = pixel_grid(ht, wd)
    q = np.stack(sample_maps(flow_back), -1).reshape(1, -1, 2)
    back = cv2.perspectiveTransform(q, np.linalg.inv(h))[0].reshape(ht, wd, 2)
    return np.stack([back[..., 0] - xs, back[..., 1] - ys], -1)


def world_maps(h: np.ndarray, shape: tuple[int, int],
               parallax: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 2) float32: where each pixel p of a static world was in the previous frame,
    ``H (p + P(p))`` (``parallax`` P: optional (H, W, 2) float32, :func:`fit_parallax`)."""
    ht, wd = shape
    xs, ys = pixel_grid(ht, wd)
    src = np.stack([xs, ys], -1) if parallax is None else np.stack(
        [xs + parallax[..., 0], ys + parallax[..., 1]], -1)
    return cv2.perspectiveTransform(src.reshape(1, -1, 2).astype(np.float32),
                                    h)[0].reshape(ht, wd, 2)


def stabilize_previous(prev: np.ndarray, h: np.ndarray, parallax: np.ndarray | None = None,
                       maps: np.ndarray | None = None) -> np.ndarray:
    """The previous frame in the current frame's coordinates: ``out(p) = prev(H (p + P(p)))``.

    ``parallax`` P: optional (H, W, 2) float32 static-world parallax (:func:`fit_parallax`);
    ``maps``: :func:`world_maps` of ``h`` and P if already computed.
    """
    if maps is None:
        maps = world_maps(h, prev.shape[:2], parallax)
    return cv2.remap(prev, maps, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def fit_parallax(points: np.ndarray, residual: np.ndarray, reliable: np.ndarray,
                 flow_m: np.ndarray, grid_shape: tuple[int, int], *, support: float,
                 threshold: float, view_moving: bool = False
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """The static world's parallax left by the homography, where there is some.

    Parallax is looked for only in regions of clear residual (above ``threshold``) that
    reach the image's border: the static world surrounds the view (floor, walls, the
    background beyond the homography's plane), while a body seen whole -- a car the
    camera follows, a pushed block -- is bounded by static pixels, and its motion can
    line up with an epipole as well as parallax can.

    Args:
        points, residual: (n, 2) node positions (a row-major ``grid_shape`` grid) and their
            motion relative to the homography.
        reliable: (n,) bool, nodes whose flow is trustworthy.
        flow_m: (H, W, 2) backward flow relative to the homography.
        grid_shape: (rows, cols) of the node grid.
        support: the epipole must explain the residual of at least this fraction of the
            reliable nodes (1.0 = off).
        threshold: px, as the homography's RANSAC threshold.
        view_moving: the camera was seen moving at the last frame: regions reach the
            border also through its rim of unreliable nodes (``EDGE_BAND``), and the nodes
            that fit the epipole may come within one node of the border instead of
            touching it.

    Returns:
        (field, explained, epipole): the (H, W, 2) float32 parallax, the (n,) bool nodes
        whose residual it explains and the (3,) homogeneous epipole; None where no
        parallax is found.
    """
    if support >= 1.0:
        return None
    unreliable = ~reliable.reshape(grid_shape)
    clear = (~unreliable & (np.linalg.norm(residual, axis=1) > threshold).reshape(grid_shape))
    # in a view already moving, the view's edge is blurred by nodes of no reliable flow
    # (what just came into view, flow extrapolated over the frame's edge): a region
    # reaches the border through them (in a still view, a person's sweater reaching the
    # top border through its blurred outline is no static world)
    edge = _edge_band(unreliable) if view_moving else None
    world = _reaching_border(clear, edge)
    if world.sum() < support * reliable.sum():
        return None
    fit = fit_epipole(points, residual, world.ravel(), threshold=threshold)
    if fit is None:
        return None
    # ... and the nodes that fit the epipole must reach the border themselves (an arm
    # that enters the view joins what it carries to the border, but does not fit e); in a
    # view already moving, within one node of it: its outermost ring, whose flow is
    # extrapolated as the view moves on, often misses e (pickplace under a moving camera:
    # 2844 nodes fitted e at one frame, 174 touched the border, and the camera's whole
    # model was refused there)
    inliers = fit[1].reshape(grid_shape)
    reach = (ndimage.binary_dilation(inliers, structure=np.ones((3, 3), bool)) if view_moving
             else inliers)
    explained = inliers & _reaching_border(reach, edge)
    if explained.sum() < max(8, support * reliable.sum()):
        return None
    h, w = flow_m.shape[:2]
    region, unmeasured = (cv2.resize(m.astype(np.uint8), (w, h),
                                     interpolation=cv2.INTER_NEAREST) > 0
                          for m in (explained, unreliable))
    return (parallax_field(flow_m, fit[0], region, threshold=threshold,
                           unmeasured=unmeasured), explained.ravel(), fit[0])


def _edge_band(unreliable: np.ndarray) -> np.ndarray:
    """(rows, cols) bool: the nodes of ``unreliable`` within ``EDGE_BAND`` of the grid's
    longer side from its border."""
    band = max(1, int(np.ceil(EDGE_BAND * max(unreliable.shape))))
    near = np.zeros_like(unreliable)
    near[:band] = near[-band:] = near[:, :band] = near[:, -band:] = True
    return unreliable & near


def _reaching_border(mask: np.ndarray, edge: np.ndarray | None = None) -> np.ndarray:
    """(rows, cols) bool: the 8-connected parts of ``mask`` that touch the grid's border,
    directly or through ``edge`` ((rows, cols) bool nodes that count as border)."""
    comp, _ = ndimage.label(mask if edge is None else mask | edge,
                            structure=np.ones((3, 3), bool))
    touch = at_border(comp)
    touch[0] = False  # label 0: outside the mask
    return touch[comp] & mask


class CameraMotion(NamedTuple):
    """What :func:`compensate_camera` found: the motion relative to the static world."""

    #: (H, W, 2) float32 backward flow relative to the static world's model.
    flow: np.ndarray
    #: (H, W, 3) uint8 previous frame in the current frame's coordinates.
    prev: np.ndarray
    #: (n, 2) the nodes' backward targets relative to the static world.
    back_points: np.ndarray
    #: 3x3 camera homography (current -> previous); None: no camera motion found.
    homography: np.ndarray | None
    #: (H, W, 2) float32, where each pixel of the static world was in the previous frame
    #: (the homography and its parallax, :func:`world_maps`); None: no camera motion.
    world: np.ndarray | None = None
    #: (3,) homogeneous epipole of the static world's parallax; None: none found.
    epipole: np.ndarray | None = None


def compensate_camera(points: np.ndarray, back_points: np.ndarray, reliability: np.ndarray,
                      flow_back: np.ndarray, prev: np.ndarray, *, support: float,
                      threshold: float, min_shift: float, parallax: float = 1.0,
                      grid_shape: tuple[int, int] | None = None,
                      reflow: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                      cur: np.ndarray | None = None, view_moving: bool = False) -> CameraMotion:
    """Motion measured against the dominant (camera) motion, where there is one.

    Args:
        points, back_points: (n, 2) node positions and their backward-flow targets.
        reliability: (n,) forward-backward reliability of each node's flow in [0, 1]; the
            nodes above ``RELIABLE`` fit the camera.
        flow_back: (H, W, 2) float32 backward flow (current -> previous).
        prev: (H, W, 3) uint8 previous frame.
        support: fraction of the reliable nodes that the static world's model (the
            homography's inliers *or* the parallax's) must explain; 1.0 turns compensation
            off.
        threshold: px, RANSAC reprojection threshold (homography and epipole).
        min_shift: px; the camera moved only if the homography moves the nodes by more
            than this (median).
        parallax: ``support`` of :func:`fit_parallax` (1.0, the default here: homography
            only).
        grid_shape: (rows, cols) of the node grid (``points`` row-major); needed for
            parallax.
        reflow, cur: a flow backend ``flow(a, b) -> (H, W, 2)`` and the (H, W, 3) uint8
            current frame: the motion the homography leaves is then measured again, as the
            flow from ``cur`` to the previous frame warped by the homography (small
            displacements, which a coarse-to-fine flow such as DIS measures better than the
            camera's large ones); None: ``flow_back`` composed with the homography.
        view_moving: the camera was seen moving at the last frame (parallax:
            :func:`fit_parallax`).

    Returns:
        :class:`CameraMotion`: the backward flow (H, W, 2), the previous frame and the
        nodes' backward targets (n, 2) relative to the static world (homography and
        parallax; 0 flow where the view just entered), the camera's 3x3 homography, the
        static world's (H, W, 2) map to the previous frame and the parallax's (3,)
        epipole (None where no parallax is found) -- ``flow_back``, ``prev``,
        ``back_points``, None, None, None (the same objects) when no camera motion is
        found.
    """
    if support >= 1.0:
        return CameraMotion(flow_back, prev, back_points, None)
    reliable = reliability > RELIABLE
    if reliable.sum() < support * len(points) * 0.5:
        return CameraMotion(flow_back, prev, back_points, None)
    fit = dominant_homography(points, back_points, reliable, threshold=threshold)
    if fit is None or _shift(points, fit[0]) <= min_shift:
        return CameraMotion(flow_back, prev, back_points, None)
    cam, explained = fit
    if reflow is None or cur is None:
        flow_m = compensate_flow(flow_back, cam)
    else:
        flow_m = np.array(reflow(cur, stabilize_previous(prev, cam)), np.float32)  # a copy
        # the second flow's small displacements also correct the homography (the first
        # flow's are biased where texture runs one way: wood grain, stripes)
        fix = dominant_homography(points, points + sample_bilinear(flow_m, points), reliable,
                                  threshold=threshold)
        if fix is not None:
            cam = cam @ fix[0]
            cam /= cam[2, 2]
            explained = fix[1]
            flow_m = compensate_flow(flow_m, fix[0])
    back_m = points + sample_bilinear(flow_m, points)
    par = None if grid_shape is None else fit_parallax(
        points, back_m - points, reliable, flow_m, grid_shape, support=parallax,
        threshold=threshold, view_moving=view_moving)
    if par is not None:
        explained = explained | par[1]
    # the static world's model (the homography and its parallax) must explain enough nodes
    if explained[reliable].mean() < support:
        return CameraMotion(flow_back, prev, back_points, None)
    par_field = None if par is None else par[0]
    maps = world_maps(cam, flow_m.shape[:2], par_field)
    prev_m = stabilize_previous(prev, cam, maps=maps)
    if par_field is not None:
        flow_m = flow_m - par_field
    # what has just come into view (its static-world source lies outside the previous
    # frame) has no measurable motion: its flow is extrapolated, not observed
    ht, wd = flow_m.shape[:2]
    entered = ((maps[..., 0] < 0) | (maps[..., 0] > wd - 1) | (maps[..., 1] < 0)
               | (maps[..., 1] > ht - 1))
    flow_m[entered] = 0.0
    return CameraMotion(flow_m, prev_m, points + sample_bilinear(flow_m, points), cam, maps,
                        None if par is None else par[2])
