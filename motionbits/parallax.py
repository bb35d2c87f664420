"""Plane + parallax: the static world's motion that a camera homography leaves (ours).

A camera that translates through a 3D scene moves each static point by the homography H
of one plane plus a *parallax* residual that points along the line through the point and
the epipole e (the image of the other camera centre), with a magnitude that grows with
the point's distance from the plane (Irani & Anandan, "Parallax geometry of pairs of
points", 1996). After the homography is removed (``camera.compensate_flow``) the static
world's residual r(p) therefore satisfies ``r(p) x (p - e) = 0`` for one e shared by the
whole image; an independently moving body breaks that (a body moving exactly along its
epipolar lines is the model's blind spot).

:func:`fit_epipole` finds e by RANSAC over node pairs (two residual lines meet at e; e may
lie at infinity, so it is homogeneous); :func:`parallax_field` turns it into a dense (H, W, 2)
field: the along-line residual where a pixel's residual lies on its epipolar line and
exceeds the threshold, in the region where the nodes found parallax and in the aligned
pixels connected to it; a smooth interpolation of it elsewhere in that region (so a slow
or misaligned body is measured against its surroundings' parallax, not erased); 0 outside.
"""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np

from motionbits.boxes import pieces_holding
from motionbits.flow import pixel_grid

__all__ = ["epipolar_distance", "fit_epipole", "parallax_field", "along_epipolar_lines",
           "moves_along_lines",
           "ParallaxOnly", "ALONG_MIN_PX", "ALONG_MIN_NODES", "ALONG_SINE", "ALONG_PX",
           "PIXEL_ALONG_PX",
           "OWN_PX", "JUMP", "PARALLAX_FRAMES", "OFF_LINES_EVERY", "ALONG", "OFF",
           "OWN"]

#: RANSAC hypotheses (node pairs) tried for the epipole; fixed seed, so runs repeat.
EPIPOLE_ITERS = 200
#: Gaussian sigma of the interpolated parallax, in multiples of the image's longer side.
SMOOTH_FRACTION = 0.03
#: A MotionBit moves along its epipolar lines at a frame when, over those of its nodes
#: that moved more than this many px relative to the static world's model ...
#: (round 39: 1 px, was 2; tall static boxes under an orbiting camera move 1-2.5 px a frame
#: through parallax, and at 2 px most of their frames did not count)
ALONG_MIN_PX = 1.0
#: ... (at least this many nodes; else the frame does not count) ...
ALONG_MIN_NODES = 4
#: ... the median of (px off the epipolar line / the larger of ALONG_SINE x px moved and
#: ALONG_PX) is below 1: off the line by less than about 3 degrees (a tall static cylinder
#: read through parallax, 0.01-0.03 at its 7 such frames; bodies carried or pushed under a
#: moving camera, 0.06-0.29 at one such frame at least) ...
ALONG_SINE = 0.05
#: ... or by less than this many px, DIS's error: round 39, tall static bodies moving
#: 1-2.5 px a frame through parallax left their lines by 0.02-0.3 px (median over their
#: nodes; 0.05-0.19 of the px moved) at nearly every frame, and were shown (0.3 px then).
#: Round 66: under orbiting cameras, static marks read along their lines at most frames
#: were 0.3-0.6 px off them at one to five (2-5 px of parallax a frame; held34-36), bodies
#: 0.67-1.5 px at the frames they were not along.
ALONG_PX = 0.6
#: The same test per pixel (:func:`moves_along_lines`, the arrivals' memory) keeps round
#: 65's 0.3 px: at 0.6 a block knocked slowly off its lines was no longer seen moving there
#: and was not found where it arrived (held36 seed-673 scene_0015).
PIXEL_ALONG_PX = 0.3
#: A frame at which that median is more than this many px off the lines is a motion of the
#: MotionBit's own (a block knocked, then standing still: a tall one keeps moving along
#: its lines through parallax afterwards); it is never parallax only. Round 39: bodies
#: knocked left their lines by 4-7 px at that frame.
OWN_PX = 2.0
#: A frame at which a MotionBit moved more than this many times as fast as its median over
#: its measured frames (each over ``ALONG_MIN_PX``: so by more than 4 px) is a motion of
#: its own too: a static body's parallax follows the camera's smooth motion; a block
#: knocked nearly along its epipolar lines leaves them by less than ``OWN_PX``, but jumps
#: (round 63: 10.1 px at its knock, 0.97 px off its lines, then 1.0-1.4 px of parallax at
#: its six frames at rest; held32 seed-593 scene_0002).
JUMP = 4.0
#: What :func:`along_epipolar_lines` says of a MotionBit at a frame.
ALONG, OFF, OWN = "along", "off", "own"
#: ... and it is a static body read through parallax once it moved so at this many such
#: frames (:class:`ParallaxOnly`) ...
PARALLAX_FRAMES = 3
#: ... and otherwise at no more than one frame in this many of those: one frame's flow
#: error or a wrong epipole is no motion of its own (round 37: a tall static cylinder
#: along its lines at 7 frames and off them at 1 was shown, and grouped with the block
#: knocked beside it).
OFF_LINES_EVERY = 5


def _homogeneous(p: np.ndarray) -> np.ndarray:
    return np.concatenate([p, np.ones(p.shape[:-1] + (1,), p.dtype)], -1)


def epipolar_distance(points: np.ndarray, residual: np.ndarray, e: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """How far each residual leaves its epipolar line, and the unit line direction.

    Args:
        points: (..., 2) float positions p.
        residual: (..., 2) float residual motion r at p.
        e: (3,) homogeneous epipole, or (3, ...) several, broadcast against the points.

    Returns:
        (dist, u): (...) px distance of ``p + r`` from the line through p and e, and
        (..., 2) the line's unit direction at p (0 where p is the epipole).
    """
    e = np.asarray(e, np.float64)
    # the line p x e through p = (x, y, 1) and e: (y e_w - e_y, e_x - x e_w, ...)
    lx = points[..., 1] * e[2] - e[1]
    ly = e[0] - points[..., 0] * e[2]
    norm = np.hypot(lx, ly)
    safe = np.where(norm > 1e-12, norm, 1.0)
    dist = np.abs(lx * residual[..., 0] + ly * residual[..., 1]) / safe
    u = np.stack([ly, -lx], -1) / safe[..., None]
    return dist, np.where((norm > 1e-12)[..., None], u, 0.0)


def fit_epipole(points: np.ndarray, residual: np.ndarray, candidates: np.ndarray, *,
                threshold: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The epipole that the most residuals point along, by RANSAC over pairs of nodes.

    Args:
        points: (n, 2) node positions.
        residual: (n, 2) their motion left by the camera homography.
        candidates: (n,) bool, nodes with a clear residual (above ``threshold``) and
            reliable flow: they vote.
        threshold: px, a residual within this distance of its epipolar line fits e.

    Returns:
        (e, inliers): the (3,) homogeneous epipole, refined by least squares on its
        inliers, and the (n,) bool candidates it explains; None with fewer than 8
        candidates.
    """
    idx = np.flatnonzero(candidates)
    if len(idx) < 8:
        return None
    p = points[idx].astype(np.float64)
    lines = np.cross(_homogeneous(p), _homogeneous(p + residual[idx]))
    lines /= np.hypot(lines[:, 0], lines[:, 1])[:, None] + 1e-12
    rng = np.random.default_rng(0)
    pairs = rng.integers(0, len(idx), size=(EPIPOLE_ITERS, 2))
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    hyp = np.cross(lines[pairs[:, 0]], lines[pairs[:, 1]])
    hyp = hyp[np.linalg.norm(hyp, axis=1) > 1e-12]
    if not len(hyp):
        return None
    # all hypotheses scored at once: (hypotheses, candidates)
    dists = epipolar_distance(p[None], residual[idx][None], hyp.T[:, :, None])[0]
    # MSAC: truncated squared distances, so that the most precise of the hypotheses with
    # many inliers wins
    best = hyp[np.argmin((np.minimum(dists, threshold) ** 2).sum(1))]
    best_dist = epipolar_distance(p, residual[idx], best)[0]
    inl = best_dist < threshold
    # least squares on the inliers, each residual line weighted so that its term is the
    # residual's px distance from its epipolar line (one reweighting step from ``best``)
    hp = _homogeneous(p[inl])
    e0 = best / np.linalg.norm(best)
    across = np.linalg.norm(np.cross(hp, e0)[:, :2], axis=1)
    weight = np.linalg.norm(residual[idx][inl], axis=1) / np.maximum(across, 1e-9)
    e = np.linalg.svd(lines[inl] * weight[:, None], full_matrices=False)[2][-1]
    e_dist = epipolar_distance(p, residual[idx], e)[0]
    if (np.minimum(e_dist, threshold) ** 2).sum() <= (np.minimum(best_dist, threshold) ** 2).sum():
        best, best_dist = e, e_dist
    out = np.zeros(len(points), bool)
    out[idx] = best_dist < threshold
    return best, out


def parallax_field(residual: np.ndarray, e: np.ndarray, region: np.ndarray, *,
                   threshold: float, unmeasured: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 2) float32 parallax of the static world at every pixel.

    Args:
        residual: (H, W, 2) float32 motion left by the camera homography (backward).
        e: (3,) homogeneous epipole (:func:`fit_epipole`).
        region: (H, W) bool, where the static world's parallax was found (at the nodes).
        threshold: px; a pixel whose residual exceeds this and lies within it of its
            epipolar line ("aligned") keeps its own along-line residual if it is in
            ``region`` or 8-connected to it through aligned pixels of ``unmeasured``; the other
            pixels of ``region`` get the smooth interpolation of those pixels' parallax
            (Gaussian, ``SMOOTH_FRACTION`` of the longer side); pixels outside get 0 (the
            homography's plane beside a parallax region has none of its parallax: on the
            moving-camera scenes, the smooth interpolation spread beyond the region left
            16% of the plane's static pixels moving > 1 px, 8% without).
        unmeasured: (H, W) bool, where the nodes could not tell (their flow was
            unreliable: the floor far below a table, whose large parallax DIS misreads
            at its edges); None: nowhere. A body next to the region is not reached
            through its own reliable nodes.
    """
    h, w = residual.shape[:2]
    xs, ys = pixel_grid(h, w)
    dist, u = epipolar_distance(np.stack([xs, ys], -1), residual, e)
    along = (residual[..., 0] * u[..., 0] + residual[..., 1] * u[..., 1])
    aligned = (dist < threshold) & (np.abs(along) > threshold)
    aligned &= region if unmeasured is None else region | unmeasured
    fits = pieces_holding(aligned, region)
    own = (along[..., None] * u).astype(np.float32)
    # normalised convolution of the fitting pixels' parallax, at 1/4 size for speed
    small = (max(1, w // 4), max(1, h // 4))
    sigma = SMOOTH_FRACTION * max(h, w) / 4
    weight = cv2.GaussianBlur(cv2.resize(fits.astype(np.float32), small,
                                         interpolation=cv2.INTER_AREA), (0, 0), sigma)
    num = cv2.GaussianBlur(cv2.resize(np.where(fits[..., None], own, 0).astype(np.float32),
                                      small, interpolation=cv2.INTER_AREA), (0, 0), sigma)
    smooth = cv2.resize(num / np.maximum(weight, 1e-3)[..., None], (w, h),
                        interpolation=cv2.INTER_LINEAR)
    smooth *= cv2.resize(np.minimum(weight / 0.05, 1.0), (w, h))[..., None]  # no support: 0
    return np.where(fits[..., None], own,
                    np.where(region[..., None], smooth, 0)).astype(np.float32)


def moves_along_lines(flow: np.ndarray, e: np.ndarray) -> np.ndarray:
    """(H, W) bool: the pixels whose motion relative to the static world's model lies on
    their epipolar line of ``e`` ((3,) homogeneous), as :func:`along_epipolar_lines`
    judges a MotionBit's nodes, but per pixel: off it by less than ``ALONG_SINE`` x the
    px moved or ``PIXEL_ALONG_PX`` -- a static body's parallax (``flow``: (H, W, 2)
    float32 backward flow relative to that model).

    Raises:
        ValueError: ``e`` is not a non-zero 3-vector.
    """
    e = np.asarray(e, np.float64)
    norm = np.linalg.norm(e) if e.shape == (3,) else 0.0
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError(f"the epipole must be a finite, non-zero homogeneous 3-vector, got {e!r}")
    h, w = flow.shape[:2]
    e = e / norm
    # the line through p = (x, y, 1) and e is (lx, ly, .) with lx a function of y and ly
    # of x alone (:func:`epipolar_distance`): the distance test is squared and broadcast
    lx = (np.arange(h) * e[2] - e[1]).astype(np.float32)[:, None]
    ly = (e[0] - np.arange(w) * e[2]).astype(np.float32)[None, :]
    fx, fy = flow[..., 0], flow[..., 1]
    across = lx * fx + ly * fy  # px off the line times the line's norm
    tolerance = np.maximum(ALONG_SINE ** 2 * (fx * fx + fy * fy),
                           np.float32(PIXEL_ALONG_PX ** 2))
    return across * across <= tolerance * (lx * lx + ly * ly)


def along_epipolar_lines(points: np.ndarray, residual: np.ndarray, node_ids: np.ndarray,
                         ids: Iterable[int], e: np.ndarray) -> dict[int, str]:
    """How the MotionBits move against the epipolar lines of ``e`` at this frame.

    Args:
        points, residual: (n, 2) node positions and their motion relative to the static
            world's model (the camera's homography and the parallax found).
        node_ids: (n,) int MotionBit id of each node (0 = none).
        ids: the MotionBit ids to judge.
        e: (3,) homogeneous epipole (:func:`fit_epipole`).

    Returns:
        id -> ``ALONG``, ``OFF`` or ``OWN``, for the ids with ``ALONG_MIN_NODES`` nodes or
        more that moved more than ``ALONG_MIN_PX``: over those nodes, ``ALONG`` where the
        median of (px off the epipolar line / max(``ALONG_SINE`` x px moved, ``ALONG_PX``))
        is below 1, ``OWN`` where the median px off the line is above ``OWN_PX``, else
        ``OFF``.
    """
    return {i: how for i, (how, _) in _judge(points, residual, node_ids, ids, e).items()}


def _judge(points: np.ndarray, residual: np.ndarray, node_ids: np.ndarray,
           ids: Iterable[int], e: np.ndarray) -> dict[int, tuple[str, float]]:
    """:func:`along_epipolar_lines`, with the median px moved by each id's nodes that
    moved more than ``ALONG_MIN_PX``: id -> (how, px)."""
    size = np.linalg.norm(residual, axis=1)
    fast = size > ALONG_MIN_PX
    if not fast.any():
        return {}
    size = size[fast]
    off = epipolar_distance(points[fast], residual[fast], e)[0]
    ratio = off / np.maximum(ALONG_SINE * size, ALONG_PX)
    owner = node_ids[fast]
    out = {}
    for i in ids:
        mine = owner == i
        if np.count_nonzero(mine) >= ALONG_MIN_NODES:
            out[int(i)] = (ALONG if np.median(ratio[mine]) < 1.0
                           else OWN if np.median(off[mine]) > OWN_PX else OFF,
                           float(np.median(size[mine])))
    return out


class ParallaxOnly:
    """The MotionBits whose motion has only ever been the static world's parallax.

    Parallax is looked for in the regions that reach the image's border (``fit_parallax``
    in ``motionbits/camera.py``), so a tall static body standing on the table, bounded by
    the table's plane, keeps its parallax as motion and is born as a MotionBit. Its motion
    lies along the epipolar lines at every frame, as the camera moves on; a body that moves
    by itself leaves them at some frame (a body moved exactly along them is the blind spot
    of plane + parallax, docs/reading_the_paper.md, "Moving cameras", round 36). Per
    MotionBit this counts the frames at which an epipole was known and it moved measurably
    (:func:`along_epipolar_lines`), and how many of those along the lines. A MotionBit
    found at rest where its body came to stand (:meth:`arrived`) moved by itself before
    it was found, and is never parallax only (round 58: blocks knocked, found where they
    stopped, then read moving along their lines through parallax, were hidden).
    """

    def __init__(self) -> None:
        # id -> (median px moved, whether along the lines) at each of its measured frames
        self._frames: dict[int, list[tuple[float, bool]]] = {}
        self._own: set[int] = set()  # ids seen moving by themselves (``OWN``) at some frame

    def observe(self, points: np.ndarray, residual: np.ndarray, node_ids: np.ndarray,
                moving: Iterable[int], e: np.ndarray) -> None:
        """Count this frame for the MotionBits ``moving`` (arguments as
        :func:`along_epipolar_lines`)."""
        for i, (how, speed) in _judge(points, residual, node_ids, moving, e).items():
            self._frames.setdefault(i, []).append((speed, how == ALONG))
            if how == OWN:
                self._own.add(i)

    def arrived(self, ids: Iterable[int]) -> None:
        """The MotionBits ``ids`` were found at rest where their body had come to stand
        (set down, or arrived: :class:`motionbits.setdown.SetDown`'s pieces): they moved
        by themselves, whatever the camera's parallax does to them afterwards."""
        self._own.update(int(i) for i in ids)

    def ids(self, present: Iterable[int]) -> set[int]:
        """Of the ids ``present``, those that moved along the epipolar lines at
        ``PARALLAX_FRAMES`` measured frames or more, otherwise at no more than one in
        ``OFF_LINES_EVERY`` of those, never by themselves (``OWN``), and never more than
        ``JUMP`` times as fast as at their median measured frame."""
        out = set()
        for i in present:
            frames = self._frames.get(int(i), [])
            lined = sum(along for _, along in frames)
            if (lined >= PARALLAX_FRAMES and len(frames) - lined <= lined // OFF_LINES_EVERY
                    and int(i) not in self._own):
                speeds = [speed for speed, _ in frames]
                if max(speeds) <= JUMP * float(np.median(speeds)):  # no jump
                    out.add(int(i))
        return out
