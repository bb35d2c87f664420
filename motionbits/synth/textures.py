"""Procedural natural textures (wood grain, marble, fabric, granite) as RGB images.

Pure numpy + OpenCV, no files, no downloads: every texture is a function of a
``numpy.random.Generator``, so a scene's look is fixed by its seed. The images are fed to
MuJoCo as PNG assets (:func:`png_bytes`).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["NATURAL_KINDS", "fractal_noise", "natural_texture", "png_bytes"]

NATURAL_KINDS = ("wood", "marble", "fabric", "granite")


def fractal_noise(rng: np.random.Generator, size: int, octaves: int = 5,
                  base: int = 4, persistence: float = 0.55) -> np.ndarray:
    """Sum of ``octaves`` upsampled random grids (value noise), tileable-free.

    Returns:
        (size, size) float32 in [0, 1].
    """
    out = np.zeros((size, size), np.float32)
    amp, total = 1.0, 0.0
    for o in range(octaves):
        cells = base * 2 ** o
        grid = rng.random((cells + 1, cells + 1)).astype(np.float32)
        out += amp * cv2.resize(grid, (size, size), interpolation=cv2.INTER_CUBIC)
        total += amp
        amp *= persistence
    out /= total
    lo, hi = float(out.min()), float(out.max())
    return (out - lo) / max(hi - lo, 1e-6)


def _lerp(c1: np.ndarray, c2: np.ndarray, t: np.ndarray) -> np.ndarray:
    return c1[None, None] * (1 - t[..., None]) + c2[None, None] * t[..., None]


def _wood(rng: np.random.Generator, size: int) -> np.ndarray:
    """Growth rings around a far-away log axis, warped by noise, with fine fibres."""
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32) / size
    cx, cy = rng.uniform(-1.5, 2.5), rng.uniform(-3.0, -1.0)  # the log's axis, off the board
    r = np.hypot((xx - cx) * rng.uniform(0.15, 0.35), yy - cy)
    warp = fractal_noise(rng, size, octaves=4, base=2) - 0.5
    rings = np.sin(2 * np.pi * (r * rng.uniform(8, 22) + warp * rng.uniform(2.0, 4.0)))
    t = 0.5 + 0.5 * np.sign(rings) * np.abs(rings) ** 0.5
    fibres = cv2.resize(rng.random((size, 8)).astype(np.float32), (size, size),
                        interpolation=cv2.INTER_LINEAR)
    t = np.clip(0.8 * t + 0.25 * (fibres - 0.5) + 0.1, 0, 1)
    light = np.array([rng.uniform(0.55, 0.85), rng.uniform(0.38, 0.6), rng.uniform(0.18, 0.35)])
    dark = light * rng.uniform(0.45, 0.7)
    return _lerp(dark, light, t)


def _marble(rng: np.random.Generator, size: int) -> np.ndarray:
    """Sine veins along a random direction, displaced by turbulence."""
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32) / size
    a = rng.uniform(0, np.pi)
    turb = fractal_noise(rng, size, octaves=6, base=3)
    v = np.sin(2 * np.pi * ((np.cos(a) * xx + np.sin(a) * yy) * rng.uniform(2, 5)
                            + turb * rng.uniform(2.5, 5.0)))
    vein = (1 - np.abs(v)) ** rng.uniform(6, 14)
    cloud = fractal_noise(rng, size, octaves=5, base=4)
    base = np.array([rng.uniform(0.8, 0.95)] * 3) - rng.uniform(0, 0.08, 3)
    veinc = base * rng.uniform(0.25, 0.55) + rng.uniform(0, 0.1, 3)
    img = _lerp(base * 0.9, base, cloud)
    return img * (1 - vein[..., None]) + veinc[None, None] * vein[..., None]


def _fabric(rng: np.random.Generator, size: int) -> np.ndarray:
    """A plain weave: alternating warp and weft threads, slubs and a faint plaid."""
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    period = float(rng.integers(5, 10))
    u, v = xx / period, yy / period
    over = ((np.floor(u) + np.floor(v)) % 2).astype(np.float32)
    warp = 0.5 + 0.5 * np.cos(2 * np.pi * (u - 0.5))
    weft = 0.5 + 0.5 * np.cos(2 * np.pi * (v - 0.5))
    thread = over * warp + (1 - over) * weft
    slub = fractal_noise(rng, size, octaves=3, base=16)
    plaid = ((np.floor(xx / (period * rng.integers(6, 14))) % 2)
             + (np.floor(yy / (period * rng.integers(6, 14))) % 2)) / 2
    c1 = rng.uniform(0.15, 0.85, 3)
    c2 = np.clip(c1 + rng.uniform(-0.3, 0.3, 3), 0, 1)
    img = _lerp(c1, c2, plaid * rng.uniform(0.3, 1.0))
    return img * (0.55 + 0.35 * thread[..., None] + 0.2 * (slub[..., None] - 0.5))


def _granite(rng: np.random.Generator, size: int) -> np.ndarray:
    """Speckled stone: three mineral colours by thresholded noise, plus fine grain."""
    grain = rng.random((size, size)).astype(np.float32)
    n1, n2 = fractal_noise(rng, size, 4, 24), fractal_noise(rng, size, 4, 24)
    grey = rng.uniform(0.25, 0.75)
    cols = [np.clip(grey * rng.uniform(0.4, 1.4) + rng.uniform(-0.08, 0.08, 3), 0, 1)
            for _ in range(3)]
    img = _lerp(cols[0], cols[1], (n1 > 0.55).astype(np.float32))
    img = np.where((n2 > 0.7)[..., None], cols[2][None, None], img)
    return img * (0.85 + 0.3 * (grain[..., None] - 0.5))


_MAKERS = {"wood": _wood, "marble": _marble, "fabric": _fabric, "granite": _granite}


def natural_texture(kind: str, rng: np.random.Generator, size: int = 512) -> np.ndarray:
    """A procedural texture of ``kind`` (one of :data:`NATURAL_KINDS`).

    Returns:
        (size, size, 3) uint8 RGB.
    """
    if kind not in _MAKERS:
        raise ValueError(f"unknown texture kind {kind!r}; choose one of {NATURAL_KINDS}")
    img = _MAKERS[kind](rng, size)
    return np.clip(img * 255 + 0.5, 0, 255).astype(np.uint8)


def png_bytes(img: np.ndarray) -> bytes:
    """PNG encoding of an (H, W, 3) uint8 RGB image."""
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(img[..., ::-1]))
    if not ok:
        raise RuntimeError("PNG encoding failed")
    return buf.tobytes()
