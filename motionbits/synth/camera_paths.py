"""Camera motion for generated clips: static, pan, orbit, hand-held shake.

A path is one :class:`~motionbits.synth.mujoco_scenes.Camera` (MuJoCo free camera:
``lookat``, ``distance``, ``azimuth``, ``elevation``) per frame, drawn from its own random
stream so the scene itself does not change with the camera mode.

* ``pan``: the camera stays in place and turns (azimuth 8-20 deg, elevation up to 5 deg over
  the clip, eased): a rotation about the optical centre, no parallax.
* ``orbit``: the camera circles the table's look-at point (azimuth 15-35 deg) while it
  moves in or out by up to 12 % and up or down by up to 8 deg: translation, parallax.
* ``shake``: a hand-held camera: a smooth random walk of the view direction (about 0.6 deg
  per frame) and of the position (about 4 mm per frame) around the base pose.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CAMERA_MODES", "camera_path"]

CAMERA_MODES = ("static", "pan", "orbit", "shake")


def _forward(azimuth: float, elevation: float) -> np.ndarray:
    """Unit view direction of a MuJoCo free camera (angles in degrees)."""
    a, e = np.radians(azimuth), np.radians(elevation)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def _ease(n: int) -> np.ndarray:
    s = np.linspace(0.0, 1.0, n)
    return 0.5 - 0.5 * np.cos(np.pi * s)


def camera_path(mode: str, base, n_frames: int, rng: np.random.Generator) -> tuple:
    """Per-frame cameras for ``mode`` starting from ``base``.

    Args:
        mode: one of :data:`CAMERA_MODES`.
        base: the scene's :class:`~motionbits.synth.mujoco_scenes.Camera`.
        n_frames: clip length.
        rng: the camera's own random stream.

    Returns:
        ``n_frames`` cameras (all equal to ``base`` for ``static``).
    """
    from motionbits.synth.mujoco_scenes import Camera

    if mode not in CAMERA_MODES:
        raise ValueError(f"unknown camera mode {mode!r}; choose one of {CAMERA_MODES}")
    look = np.asarray(base.lookat, float)
    n = int(n_frames)
    if mode == "static":
        return (base,) * n
    e = _ease(n)
    sign = 1.0 if rng.random() < 0.5 else -1.0
    if mode == "pan":
        pos = look - base.distance * _forward(base.azimuth, base.elevation)
        az = base.azimuth + sign * rng.uniform(8, 20) * e
        el = np.clip(base.elevation + rng.uniform(-5, 5) * e, -80, -10)
        out = []
        for a, b in zip(az, el):
            out.append(Camera(tuple(float(v) for v in pos + base.distance * _forward(a, b)),
                              float(base.distance), float(a), float(b)))
        return tuple(out)
    if mode == "orbit":
        az = base.azimuth + sign * rng.uniform(15, 35) * e
        el = np.clip(base.elevation + rng.uniform(-8, 8) * e, -80, -10)
        dist = base.distance * (1 + rng.uniform(-0.12, 0.12) * e)
        return tuple(Camera(tuple(float(v) for v in look), float(d), float(a), float(b))
                     for a, b, d in zip(az, el, dist))
    # shake: AR(1) random walks of angles and position around the base pose
    ang = np.zeros((n, 2))
    off = np.zeros((n, 3))
    for k in range(1, n):
        ang[k] = 0.6 * ang[k - 1] + rng.normal(0, 0.6, 2)
        off[k] = 0.6 * off[k - 1] + rng.normal(0, 0.004, 3)
    pos0 = look - base.distance * _forward(base.azimuth, base.elevation)
    out = []
    for k in range(n):
        a, b = base.azimuth + ang[k, 0], float(np.clip(base.elevation + ang[k, 1], -85, -5))
        lk = pos0 + off[k] + base.distance * _forward(a, b)
        out.append(Camera(tuple(float(v) for v in lk), float(base.distance), float(a), b))
    return tuple(out)
