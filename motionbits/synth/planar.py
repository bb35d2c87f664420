"""Planar scenes: textured rigid polygons moving over a textured static background.

Every body follows an exact SE(2) trajectory, so the ground truth is exact: the label map
of each frame marks the visible pixels of every body that has moved up to that frame
(MotionBits definition, paper eq. 4). These clips are the built-in default input of the
CLI and the test scenes of the segmenter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from motionbits.frames import finite_number, whole_number

__all__ = ["Polygon", "Body", "PlanarClip", "render_planar_clip", "demo_clip", "smooth_texture"]

_SUPERSAMPLE = 2  # render at 2x and downsample: anti-aliased edges like a real camera
MAX_FRAME_PIXELS = 4096 * 4096  # H x W of one frame (rendered at 2x: ~2 GB of body layers)
MAX_CLIP_PIXELS = 2 ** 28  # n_frames x H x W (frames and labels: 7 bytes a pixel, ~1.9 GB)


def _check_size(size: Any) -> tuple[int, int]:
    """``size`` as (H, W), two whole numbers >= 1 (else OpenCV's "inv_scale_x > 0", numpy's
    "negative dimensions are not allowed", or an IndexError) of at most ``MAX_FRAME_PIXELS``
    pixels (else a MemoryError, or minutes of swapping)."""
    if (isinstance(size, (str, bytes)) or not isinstance(size, Sequence) or len(size) != 2
            or any(whole_number("size", v) < 1 for v in size)):
        raise ValueError(f"size must be (height, width), two whole numbers >= 1, got {size!r:.40}")
    h, w = int(size[0]), int(size[1])
    if h * w > MAX_FRAME_PIXELS:
        raise ValueError(f"size must be at most {MAX_FRAME_PIXELS:,} pixels (4096 x 4096) a frame, "
                         f"got {h} x {w}")
    return h, w


@dataclass(frozen=True)
class Polygon:
    """A filled polygon with its own texture. ``points``: (N, 2) float (x, y) pixels at frame 0."""

    points: tuple[tuple[float, float], ...]
    texture_seed: int = 0

    def __post_init__(self) -> None:
        pts = np.asarray(self.points, dtype=object)
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 3:  # else OpenCV's fillPoly assertion
            raise ValueError(f"a Polygon's points must be at least 3 (x, y) pairs, got {self.points!r:.60}")
        for v in pts.ravel():  # drawn as int32 at 2x: 1e12 wrapped (and took 15 s)
            if abs(finite_number("a Polygon's point coordinate", v)) > 1e9:
                raise ValueError(f"a Polygon's point coordinate must be within +-1e9 px, got {v!r}")
        if whole_number("texture_seed", self.texture_seed) < 0:
            raise ValueError(f"texture_seed must be >= 0, got {self.texture_seed}")

    @staticmethod
    def rect(x0: float, y0: float, x1: float, y1: float, texture_seed: int = 0) -> "Polygon":
        return Polygon(((x0, y0), (x1, y0), (x1, y1), (x0, y1)), texture_seed)

    @staticmethod
    def regular(cx: float, cy: float, radius: float, sides: int, phase: float = 0.0,
                texture_seed: int = 0) -> "Polygon":
        if whole_number("sides", sides) < 3:  # 2.5 drew a triangle
            raise ValueError(f"sides must be >= 3, got {sides}")
        a = phase + 2 * np.pi * np.arange(sides) / sides
        return Polygon(tuple(zip(cx + radius * np.cos(a), cy + radius * np.sin(a))), texture_seed)


@dataclass(frozen=True)
class Body:
    """One rigid body: one or more glued polygons and a piecewise-constant SE(2) motion.

    During frames ``start < f <= stop`` the body turns by ``omega`` rad per frame about
    ``pivot`` (image coordinates at frame 0, carried with the body) and translates by
    ``velocity`` px per frame; before and after, it rests. ``omega = 0`` and
    ``velocity = (0, 0)`` is a static distractor.
    """

    polygons: tuple[Polygon, ...]
    omega: float = 0.0
    velocity: tuple[float, float] = (0.0, 0.0)
    pivot: tuple[float, float] | None = None  # default: centroid of the polygons
    start: int = 0
    stop: int | None = None

    def __post_init__(self) -> None:
        if (isinstance(self.polygons, (str, bytes)) or not isinstance(self.polygons, Sequence)
                or not self.polygons or not all(isinstance(p, Polygon) for p in self.polygons)):
            raise TypeError(f"a Body's polygons must be a non-empty tuple of Polygon, got {self.polygons!r:.60}")
        finite_number("omega", self.omega)
        for name, pair in (("velocity", self.velocity), ("pivot", self.pivot)):
            if pair is None and name == "pivot":
                continue
            if isinstance(pair, (str, bytes)) or not isinstance(pair, Sequence) or len(pair) != 2:
                raise ValueError(f"{name} must be an (x, y) pair, got {pair!r:.40}")
            for v in pair:
                finite_number(name, v)
        whole_number("start", self.start)  # 1.5 started the motion between frames
        if self.stop is not None:
            whole_number("stop", self.stop)

    def moves(self, n_frames: int) -> bool:
        active = min(self.stop if self.stop is not None else n_frames, n_frames - 1) - self.start
        return active > 0 and (self.omega != 0.0 or any(v != 0.0 for v in self.velocity))

    def pose(self, frame: int) -> np.ndarray:
        """(2, 3) affine matrix mapping frame-0 coordinates to coordinates at ``frame``."""
        end = self.stop if self.stop is not None else frame
        steps = float(np.clip(min(frame, end) - self.start, 0, None))
        pts = np.concatenate([np.asarray(p.points, float) for p in self.polygons])
        px, py = self.pivot if self.pivot is not None else pts.mean(axis=0)
        th = self.omega * steps
        c, s = np.cos(th), np.sin(th)
        tx = px - (c * px - s * py) + self.velocity[0] * steps
        ty = py - (s * px + c * py) + self.velocity[1] * steps
        return np.array([[c, -s, tx], [s, c, ty]])


@dataclass
class PlanarClip:
    """A rendered clip with exact ground truth.

    Attributes:
        frames: (T, H, W, 3) uint8 RGB.
        labels: (T, H, W) int32 per-frame ground truth: body ``i`` (1-based, in ``bodies``
            order among moving bodies) where it is visible and has moved by that frame.
        bodies: the bodies, in drawing order (later ones on top).
        ids: body index -> ground-truth label (0 for bodies that never move in the clip).
    """

    frames: np.ndarray
    labels: np.ndarray
    bodies: tuple[Body, ...]
    ids: dict[int, int] = field(default_factory=dict)

    @property
    def gt(self) -> np.ndarray:
        """(H, W) int32 ground truth of the last frame (the MoRiBo convention)."""
        return self.labels[-1]


def smooth_texture(shape: tuple[int, int], rng: np.random.Generator, *, scales=(4, 16, 48),
                   contrast: float = 1.0) -> np.ndarray:
    """(H, W, 3) uint8 multi-scale coloured noise: enough texture for optical flow."""
    h, w = shape
    acc = np.zeros((h, w, 3), np.float32)
    for s in scales:
        small = rng.normal(size=(max(2, h // s), max(2, w // s), 3)).astype(np.float32)
        acc += cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    acc /= acc.std() + 1e-6
    base = rng.uniform(60, 190, size=3).astype(np.float32)
    mix = rng.normal(scale=30 * contrast, size=(3, 3)).astype(np.float32)
    return np.clip(base + acc @ mix, 0, 255).astype(np.uint8)


def _body_layer(body: Body, shape_ss: tuple[int, int], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Texture and mask of a body at frame 0, at the supersampled size."""
    h, w = shape_ss
    tex = np.zeros((h, w, 3), np.uint8)
    mask = np.zeros((h, w), np.uint8)
    for poly in body.polygons:
        pts = np.round(np.asarray(poly.points) * _SUPERSAMPLE).astype(np.int32)
        m = np.zeros((h, w), np.uint8)
        cv2.fillPoly(m, [pts], 1)
        t = smooth_texture((h, w), np.random.default_rng([seed, poly.texture_seed]),
                           scales=(6, 20), contrast=1.2)
        tex[m > 0] = t[m > 0]
        mask |= m
    return tex, mask


def render_planar_clip(bodies: list[Body] | tuple[Body, ...], *, size: tuple[int, int] = (480, 640),
                       n_frames: int = 12, seed: int = 0, noise: float = 1.5) -> PlanarClip:
    """Render ``bodies`` over a textured background.

    Args:
        bodies: drawn in order, later bodies on top.
        size: (H, W) of the output frames.
        n_frames: number of frames T >= 1.
        seed: texture and noise seed; same seed and bodies -> identical clip.
        noise: standard deviation of per-frame Gaussian sensor noise (grey levels).

    Returns:
        A :class:`PlanarClip`.

    Raises:
        TypeError / ValueError: ``bodies`` is not a sequence of :class:`Body`, ``size`` not
            two whole numbers >= 1 (at most ``MAX_FRAME_PIXELS`` pixels, and
            ``n_frames`` x H x W at most ``MAX_CLIP_PIXELS``), ``n_frames`` not a whole number >= 1, ``seed`` not a
            whole number >= 0, or ``noise`` not a finite number >= 0.
    """
    if whole_number("n_frames", n_frames) < 1:
        raise ValueError(f"n_frames must be >= 1, got {n_frames}")
    n_frames = int(n_frames)
    h, w = _check_size(size)
    if whole_number("seed", seed) < 0:  # else numpy's "expected non-negative integer"
        raise ValueError(f"seed must be >= 0, got {seed}")
    if finite_number("noise", noise) < 0:  # NaN and inf noise gave black / saturated frames
        raise ValueError(f"noise must be >= 0, got {noise}")
    if n_frames * h * w > MAX_CLIP_PIXELS:  # else a MemoryError (or swapping) part-way
        raise ValueError(f"n_frames x height x width must be at most {MAX_CLIP_PIXELS:,} pixels "
                         f"(~1.9 GB of frames and labels), got {n_frames} x {h} x {w}")
    if (isinstance(bodies, (str, bytes)) or not isinstance(bodies, Sequence)
            or not all(isinstance(b, Body) for b in bodies)):  # a Polygon: AttributeError
        raise TypeError(f"bodies must be a list of Body, got {bodies!r:.60}")
    hs, ws = h * _SUPERSAMPLE, w * _SUPERSAMPLE
    rng = np.random.default_rng(seed)
    background = smooth_texture((h, w), rng, contrast=0.8)
    layers = [_body_layer(b, (hs, ws), seed * 1000 + i + 1) for i, b in enumerate(bodies)]
    movers = [i for i, b in enumerate(bodies) if b.moves(n_frames)]
    ids = {i: movers.index(i) + 1 if i in movers else 0 for i in range(len(bodies))}

    frames = np.empty((n_frames, h, w, 3), np.uint8)
    labels = np.zeros((n_frames, h, w), np.int32)
    scale = np.diag([_SUPERSAMPLE, _SUPERSAMPLE, 1.0])
    for f in range(n_frames):
        img = background.astype(np.float32)
        for i, (body, (tex, mask)) in enumerate(zip(bodies, layers)):
            a = np.vstack([body.pose(f), [0, 0, 1]])
            a_ss = (scale @ a @ np.linalg.inv(scale))[:2]
            tex_f = cv2.warpAffine(tex, a_ss, (ws, hs), flags=cv2.INTER_LINEAR)
            mask_f = cv2.warpAffine(mask * 255, a_ss, (ws, hs), flags=cv2.INTER_LINEAR)
            alpha = cv2.resize(mask_f, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32) / 255
            col = cv2.resize(tex_f, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32)
            # the texture is black outside its mask, so ``col`` is premultiplied by alpha
            img = img * (1 - alpha[..., None]) + col
            moved = ids[i] > 0 and body.start < f
            visible = alpha >= 0.5
            labels[f][visible] = ids[i] if moved else 0
        if noise > 0:
            img = img + rng.normal(scale=noise, size=img.shape)
        frames[f] = np.clip(np.round(img), 0, 255).astype(np.uint8)
    return PlanarClip(frames=frames, labels=labels, bodies=tuple(bodies), ids=ids)


def demo_clip(n_frames: int = 16, size: tuple[int, int] = (480, 640), seed: int = 0) -> PlanarClip:
    """The built-in demo: the cases the segmenter must handle, in one 480x640 scene.

    - a hexagon rotating about a pivot far from its centre;
    - a quad in pure translation;
    - two differently textured shapes glued into one body;
    - two touching bodies with different motions;
    - a body that moves, then stops;
    - a static distractor (never moves: background).
    Geometry is given for 480x640 and scaled to ``size``.
    """
    size = _check_size(size)  # before scaling: an int size failed with "not subscriptable"
    sy, sx = size[0] / 480.0, size[1] / 640.0

    def p(x: float, y: float) -> tuple[float, float]:
        return (x * sx, y * sy)

    def poly(points, seed_):
        return Polygon(tuple(p(*q) for q in points), seed_)

    def rect(x0, y0, x1, y1, seed_):
        return poly(((x0, y0), (x1, y0), (x1, y1), (x0, y1)), seed_)

    hexagon = poly(Polygon.regular(120, 130, 55, 6).points, 1)
    bodies = [
        # rotation about a pivot 160 px away from the centre: mostly a swing
        Body((hexagon,), omega=0.02, pivot=p(260, 170)),
        # pure translation
        Body((rect(420, 60, 520, 150, 2),), velocity=(-2.5 * sx, 1.5 * sy)),
        # glued pair: a square and a triangle with different textures, one rigid body
        Body((rect(90, 300, 170, 380, 3), poly(((170, 300), (240, 340), (170, 380)), 4)),
             omega=-0.015, velocity=(2.0 * sx, -0.5 * sy)),
        # two touching bodies with different motions
        Body((rect(330, 300, 410, 400, 5),), velocity=(-1.8 * sx, 0.0)),
        Body((rect(410, 300, 490, 400, 6),), omega=0.025),
        # moves for 6 frames, then stops
        Body((poly(((540, 240), (610, 250), (600, 330), (530, 310)), 7),), velocity=(0, 2.5 * sy),
             start=0, stop=6),
        # static distractor
        Body((poly(Polygon.regular(300, 60, 35, 5).points, 8),)),
    ]
    return render_planar_clip(bodies, size=size, n_frames=n_frames, seed=seed)
