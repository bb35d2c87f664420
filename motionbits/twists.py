"""Local SE(2) spatial twists (paper Sec. 5.1, EstimateLocalTwists).

For every node, its k nearest neighbours plus itself (N*) give point pairs
p (current frame) -> q = p + F(t->t-1)(p) (previous frame). A rigid motion q ~ R p + t is
fitted by RANSAC over minimal 2-point sets -- with 6 points there are only 15 pairs, so all
of them are tried (deterministic) -- and refined by weighted Kabsch on the inliers. The
motion is expressed about the image origin (the fixed frame {s}), where every point of one
rigid body has the same spatial twist V_s = [omega, v_x, v_y]; twists are reported for the
forward motion t-1 -> t. Everything is vectorised over all nodes.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import cv2
import numpy as np
from scipy import ndimage

from motionbits.boxes import grow_box, label_boxes, nonzero_box
from motionbits.nodes import binary_fill_holes

__all__ = ["LocalMotions", "fit_local_motions", "kabsch_2d", "se2_log", "se2_exp",
           "rigid_matrix", "nodes_to_fit", "refine_rigid_motion", "refine_moving_motions"]

#: Fast path: a node whose own flow exceeds this fraction of ``move_threshold`` seeds the
#: set of nodes whose local twist is fitted.
FIT_SEED_FRACTION = 0.5
#: Fast path: side (nodes) of the square by which the seeds are grown -- 5 = two rings of
#: the grid, a node's neighbourhood and the neighbourhoods of those.
FIT_GROWTH = 5
#: Side (px) of the square by which a MotionBit's mask is eroded before its motion is
#: refined on the images: boundary pixels mix two motions.
REFINE_ERODE = 5
#: ECC iteration cap of the refinement, and the px of context around a MotionBit's box
#: (its motion must stay inside it).
REFINE_ITERATIONS = 10
REFINE_MARGIN = 16
#: ECC stops once an iteration raises the correlation by less than this (1e-5 ran all ten
#: iterations on the built-in clip: 13.6 ms a frame; 1e-3: 9.4 ms, rotations within 3.4% of
#: the truth, 3.75% before).
REFINE_EPS = 1e-3


@dataclass(frozen=True)
class LocalMotions:
    """Per-node rigid fits.

    Attributes:
        twist: (n, 3) float64 spatial twists [omega (rad/frame), v_x, v_y (px/frame)] of the
            forward motion t-1 -> t, about the image origin.
        angle: (n,) float64 rotation of the backward motion (current -> previous), radians.
        trans: (n, 2) float64 translation of the backward motion.
        displacement: (n,) float64 |motion of the node itself| in px, from the fit.
        inliers: (n, m) bool RANSAC inliers among each node's m = k + 1 points.
    """

    twist: np.ndarray
    angle: np.ndarray
    trans: np.ndarray
    displacement: np.ndarray
    inliers: np.ndarray


def _sum_last(a: np.ndarray) -> np.ndarray:
    """``a.sum(-1)`` over a short last axis (a neighbourhood's points), as numpy sums fewer
    than 8 numbers -- in order -- but without its per-row overhead."""
    if a.shape[-1] >= 8 or a.shape[-1] < 2:
        return a.sum(-1)
    out = a[..., 0] + a[..., 1]
    for j in range(2, a.shape[-1]):
        out += a[..., j]
    return out


def kabsch_2d(p: np.ndarray, q: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weighted least-squares rigid motion q ~ R(theta) p + t, batched.

    Args:
        p, q: (..., m, 2) point sets.
        w: (..., m) non-negative weights (a batch item with all-zero weights gets the
            identity rotation).

    Returns:
        theta (...,) and t (..., 2).
    """
    ws = w.sum(-1)
    ws_safe = np.where(ws > 0, ws, 1.0)
    px, py, qx, qy = p[..., 0], p[..., 1], q[..., 0], q[..., 1]
    if p.shape[-2] < 8:  # a few points each (neighbourhoods): summed in order, per coordinate

        def mean(v: np.ndarray) -> np.ndarray:
            total = w[..., 0] * v[..., 0]
            for j in range(1, v.shape[-1]):
                total += w[..., j] * v[..., j]
            return total / ws_safe

        pmx, pmy, qmx, qmy = mean(px), mean(py), mean(qx), mean(qy)
    else:
        pm = (w[..., None] * p).sum(-2) / ws_safe[..., None]
        qm = (w[..., None] * q).sum(-2) / ws_safe[..., None]
        pmx, pmy, qmx, qmy = pm[..., 0], pm[..., 1], qm[..., 0], qm[..., 1]
    pcx, pcy = px - pmx[..., None], py - pmy[..., None]
    qcx, qcy = qx - qmx[..., None], qy - qmy[..., None]
    cross = _sum_last(w * (pcx * qcy - pcy * qcx))
    dot = _sum_last(w * (pcx * qcx + pcy * qcy))
    theta = np.arctan2(cross, dot)
    c, s = np.cos(theta), np.sin(theta)
    t = np.stack([qmx - (c * pmx - s * pmy), qmy - (s * pmx + c * pmy)], -1)
    return theta, t


def se2_log(theta: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Twist [omega, v_x, v_y] of the SE(2) element (R(theta), t), batched: (...,) , (..., 2) -> (..., 3)."""
    half = 0.5 * theta
    small = np.abs(theta) < 1e-4
    # a = (theta / 2) cot(theta / 2), with its series near 0
    a = np.where(small, 1.0 - theta**2 / 12.0, half / np.tan(np.where(small, 1.0, half)))
    vx = a * t[..., 0] + half * t[..., 1]
    vy = -half * t[..., 0] + a * t[..., 1]
    return np.stack([theta, vx, vy], -1)


def rigid_matrix(theta: float, t: np.ndarray) -> np.ndarray:
    """(2, 3) matrix of the rigid backward motion q = R(theta) p + t."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, t[0]], [s, c, t[1]]], np.float64)


def se2_exp(twist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`se2_log`: (..., 3) twists -> theta (...,), t (..., 2)."""
    theta = twist[..., 0]
    small = np.abs(theta) < 1e-4
    th = np.where(small, 1.0, theta)
    s = np.where(small, 1.0 - theta**2 / 6.0, np.sin(th) / th)
    c = np.where(small, theta / 2.0, (1.0 - np.cos(th)) / th)
    vx, vy = twist[..., 1], twist[..., 2]
    return theta, np.stack([s * vx - c * vy, c * vx + s * vy], -1)


def fit_local_motions(
    points: np.ndarray,
    back_points: np.ndarray,
    neighbors: np.ndarray,
    weights: np.ndarray,
    inlier_threshold: float,
    dtype: type = np.float64,
    nodes: np.ndarray | None = None,
    fit_fn=None,
) -> LocalMotions:
    """RANSAC (all 2-point subsets) + weighted Kabsch for every node's neighbourhood.

    Args:
        points: (n, 2) node positions p in the current frame.
        back_points: (n, 2) q = p + backward flow at p.
        neighbors: (n, k) int neighbour indices; N* = the node plus these.
        weights: (n,) reliability of each node's flow in [0, 1] (forward-backward
            consistency); the Kabsch refit and the RANSAC score are weighted by it.
        inlier_threshold: residual (px) under which a point is an inlier.
        dtype: float type of the hypothesis scoring (float32 halves its memory traffic);
            the final weighted Kabsch fits are always float64.
        nodes: optional indices of the nodes to fit; every other node gets the pure
            translation of its own flow (angle 0, all points inliers), which is what a
            neighbourhood that does not move yields up to noise.
        fit_fn: optional replacement of the neighbourhood fit with the signature of
            ``_fit_neighbourhoods`` (e.g. :meth:`motionbits.torch_ops.TorchOps.fit_neighbourhoods`).

    Returns:
        :class:`LocalMotions` for all n nodes.
    """
    n = points.shape[0]
    fit = np.arange(n) if nodes is None else np.asarray(nodes, np.int64)
    idx = np.concatenate([fit[:, None], neighbors[fit]], axis=1)  # (n', m)
    angle, trans, inliers = (fit_fn or _fit_neighbourhoods)(points, back_points, idx, weights,
                                                            inlier_threshold, dtype)
    if nodes is not None:
        angle_all = np.zeros(n)
        trans_all = (back_points - points).astype(np.float64)
        inliers_all = np.ones((n, idx.shape[1]), bool)
        angle_all[fit], trans_all[fit], inliers_all[fit] = angle, trans, inliers
        angle, trans, inliers = angle_all, trans_all, inliers_all
    x, y = points[:, 0].astype(np.float64), points[:, 1].astype(np.float64)
    c, s = np.cos(angle), np.sin(angle)
    displacement = np.hypot(c * x - s * y + trans[:, 0] - x, s * x + c * y + trans[:, 1] - y)
    twist = -se2_log(angle, trans)  # log(T^-1) = -log(T): forward motion
    return LocalMotions(twist=twist, angle=angle, trans=trans, displacement=displacement,
                        inliers=inliers)


def _fit_neighbourhoods(points, back_points, idx, weights, inlier_threshold, dtype):
    """Backward rigid motion (angle (n',), trans (n', 2)) and inliers (n', m) of each row
    of point indices ``idx`` (n', m)."""
    n, m = idx.shape
    # points as (m, n), hypotheses as (P, n), residuals as (P, m, n): every operation runs
    # along the n' neighbourhoods (numpy is slow over many short rows)
    nodes = np.ascontiguousarray(idx.T)
    px, py = (points[:, i].astype(dtype)[nodes] for i in range(2))
    qx, qy = (back_points[:, i].astype(dtype)[nodes] for i in range(2))
    w = weights.astype(dtype)[nodes]

    # every 2-point hypothesis: its rotation from the segment directions and its
    # translation from the segment midpoints, written out per coordinate (small batched
    # matrix products are slow in numpy)
    pairs = np.array(list(combinations(range(m), 2)))  # (P, 2)
    a, b = pairs[:, 0], pairs[:, 1]
    dpx, dpy = px[b] - px[a], py[b] - py[a]  # (P, n)
    dqx, dqy = qx[b] - qx[a], qy[b] - qy[a]
    theta = np.arctan2(dpx * dqy - dpy * dqx, dpx * dqx + dpy * dqy)
    c, s = np.cos(theta), np.sin(theta)
    mpx, mpy = 0.5 * (px[a] + px[b]), 0.5 * (py[a] + py[b])
    tx = 0.5 * (qx[a] + qx[b]) - (c * mpx - s * mpy)
    ty = 0.5 * (qy[a] + qy[b]) - (s * mpx + c * mpy)
    c, s = c[:, None], s[:, None]  # (P, 1, n)
    # residuals rx = c px - s py + tx - qx, ry = s px + c py + ty - qy, (P, m, n), computed
    # in place (the same operations in the same order: fewer large temporaries)
    rx, tmp = c * px, s * py
    rx -= tmp
    rx += tx[:, None]
    rx -= qx
    ry = s * px
    np.multiply(c, py, out=tmp)
    ry += tmp
    ry += ty[:, None]
    ry -= qy
    r2 = rx * rx
    r2 += np.multiply(ry, ry, out=ry)
    tau2 = inlier_threshold**2
    # MSAC cost: inliers pay their squared residual, outliers a constant
    capped = np.minimum(r2, tau2, out=rx)
    capped *= w
    cost = _sum_last(np.moveaxis(capped, 1, -1)) + 1e-9 * np.arange(len(pairs))[:, None]
    best = np.argmin(cost, axis=0)
    inliers = r2[best, :, np.arange(n)] < tau2  # (n, m)
    fit_w = weights.astype(np.float64)[idx] * inliers
    # a neighbourhood without any weighted inlier falls back to all points, unweighted
    none = fit_w.sum(1) <= 0
    fit_w[none] = 1.0
    ang, trans = kabsch_2d(points.astype(np.float64)[idx], back_points.astype(np.float64)[idx],
                           fit_w)

    return ang, trans, inliers


def nodes_to_fit(node_flow: np.ndarray, prior_nodes: np.ndarray, shape: tuple[int, int],
                 move_threshold: float) -> np.ndarray:
    """Fast path: the nodes whose local twist can matter this frame.

    A node enters the moving set if its fitted displacement exceeds the threshold, if
    it was in a MotionBit, or if it lies in a hole of that set; the graph then reads
    the twists of its neighbourhood. So: nodes whose own flow exceeds
    ``FIT_SEED_FRACTION`` of the threshold or that were in a MotionBit, grown by two rings
    of the grid (``FIT_GROWTH``: their neighbourhoods, and the neighbourhoods of those),
    with holes filled. Elsewhere nothing moves and a rigid fit only returns the flow's own
    translation.

    Args:
        node_flow: (n, 2) backward flow at each node (px).
        prior_nodes: (n,) int MotionBit id of each node at the last frame (0 = none).
        shape: (rows, cols) of the node grid, rows * cols = n.
        move_threshold: px/frame, the config's ``move_threshold``.

    Returns:
        (m,) int64 sorted indices of the nodes to fit.
    """
    seed = (np.hypot(node_flow[:, 0], node_flow[:, 1]) > FIT_SEED_FRACTION * move_threshold) | (
        prior_nodes != 0)
    grown = cv2.dilate(seed.reshape(shape).astype(np.uint8), np.ones((FIT_GROWTH, FIT_GROWTH),
                                                                    np.uint8))
    return np.flatnonzero(binary_fill_holes(grown > 0))


def refine_rigid_motion(cur_gray: np.ndarray, prev_gray: np.ndarray, mask: np.ndarray,
                        theta: float, t: np.ndarray, *, iterations: int = REFINE_ITERATIONS,
                        margin: int = REFINE_MARGIN) -> tuple[float, np.ndarray]:
    """Refine a rigid backward motion q = R(theta) p + t of the pixels ``mask`` on the images
    themselves (OpenCV's ECC alignment, Euclidean model, started from the given motion).

    Optical flow is regularised: it pulls a body's rotation toward its surroundings' (DIS
    reads the demo's rotations 15-20% low). Aligning the body's own pixels removes that
    bias. Falls back to the given motion where ECC does not converge.

    Args:
        cur_gray, prev_gray: (H, W) float32 grey frames.
        mask: (H, W) bool pixels of the body in the current frame.
        theta, t: the starting backward motion (radians; (2,) px).
        iterations: ECC iteration cap.
        margin: px of context around the mask's box (the motion must stay inside it).

    Returns:
        theta, t (2,) of the refined backward motion.
    """
    box = ndimage.find_objects(mask.astype(np.uint8))
    if not box:
        return theta, np.asarray(t, np.float64)
    return _refine_in_box(cur_gray, prev_gray, mask, 1, box[0], theta, t,
                          iterations=iterations, margin=margin)


def _refine_in_box(cur_gray: np.ndarray, prev_gray: np.ndarray, labels: np.ndarray, lab: int,
                   box: tuple[slice, slice], theta: float, t: np.ndarray, *, iterations: int,
                   margin: int) -> tuple[float, np.ndarray]:
    """:func:`refine_rigid_motion` of the pixels ``labels == lab``, all inside ``box`` (their
    bounding box); only the box grown by ``margin`` is read."""
    rows, cols = grow_box(box, margin, labels.shape)
    y0, y1, x0, x1 = rows.start, rows.stop, cols.start, cols.stop
    mask = labels[y0:y1, x0:x1] == lab
    if np.count_nonzero(mask) < 16:
        return theta, np.asarray(t, np.float64)
    c, s = np.cos(theta), np.sin(theta)
    # the same motion in crop coordinates: q' = R (p' + o) + t - o
    off = np.array([x0, y0], np.float64)
    tc = np.array([[c, -s], [s, c]]) @ off + np.asarray(t, np.float64) - off
    warp = np.array([[c, -s, tc[0]], [s, c, tc[1]]], np.float32)
    try:
        _, warp = cv2.findTransformECC(
            cur_gray[y0:y1, x0:x1], prev_gray[y0:y1, x0:x1], warp, cv2.MOTION_EUCLIDEAN,
            (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, iterations, REFINE_EPS),
            mask.astype(np.uint8), 1)
    except cv2.error:
        return theta, np.asarray(t, np.float64)
    th = float(np.arctan2(warp[1, 0], warp[0, 0]))
    r = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return th, warp[:, 2].astype(np.float64) + off - r @ off


def refine_moving_motions(cur_gray: np.ndarray, prev_gray: np.ndarray, labels: np.ndarray,
                          ids: np.ndarray, thetas: np.ndarray, trans: np.ndarray,
                          moving: set[int]) -> tuple[np.ndarray, np.ndarray]:
    """The motions of the moving MotionBits refined on their own pixels
    (:func:`refine_rigid_motion` on each mask eroded by ``REFINE_ERODE``; flow reads
    rotations low); the others are kept.

    Args:
        cur_gray, prev_gray: (H, W) float32 grey frames.
        labels: (H, W) int32 label map of the current frame.
        ids: (K,) MotionBit ids with backward motions ``thetas`` (K,) and ``trans`` (K, 2).
        moving: the ids to refine.

    Returns:
        thetas (K,) float64 and trans (K, 2) float64, new arrays.
    """
    thetas, trans = thetas.copy(), trans.copy()
    todo = [k for k, lab in enumerate(ids) if lab in moving]
    if not todo:
        return thetas, trans
    small = labels.max() < 1 << 16  # uint16 morphology (faster) where the ids fit
    # on the labels' box grown by the erosion's reach: the whole image's erosion, which is
    # 0 outside that box
    box = grow_box(nonzero_box(labels), REFINE_ERODE // 2, labels.shape)
    inner = np.zeros(labels.shape, np.int32)
    inner[box] = cv2.erode(labels[box].astype(np.uint16 if small else np.float32),
                           np.ones((REFINE_ERODE, REFINE_ERODE), np.uint8))
    boxes = label_boxes(inner, max_label=max(int(ids[k]) for k in todo))
    for k in todo:
        box = boxes[int(ids[k]) - 1]
        if box is not None:
            thetas[k], trans[k] = _refine_in_box(cur_gray, prev_gray, inner, int(ids[k]), box,
                                                 thetas[k], trans[k], iterations=REFINE_ITERATIONS,
                                                 margin=REFINE_MARGIN)
    return thetas, trans
