"""One tower-stacking trial (Supplement B): push, segment, greedily grasp and stack.

1. A seeded scene (:func:`motionbits.stacking.scene.build_scene`) settles.
2. Interaction: the gripper, fingers closed, gives each composite one short push in a
   random direction (random order), then leaves the camera's view. Every object moves,
   so a motion method *can* see all five. The camera records at ``frame_dt``.
3. The method under test maps the clip to a label map of its last frame.
4. Greedy controller: masks largest (pixel area) first; each mask is lifted to 3-D with
   the depth render and its bird's-eye centroid, principal axes and width give the grasp
   (:func:`motionbits.stacking.perception.world_grasp`); the hand descends, closes,
   lifts, carries the object to the tower, lowers it onto the tower top (measured in the
   depth render) and opens. It stops once five objects are stacked or the masks run out.
5. The simulator referees every step. Failure reasons: ``grasp`` (nothing lifted, or the
   object slipped out on the way), ``stack`` (the placed object did not come to rest on
   the tower upright, or the tower moved), ``masks`` (masks ran out before five objects
   were stacked). Success: five objects in the tower, standing still.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from motionbits.stacking.perception import WorldGrasp, world_grasp
from motionbits.stacking.scene import FINGER_MAX, N_OBJECTS, StackScene, build_scene
from motionbits.stacking.sim import StackSim

__all__ = ["TrialConfig", "TrialResult", "run_trial", "trial_scene", "record_push_clip",
           "FAILURES"]

FAILURES = ("grasp", "stack", "masks")
LabelsFn = Callable[[list[np.ndarray]], np.ndarray]


@dataclass(frozen=True)
class TrialConfig:
    """Parameters of a trial (defaults are ours; Supplement B gives none of these)."""

    width: int = 640
    height: int = 480
    frame_dt: float = 0.1  # s between recorded frames (10 fps)
    push_speed: float = 0.06  # m/s
    push_dist: tuple[float, float] = (0.03, 0.05)  # m, drawn per object
    min_mask_px: int = 150  # masks smaller than this are ignored (specks)
    finger_depth: float = 0.022  # m the fingertips go below an object's top
    carry_clearance: float = 0.06  # m above the tower top while carrying
    settle_s: float = 0.6  # s the scene settles after each placement


@dataclass
class TrialResult:
    """What happened in one trial.

    Attributes:
        seed, index: the trial's seed and index (the scene is ``[seed, index]``).
        method: method name.
        stacked: objects stacked while the tower stood.
        success: five stacked, the tower standing still.
        failure: one of :data:`FAILURES`, or None on success.
        n_masks: masks the method gave (at least ``min_mask_px`` pixels).
        seconds: wall time of the whole trial; ``segment_seconds`` of the method alone.
        n_frames: length of the clip given to the method.
        log: one line per controller step.
    """

    seed: int
    index: int
    method: str
    stacked: int = 0
    success: bool = False
    failure: str | None = None
    n_masks: int = 0
    seconds: float = 0.0
    segment_seconds: float = 0.0
    n_frames: int = 0
    log: list[str] = field(default_factory=list)


def trial_scene(seed: int, index: int, config: TrialConfig = TrialConfig()) -> tuple[StackScene, np.random.Generator]:
    """The scene of trial ``index`` under ``seed`` and the random stream for its pushes."""
    rng = np.random.default_rng([int(seed), int(index), 14])
    return build_scene(rng, width=config.width, height=config.height), rng


def _push_plan(sim: StackSim, rng: np.random.Generator, config: TrialConfig) -> list[tuple[np.ndarray, np.ndarray]]:
    """Start and end points of one push per object (random order, clear descent)."""
    pos = sim.object_pos()[:, :2]
    scene = sim.scene
    radii = [0.71 * c * (1 + np.ptp(np.asarray(_cells(s)), axis=0).max()) for s, c in zip(scene.shapes, scene.cell)]
    centre = pos.mean(axis=0)
    plan = []
    for i in rng.permutation(N_OBJECTS):
        for _ in range(60):
            to_c = centre - pos[i]
            base = math.atan2(to_c[1], to_c[0]) if np.linalg.norm(to_c) > 0.02 else rng.uniform(-np.pi, np.pi)
            ang = base + rng.uniform(-1.4, 1.4)
            d = np.array([math.cos(ang), math.sin(ang)])
            start = pos[i] - d * (radii[i] + 0.03)
            # the descent (a 2 cm disc at the start) must not land on another object
            if all(np.linalg.norm(start - pos[j]) > radii[j] + 0.025 for j in range(N_OBJECTS) if j != i):
                dist = rng.uniform(*config.push_dist)
                plan.append((start, start + d * (0.03 + dist)))
                break
    return plan


def _cells(shape: str):
    from motionbits.stacking.scene import SHAPES
    return SHAPES[shape]


def record_push_clip(sim: StackSim, rng: np.random.Generator, config: TrialConfig) -> list[np.ndarray]:
    """Settle, push every object once, leave the view; return the recorded RGB frames."""
    sim.place_hand([0.0, -0.05, 0.35])
    sim.set_opening(0.0)
    sim.step(0.5)
    frames: list[np.ndarray] = [sim.rgb()]
    sim.recorder = frames.append
    z_push, z_air = 0.01, 0.09
    for start, end in _push_plan(sim, rng, config):
        yaw = math.atan2(end[1] - start[1], end[0] - start[0])  # fingers side by side
        sim.move([start[0], start[1], z_air], yaw, speed=0.3)
        sim.move([start[0], start[1], z_push], speed=0.25)
        sim.move([end[0], end[1], z_push], speed=config.push_speed)
        sim.move([end[0], end[1], z_air], speed=0.25)
    sim.move([sim.hand_pos[0], 0.05, 0.6], speed=0.4)  # up and out of view
    sim.step(0.25)
    sim.recorder = None
    return frames


def _tower_top(points: np.ndarray, tower_xy: np.ndarray, radius: float = 0.06) -> tuple[float, np.ndarray]:
    """Height (0 = table) and (x, y) centre of the tower's top face, from the depth render:
    the highest points within ``radius`` of the tower axis, and the centroid of those
    within 6 mm of the top."""
    near = np.linalg.norm(points[..., :2] - tower_xy, axis=-1) < radius
    pts = points[near]
    if not len(pts) or np.percentile(pts[:, 2], 99) < 0.005:
        return 0.0, tower_xy
    top = float(np.percentile(pts[:, 2], 99))
    face = pts[pts[:, 2] > top - 0.006]
    return top, face[:, :2].mean(axis=0)


def _masks(labels: np.ndarray, min_px: int) -> list[np.ndarray]:
    ids, counts = np.unique(labels[labels > 0], return_counts=True)
    order = np.argsort(-counts, kind="stable")
    return [labels == ids[k] for k in order if counts[k] >= min_px]


def run_trial(method: str, labels_fn: LabelsFn | None, seed: int, index: int,
              config: TrialConfig = TrialConfig(),
              video: Callable[[np.ndarray], None] | None = None,
              gt: bool = False) -> TrialResult:
    """Run one trial with masks from ``labels_fn`` (or ground truth if ``gt``).

    Args:
        method: name recorded in the result.
        labels_fn: ``frames -> (H, W) int labels of the last frame``; ignored if ``gt``.
        seed, index: select the scene and its pushes (same for every method).
        config: trial parameters.
        video: called with every frame of the whole trial (push and stacking), if given.
        gt: use the simulator's exact instance masks of the last frame (all five objects).
    """
    t0 = time.perf_counter()
    scene, rng = trial_scene(seed, index, config)
    sim = StackSim(scene, frame_dt=config.frame_dt)
    res = TrialResult(seed=seed, index=index, method=method)
    try:
        frames = record_push_clip(sim, rng, config)
        res.n_frames = len(frames)
        if video is not None:
            for f in frames:
                video(f)
        t1 = time.perf_counter()
        if gt:
            labels = sim.segmentation() + 1
        else:
            labels = np.asarray(labels_fn(frames))
        res.segment_seconds = time.perf_counter() - t1
        if labels.shape != (scene.height, scene.width):
            raise ValueError(f"method {method!r} returned labels of shape {labels.shape}, "
                             f"expected {(scene.height, scene.width)}")
        cam = sim.camera()
        points = cam.backproject(sim.depth())
        masks = _masks(labels, config.min_mask_px)
        res.n_masks = len(masks)
        grasps = [world_grasp(m, points) for m in masks]
        if video is not None:
            sim.recorder = video
        _stack(sim, [g for g in grasps if g is not None], config, res)
        sim.recorder = None
    finally:
        sim.close()
    res.seconds = time.perf_counter() - t0
    return res


def _stack(sim: StackSim, grasps: list[WorldGrasp], config: TrialConfig, res: TrialResult) -> None:
    tower_xy = np.array(sim.scene.tower_xy)
    place_xy = tower_xy  # centre of the tower's top face (measured after every placement)
    place_yaw: float | None = None  # every object goes down with the first one's axes
    stacked: list[int] = []
    rest: dict[int, np.ndarray] = {}
    tower_top = 0.0
    for k, g in enumerate(grasps):
        if len(stacked) == N_OBJECTS:
            break
        before = sim.object_pos()
        carry_z = tower_top + 0.12 + config.carry_clearance
        open_half = min(g.width / 2 + 0.02, FINGER_MAX)
        grasp_z = max(g.top - config.finger_depth, 0.004)
        sim.set_opening(open_half)
        sim.move([g.xy[0], g.xy[1], carry_z], g.yaw, speed=0.4)
        sim.move([g.xy[0], g.xy[1], grasp_z], speed=0.2)
        sim.set_opening(0.0)
        sim.step(0.5)
        sim.move([g.xy[0], g.xy[1], carry_z], speed=0.2)
        sim.step(0.2)
        lifted = [i for i in range(N_OBJECTS)
                  if i not in stacked and sim.object_pos()[i, 2] > before[i, 2] + 0.03]
        if not lifted:
            res.failure = "grasp"
            res.log.append(f"mask {k}: grasp at {g.xy[0]:+.3f},{g.xy[1]:+.3f} lifted nothing")
            return
        # each object is held with its minor axis along the jaws: placing it with the same
        # hand yaw as the first object lines all their principal axes up (the gripper is
        # symmetric, so the yaw is free modulo pi: take the nearest)
        place_yaw = sim.hand_yaw if place_yaw is None else place_yaw
        yaw = place_yaw + math.pi * round((sim.hand_yaw - place_yaw) / math.pi)
        sim.move([place_xy[0], place_xy[1], carry_z], yaw, speed=0.3)
        if not all(sim.object_pos()[i, 2] > 0.05 for i in lifted):
            res.failure = "grasp"
            res.log.append(f"mask {k}: object {lifted} slipped out while carried")
            return
        place_z = tower_top + grasp_z + 0.008
        sim.move([place_xy[0], place_xy[1], place_z], speed=0.15)
        sim.relax()
        sim.step(0.3)
        sim.move([place_xy[0], place_xy[1], carry_z], speed=0.1)
        sim.set_opening(FINGER_MAX)
        sim.move([tower_xy[0] + 0.1, 0.1, 0.6], speed=0.4)  # up and out of the camera view
        sim.step(config.settle_s)
        pos, up = sim.object_pos(), sim.object_up()
        new_ok = all(
            np.linalg.norm(pos[i, :2] - tower_xy) < 0.06 and up[i] > math.cos(math.radians(15))
            and pos[i, 2] > tower_top for i in lifted)
        old_ok = all(np.linalg.norm(pos[i] - rest[i]) < 0.015 for i in stacked)
        if not (new_ok and old_ok):
            res.failure = "stack"
            res.log.append(
                f"mask {k}: object {lifted} placed, tower fell (new upright/on tower: {new_ok}, "
                f"old in place: {old_ok}; new at {np.round(pos[lifted], 3).tolist()}, "
                f"up {np.round(up[lifted], 3).tolist()}, tower top was {tower_top:.3f})")
            return
        stacked.extend(lifted)
        for i in lifted:
            rest[i] = pos[i]
        res.stacked = len(stacked)
        tower_top, place_xy = _tower_top(sim.camera().backproject(sim.depth()), tower_xy)
        res.log.append(f"mask {k}: stacked {lifted}, tower top {tower_top:.3f} m")
    if len(stacked) < N_OBJECTS:
        res.failure = "masks"
        res.log.append(f"masks ran out with {len(stacked)} stacked")
        return
    sim.step(1.0)
    pos = sim.object_pos()
    still = np.all(sim.object_speed() < 0.01) and all(
        np.linalg.norm(pos[i] - rest[i]) < 0.015 for i in stacked)
    res.success = bool(still)
    if not still:
        res.failure = "stack"
        res.log.append("tower not standing still after the last placement")
