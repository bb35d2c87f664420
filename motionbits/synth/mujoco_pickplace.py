"""The ``pickplace`` track: long, fast, overlapping motions over natural textures.

``compose_pickplace(rng)`` draws a :class:`~motionbits.synth.mujoco_scenes.ScenePlan` with
a :class:`~motionbits.synth.mujoco_choreo.Choreography`:

* a table of wood, marble, fabric or granite; natural or builtin textures on 4-7 free
  objects (blocks, glued composites, balls) and 0-2 static distractors; every light casts
  shadows;
* the main agent (an articulated hand or a parallel gripper) enters from any side, 30-45
  cm away, grasps a block, lifts it 10-15 cm in 1.4-1.8 frames, carries it 12-28 cm
  across the table in 4.2-5 frames (peaks of up to 10 cm per frame, tens of pixels at
  480x640), turns it, sets it down and leaves;
* with probability 0.8 a second agent (a rigid hand) sweeps another object 20-40 cm at
  the same time; with probability 0.5 a ball is kicked and rolls (or a block slides); at
  least one of the two happens.

Agents are mocap bodies ``agent*``: their pixels go to ``ignore.png``, every other body
that moved is labelled, as in the robot and hand tracks.
"""

from __future__ import annotations

import numpy as np

from motionbits.synth.mujoco_agents import AgentSpec, NaturalScene
from motionbits.synth.mujoco_choreo import AgentPath, Carry, Choreography, Kick
from motionbits.synth.mujoco_mjcf import Part

__all__ = ["compose_pickplace", "PICKPLACE_TABLE_HALF", "N_FRAMES"]

PICKPLACE_TABLE_HALF = (0.55, 0.4)
N_FRAMES = 16
FRAME_DT = 0.1  # s between frames (10 fps, like the other tracks)


def _place(rng, parts: list[Part], radius: float, region, tries: int = 300) -> np.ndarray | None:
    x0, x1, y0, y1 = region
    for _ in range(tries):
        xy = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
        if all(np.linalg.norm(xy - p.xy) > radius + p.radius + 0.02 for p in parts):
            return xy
    return None


def _clear(a: np.ndarray, b: np.ndarray, parts: list[Part], skip: set[str], r: float) -> bool:
    """True if the 2-D segment a->b passes no part (but those in ``skip``) closer than r."""
    a, b = np.asarray(a[:2], float), np.asarray(b[:2], float)
    ab = b - a
    for p in parts:
        if p.name in skip:
            continue
        t = np.clip(np.dot(p.xy - a, ab) / max(np.dot(ab, ab), 1e-12), 0, 1)
        if np.linalg.norm(a + t * ab - p.xy) < p.radius + r:
            return False
    return True


def _pick_and_place(rng, agent: AgentSpec, target: Part, place: np.ndarray,
                    rest_z: float) -> tuple[AgentPath, Carry]:
    """Keyframes of approach, grasp, lift, carry, set down and leave."""
    phi = rng.uniform(0, 2 * np.pi)  # the side it comes from
    away = np.array([np.cos(phi), np.sin(phi), 0.0])
    yaw0 = float(phi + np.pi / 2)  # the forearm trails towards where it came from
    yaw1 = yaw0 + float(rng.uniform(-0.9, 0.9))
    grasp_z = max(0.006, 0.35 * target.height) if agent.kind == "hand" else max(0.005, 0.25 * target.height)
    hover = rest_z + target.height + 0.06
    lift = float(rng.uniform(0.1, 0.15)) + target.height
    tgt = np.array([target.xy[0], target.xy[1], grasp_z])
    dst = np.array([place[0], place[1], grasp_z + 0.003])
    start = tgt + away * rng.uniform(0.3, 0.45) + np.array([0, 0, rng.uniform(0.12, 0.22)])
    leave_dir = rng.uniform(0, 2 * np.pi)
    leave = dst + np.array([np.cos(leave_dir) * 0.15, np.sin(leave_dir) * 0.15, 0.12])
    t = [0.0]
    # approach, descend, close, lift, carry, set down, open (frames); then leave
    for dt in (rng.uniform(2.4, 3.2), rng.uniform(0.8, 1.1), rng.uniform(0.5, 0.7),
               rng.uniform(1.4, 1.8), rng.uniform(4.2, 5.0), rng.uniform(1.4, 1.8),
               rng.uniform(0.5, 0.7)):
        t.append(t[-1] + dt)
    t.append(float(N_FRAMES - 1))
    pos = np.array([start, tgt + [0, 0, hover], tgt, tgt, tgt + [0, 0, lift],
                    dst + [0, 0, lift * 0.7], dst, dst, leave])
    yaws = np.array([yaw0, yaw0, yaw0, yaw0, yaw0, yaw1, yaw1, yaw1, yaw1])
    grips = np.array([0, 0, 0, 1, 1, 1, 1, 0, 0], float)
    path = AgentPath(agent.name, tuple(float(v) for v in t), pos, yaws, grips, agent.actuators)
    # Grasp once the fingers have closed; release on touch-down.
    return path, Carry(agent.name, target.name, t[3], t[6])


def _sweep(rng, agent: AgentSpec, part: Part, dist: float, t0: float, t1: float,
           direction: np.ndarray) -> AgentPath:
    """A rigid hand sweeps ``part`` by ``dist`` along ``direction`` between t0 and t1."""
    d = np.array([direction[0], direction[1], 0.0])
    z = float(np.clip(part.height * 0.4, 0.006, 0.03))
    contact = np.array([part.xy[0], part.xy[1], z]) - d * (part.radius + 0.012)
    start = contact - d * rng.uniform(0.04, 0.08)
    end = contact + d * dist
    yaw = float(np.arctan2(d[1], d[0]) - np.pi / 2)
    above = np.array([0, 0, 0.15])
    times = (0.0, t0, t1, min(t1 + 2.0, N_FRAMES - 1.0))
    if times[-1] <= times[-2]:
        times = (0.0, t0, t1, t1 + 1.0)
    pos = np.array([start + above - d * 0.1, start, end, end + above])
    return AgentPath(agent.name, times, pos, np.full(4, yaw), np.zeros(4), agent.actuators)


def compose_pickplace(rng: np.random.Generator, *, width: int = 640, height: int = 480):
    """Draw one ``pickplace`` scene (see the module doc).

    Raises:
        ValueError: no feasible pick-and-place for this draw (the caller retries).
    """
    from motionbits.synth.mujoco_scenes import Camera, ScenePlan

    s = NaturalScene(rng, width=max(width, 64), height=max(height, 64))
    s.table(PICKPLACE_TABLE_HALF)
    hx, hy = PICKPLACE_TABLE_HALF
    inner = (-hx + 0.1, hx - 0.1, -hy + 0.1, hy - 0.1)
    for _ in range(int(rng.integers(0, 3))):
        xy = _place(rng, s.parts, 0.05, inner)
        if xy is not None:
            s.static_object(xy)
    graspable: list[Part] = []
    others: list[Part] = []
    for i in range(int(rng.integers(4, 8))):
        xy = _place(rng, s.parts, 0.06, inner)
        if xy is None:
            continue
        u = rng.random()
        if i == 0 or u < 0.45:
            part = s.free_block(xy)
            (graspable if part.radius < 0.05 and part.height < 0.075 else others).append(part)
        elif u < 0.8:
            others.append(s.composite(xy))
        else:
            others.append(s.ball(xy))
    if not graspable:
        raise ValueError("no graspable block was placed")
    target = graspable[0]
    movable = [p for p in graspable[1:] + others]

    place = None
    for _ in range(200):
        xy = _place(rng, [p for p in s.parts if p is not target], target.radius + 0.02, inner, tries=1)
        if xy is not None and 0.12 <= np.linalg.norm(xy - target.xy) <= 0.28:
            place = xy
            break
    if place is None:
        raise ValueError("no free spot to set the object down")

    main = s.articulated_hand() if rng.random() < 0.6 else s.parallel_gripper(
        closed_gap=min(target.radius * 0.7, 0.04))
    s.exclude_contacts(main, target.name)
    path, carry = _pick_and_place(rng, main, target, place, 0.0)
    agents, kicks = [path], []

    busy = {target.name}
    blocked = [Part("place", "spot", place, target.radius, 0.0)]
    if movable and rng.random() < 0.8:
        for part in rng.permutation(np.array(movable, dtype=object)):
            if part.kind == "ball":
                continue
            ang = np.arctan2(-part.xy[1], -part.xy[0]) + rng.uniform(-1.2, 1.2)
            d = np.array([np.cos(ang), np.sin(ang)])
            dist = float(rng.uniform(0.2, 0.4))
            end = part.xy + d * (dist + part.radius)
            if abs(end[0]) > hx - 0.08 or abs(end[1]) > hy - 0.08:
                continue
            if not _clear(part.xy, end, s.parts + blocked, busy | {part.name}, part.radius + 0.03):
                continue
            sweeper = s.rigid_pusher()
            t0 = float(rng.uniform(2.0, 4.0))
            agents.append(_sweep(rng, sweeper, part, dist, t0, t0 + float(rng.uniform(6.0, 9.0)), d))
            busy.add(part.name)
            break
    if rng.random() < 0.5:
        for part in movable:
            if part.name in busy or part.kind not in ("ball", "block"):
                continue
            ang = np.arctan2(-part.xy[1], -part.xy[0]) + rng.uniform(-0.6, 0.6)
            speed = float(rng.uniform(0.35, 0.6)) if part.kind == "ball" else float(rng.uniform(0.5, 0.8))
            v = np.array([np.cos(ang), np.sin(ang)]) * speed
            w = (np.array([-v[1], v[0]]) / part.radius if part.kind == "ball" else np.zeros(2))
            spin = 0.0 if part.kind == "ball" else float(rng.uniform(-6, 6))
            kicks.append(Kick(part.name, float(rng.uniform(1.0, 6.0)),
                              (float(v[0]), float(v[1]), 0.0, float(w[0]), float(w[1]), spin)))
            busy.add(part.name)
            break
    if len(agents) + len(kicks) < 2:
        raise ValueError("nothing moves besides the carried block")
    s.lights(int(rng.integers(1, 3)))

    camera = Camera(
        lookat=(float(rng.uniform(-0.06, 0.06)), float(rng.uniform(-0.02, 0.08)),
                float(rng.uniform(0.0, 0.05))),
        distance=float(rng.uniform(0.9, 1.15)),
        azimuth=float(90 + rng.uniform(-30, 30)),
        elevation=float(-rng.uniform(35, 60)),
    )
    return ScenePlan(
        track="pickplace", xml=s.xml(), init_qpos=dict(s.init_qpos), camera=camera,
        n_frames=N_FRAMES, frame_dt=FRAME_DT, start=path.positions[0], end=path.positions[-1],
        yaw=float(path.yaws[0]), target=(target.name, target.kind),
        parts=tuple((p.name, p.kind) for p in s.parts),
        script=Choreography(tuple(agents), (carry,), tuple(kicks)), assets=dict(s.files),
        max_travel=1.0,
    )
