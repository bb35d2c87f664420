"""Random tabletop scenes for the two benchmark tracks, and the pusher's motion plan.

``compose_scene(track, rng)`` returns a :class:`ScenePlan`: the MJCF model, initial joint
positions, the camera, the clip length and a straight push of the mocap pusher.

* ``robot`` (like MoRiBo's BridgeData track): a gripper on a forearm pushes one of 2-4 free
  blocks / glued composites, or closes a drawer; 1-2 static distractors.
* ``hand`` (like the human-in-the-wild track): a rigid hand pushes an articulated part
  (drawer, cabinet door, laptop lid) or an object among 4-7 free objects and 1-3 static
  distractors; more bodies, more clutter.
* ``pickplace`` (harder): natural textures, shadows, an articulated hand or gripper carries
  a block across the table while other bodies move; see :mod:`~motionbits.synth.mujoco_pickplace`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from motionbits.synth.mujoco_choreo import Choreography
from motionbits.synth.mujoco_mjcf import MJCFScene, Part

__all__ = ["TRACKS", "Camera", "ScenePlan", "compose_scene"]

TRACKS = ("robot", "hand", "pickplace")
TABLE_HALF = (0.45, 0.35)
_TIP_RADIUS = 0.012  # half thickness of the pusher's contact surface (fingers / fingertips)


@dataclass(frozen=True)
class Camera:
    """A MuJoCo free camera: looks at ``lookat`` from ``distance`` m; angles in degrees."""

    lookat: tuple[float, float, float]
    distance: float
    azimuth: float
    elevation: float


@dataclass(frozen=True)
class ScenePlan:
    """Everything needed to simulate and render one clip.

    Attributes:
        track: ``"robot"`` or ``"hand"``.
        xml: MJCF model.
        init_qpos: joint name -> initial position (articulated parts start ajar).
        camera: the viewpoint.
        n_frames: clip length (12-16).
        frame_dt: simulated seconds between frames.
        start, end: (3,) pusher origin (contact tip) at the first and last frame.
        yaw: pusher heading in radians (its forearm trails behind the push direction).
        target: name and kind of the part the push is aimed at.
        parts: names and kinds of all placed parts.
        script: scripted agents, carries and kicks; ``None`` = the straight push of the
            mocap body ``pusher`` from ``start`` to ``end`` (robot and hand tracks).
        assets: file name -> bytes of textures the MJCF refers to.
        max_travel: a body moving farther than this (m) makes the clip implausible.
        cameras: one camera per frame (a moving camera); ``None`` = ``camera`` throughout.
    """

    track: str
    xml: str
    init_qpos: dict[str, float]
    camera: Camera
    n_frames: int
    frame_dt: float
    start: np.ndarray
    end: np.ndarray
    yaw: float
    target: tuple[str, str]
    parts: tuple[tuple[str, str], ...]
    script: Choreography | None = None
    assets: dict[str, bytes] = field(default_factory=dict)
    max_travel: float = 0.35
    cameras: tuple[Camera, ...] | None = None


def _place(rng: np.random.Generator, parts: list[Part], radius: float,
           region: tuple[float, float, float, float], tries: int = 200) -> np.ndarray | None:
    """A point in ``region`` (x0, x1, y0, y1) at least ``radius`` + margin from every part."""
    x0, x1, y0, y1 = region
    for _ in range(tries):
        xy = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
        if all(np.linalg.norm(xy - p.xy) > radius + p.radius + 0.015 for p in parts):
            return xy
    return None


def _segment_clear(a: np.ndarray, b: np.ndarray, parts: list[Part], skip: str, r: float) -> bool:
    """True if the pusher's path a->b stays clear of every part but ``skip`` (2-D)."""
    ab = b[:2] - a[:2]
    for p in parts:
        if p.name == skip:
            continue
        t = np.clip(np.dot(p.xy - a[:2], ab) / max(np.dot(ab, ab), 1e-12), 0, 1)
        if np.linalg.norm(a[:2] + t * ab - p.xy) < p.radius + r:
            return False
    return True


def _push_free(rng: np.random.Generator, part: Part) -> tuple[np.ndarray, np.ndarray, float]:
    """Contact point, direction and distance of a push of a free object, roughly towards
    the table centre so it stays on the table."""
    to_centre = -part.xy / (np.linalg.norm(part.xy) + 1e-9)
    ang = np.arctan2(to_centre[1], to_centre[0]) + rng.uniform(-1.0, 1.0)
    d = np.array([np.cos(ang), np.sin(ang), 0.0])
    z = float(np.clip(part.height * 0.45, 0.006, 0.03))
    point = np.array([part.xy[0], part.xy[1], z]) - d * part.radius * 0.8
    return point, d, float(rng.uniform(0.05, 0.10))


def compose_scene(track: str, rng: np.random.Generator, *, width: int = 640,
                  height: int = 480) -> ScenePlan:
    """Draw one random scene of ``track`` and a push that moves something in it.

    Raises:
        ValueError: unknown track, or no collision-free push could be planned for this draw
            (the caller retries with another random stream).
    """
    if track not in TRACKS:
        raise ValueError(f"unknown track {track!r}; choose one of {TRACKS}")
    if track == "pickplace":
        from motionbits.synth.mujoco_pickplace import compose_pickplace

        return compose_pickplace(rng, width=width, height=height)
    s = MJCFScene(rng, width=max(width, 64), height=max(height, 64))
    s.table(TABLE_HALF)
    hx, hy = TABLE_HALF
    inner = (-hx + 0.1, hx - 0.1, -hy + 0.1, hy - 0.12)
    back = (-hx + 0.14, hx - 0.14, 0.12, hy - 0.1)
    robot = track == "robot"

    furniture: list[Part] = []
    n_furn = int(rng.random() < 0.4) if robot else int(rng.integers(1, 3))
    makers = [s.drawer] if robot else [s.drawer, s.door_cabinet, s.laptop]
    for _ in range(n_furn):
        make = makers[int(rng.integers(len(makers)))]
        xy = _place(rng, s.parts, 0.16, back)
        if xy is not None:
            furniture.append(make(xy))
    n_static = int(rng.integers(1, 3)) if robot else int(rng.integers(1, 4))
    for _ in range(n_static):
        xy = _place(rng, s.parts, 0.05, inner)
        if xy is not None:
            s.static_object(xy)
    n_free = int(rng.integers(2, 5)) if robot else int(rng.integers(4, 8))
    free: list[Part] = []
    for _ in range(n_free):
        xy = _place(rng, s.parts, 0.06, inner)
        if xy is None:
            continue
        free.append(s.composite(xy) if rng.random() < 0.45 else s.free_block(xy))
    if not free and not furniture:
        raise ValueError("no movable part could be placed")

    (s.gripper if robot else s.hand)()
    s.lights(int(rng.integers(1, 3)))

    # The push: an articulated part (if any; hand track prefers them) or a free object.
    p_art = 0.6 if not robot else 0.5
    candidates = furniture if (furniture and (rng.random() < p_art or not free)) else free
    order = rng.permutation(len(candidates))
    n_frames = int(rng.integers(12, 17))
    frame_dt = 0.1
    for i in order:
        part = candidates[int(i)]
        point, d, dist = part.push if part.push is not None else _push_free(rng, part)
        approach = float(rng.uniform(0.015, 0.035))
        start = point - d * (_TIP_RADIUS + approach)
        # Cap the speed at ~1.2 cm per frame (a few px per frame at ~1 m), at least 0.5 cm.
        total = approach + dist
        cap = 0.012 * (n_frames - 1)
        if total > cap:
            dist = max(cap - approach, 0.02)
        end = point + d * dist
        start[2] = end[2] = max(point[2] - 0.012, 0.004)
        if not _segment_clear(start, end, s.parts, part.name, _TIP_RADIUS + 0.035):
            continue
        if max(abs(end[0]), abs(start[0])) > hx - 0.03 or max(abs(end[1]), abs(start[1])) > hy - 0.02:
            continue
        yaw = float(np.arctan2(d[1], d[0]) - np.pi / 2)
        camera = Camera(
            lookat=(float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.02, 0.08)),
                    float(rng.uniform(0.0, 0.06))),
            distance=float(rng.uniform(0.8, 1.05)),
            azimuth=float(90 + rng.uniform(-25, 25)),
            elevation=float(-rng.uniform(32, 55)),
        )
        return ScenePlan(
            track=track, xml=s.xml(), init_qpos=dict(s.init_qpos), camera=camera,
            n_frames=n_frames, frame_dt=frame_dt, start=start, end=end, yaw=yaw,
            target=(part.name, part.kind), parts=tuple((p.name, p.kind) for p in s.parts),
        )
    raise ValueError("no collision-free push found for this scene")
