"""One tower-stacking trial (Supplement B): push, segment, greedily grasp and stack.

1. A seeded scene (:func:`motionbits.stacking.scene.build_scene`) settles.
2. Interaction: the gripper, fingers closed, gives each composite one short push in a
   random direction away from the arrangement's centre (random order), then leaves the
   camera's view. Every object moves,
   so a motion method *can* see all five. The camera records at ``frame_dt``.
3. The method under test maps the clip to a label map of its last frame.
4. Greedy controller: masks largest (pixel area) first; each mask is lifted to 3-D with
   the depth render and its bird's-eye centroid, principal axes and width give the grasp
   (:func:`motionbits.stacking.perception.world_grasp`); the hand descends, closes,
   lifts, carries the object to the tower, lowers it onto the tower top (measured in the
   depth render) and relaxes the fingers. It stops once five objects are stacked or the masks run out.
5. The simulator referees every step. Failure reasons: ``grasp`` (nothing lifted, or the
   object slipped out on the way), ``stack`` (the placed object did not come to rest on
   the tower upright, or the tower moved), ``masks`` (masks ran out before five objects
   were stacked). Success: five objects in the tower, standing still.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from motionbits.frames import finite_number, whole_number
from motionbits.stacking.perception import (
    HeightMap,
    WorldGrasp,
    finger_clearance,
    world_grasp,
)
from motionbits.stacking.scene import (
    FINGER_MAX,
    N_OBJECTS,
    SHAPES,
    StackScene,
    build_scene,
)
from motionbits.stacking.sim import StackSim

__all__ = ["FAILURES", "PushedScene", "TrialConfig", "TrialResult", "push_scene", "run_trial",
           "trial_scene"]

FAILURES = ("grasp", "stack", "masks")
LabelsFn = Callable[[list[np.ndarray]], np.ndarray]


@dataclass(frozen=True)
class TrialConfig:
    """Parameters of a trial (defaults are ours; Supplement B gives none of these)."""

    width: int = 640
    height: int = 480
    frame_dt: float = 0.1  # s between recorded frames (10 fps)
    push_speed: float = 0.08  # m/s
    transit_speed: float = 0.25  # m/s of the gripper between pushes (~2.5 cm per frame)
    push_dist: tuple[float, float] = (0.03, 0.05)  # m, drawn per object
    min_mask_px: int = 150  # masks smaller than this are ignored (specks)
    min_object_height: float = 0.01  # m: masks whose points are all lower are skipped
    finger_depth: float = 0.018  # m the fingertips go below an object's top
    finger_margin: float = 0.012  # m between an open finger and the object's extent
    carry_clearance: float = 0.06  # m above the tower top while carrying
    settle_s: float = 0.6  # s the scene settles after each placement

    def __post_init__(self) -> None:
        """Every field checked when built (``width=0`` or ``frame_dt=0`` were accepted and
        failed inside MuJoCo or as a division by zero minutes later)."""
        for name in ("width", "height"):
            v = whole_number(name, getattr(self, name))
            if not 32 <= v <= 16384:
                raise ValueError(f"{name} must be in [32, 16384] pixels, got {v}")
        if whole_number("min_mask_px", self.min_mask_px) < 0:
            raise ValueError(f"min_mask_px must be >= 0, got {self.min_mask_px}")
        for name in ("frame_dt", "push_speed", "transit_speed"):
            if finite_number(name, getattr(self, name)) <= 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("min_object_height", "finger_depth", "finger_margin", "carry_clearance", "settle_s"):
            if finite_number(name, getattr(self, name)) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        d = self.push_dist
        if (isinstance(d, (str, bytes)) or not isinstance(d, (tuple, list)) or len(d) != 2
                or not 0 <= finite_number("push_dist", d[0]) <= finite_number("push_dist", d[1])):
            raise ValueError(f"push_dist must be (low, high) metres with 0 <= low <= high, got {d!r:.40}")


@dataclass
class PushedScene:
    """A trial's scene after the push: what every method is run on.

    Attributes:
        seed, index: the trial (the scene is drawn from ``[seed, index]``).
        scene: the drawn scene.
        frames: the recorded clip, (H, W, 3) uint8 RGB each.
        state: the simulator state after the clip (restored for every method).
        pushed: objects the push moved by more than 5 mm or 3 degrees.
        seconds: wall time of simulating and rendering the push.
    """

    seed: int
    index: int
    scene: StackScene
    frames: list[np.ndarray]
    state: tuple
    pushed: int
    seconds: float


@dataclass
class TrialResult:
    """What happened in one trial.

    Attributes:
        seed, index: the trial.
        method: method name.
        stacked: objects stacked while the tower stood.
        success: five stacked, the tower standing still.
        failure: one of :data:`FAILURES`, or None on success.
        n_masks: masks the method gave (at least ``min_mask_px`` pixels).
        seconds: wall time of segmentation and stacking (the shared push clip excluded);
            ``segment_seconds`` of the method alone.
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


def _radius(shape: str, cell: float) -> float:
    c = np.asarray(SHAPES[shape], float)
    c -= c.mean(axis=0)
    return float(np.max(np.linalg.norm(c, axis=1)) * cell + 0.71 * cell)


def _push_plan(sim: StackSim, rng: np.random.Generator, config: TrialConfig) -> list[tuple[np.ndarray, np.ndarray]]:
    """Start and end of one push per object, random order, roughly away from the
    arrangement's centre (within 80 degrees; so the push does not drive objects into each
    other), starting where the closed fingers can come down without touching another
    object."""
    pos = sim.object_pos()[:, :2]
    radii = [_radius(s, c) for s, c in zip(sim.scene.shapes, sim.scene.cell)]
    centre = pos.mean(axis=0)
    plan = []
    for i in rng.permutation(N_OBJECTS):
        out = pos[i] - centre
        base = math.atan2(out[1], out[0]) if np.linalg.norm(out) > 0.02 else rng.uniform(-np.pi, np.pi)
        for attempt in range(120):
            spread = 1.4 if attempt < 60 else np.pi  # then any direction
            ang = base + rng.uniform(-spread, spread)
            d = np.array([math.cos(ang), math.sin(ang)])
            start = pos[i] - d * (radii[i] + 0.025)
            if all(np.linalg.norm(start - pos[j]) > radii[j] + 0.02 for j in range(N_OBJECTS) if j != i):
                plan.append((start, start + d * (0.025 + rng.uniform(*config.push_dist))))
                break
    return plan


def _nearest_yaw(current: float, yaw: float) -> float:
    """``yaw`` plus the multiple of pi closest to ``current`` (the gripper is symmetric)."""
    return yaw + math.pi * round((current - yaw) / math.pi)


def push_scene(seed: int, index: int, config: TrialConfig = TrialConfig()) -> PushedScene:
    """Draw trial ``index``'s scene, push every object once, record the clip.

    The gripper, fingers closed, pushes each composite in turn (random order and
    direction), then rises out of the camera's view.
    """
    t0 = time.perf_counter()
    scene, rng = trial_scene(seed, index, config)
    sim = StackSim(scene, frame_dt=config.frame_dt)
    try:
        sim.place_hand([0.0, -0.05, 0.35])
        sim.set_opening(0.0)
        sim.step(0.5)
        p0, m0 = sim.object_pos(), sim.data.xmat[sim.object_ids].copy()
        frames: list[np.ndarray] = [sim.rgb()]
        sim.recorder = frames.append
        z_push, z_air = 0.01, 0.07
        for start, end in _push_plan(sim, rng, config):
            yaw = _nearest_yaw(sim.hand_yaw, math.atan2(end[1] - start[1], end[0] - start[0]))
            sim.move([start[0], start[1], z_air], yaw, speed=config.transit_speed)
            sim.move([start[0], start[1], z_push], speed=config.transit_speed)
            sim.move([end[0], end[1], z_push], speed=config.push_speed)
            sim.move([end[0], end[1], z_air], speed=config.transit_speed)
        sim.move([sim.hand_pos[0], 0.05, 0.6], speed=config.transit_speed)  # up, out of view
        sim.step(0.2)
        sim.recorder = None
        p1, m1 = sim.object_pos(), sim.data.xmat[sim.object_ids]
        turned = [math.degrees(math.acos(np.clip((np.trace(a.reshape(3, 3).T @ b.reshape(3, 3)) - 1) / 2, -1, 1)))
                  for a, b in zip(m0, m1)]
        moved = int(sum((np.linalg.norm(p1 - p0, axis=1) > 0.005) | (np.array(turned) > 3)))
        return PushedScene(seed=seed, index=index, scene=scene, frames=frames, state=sim.get_state(),
                           pushed=moved, seconds=time.perf_counter() - t0)
    finally:
        sim.close()


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


def _approach(g: WorldGrasp, heights: HeightMap, config: TrialConfig) -> tuple[float, float, float]:
    """``(yaw, half opening, fingertip height)`` of the grasp: across the minor axis if
    both fingers can come down there (depth render), else across the major axis, else
    the minor axis anyway. Unseen footprints (hidden behind objects) count as blocked."""
    grasp_z = max(g.top - config.finger_depth, 0.004)
    options = [(g.yaw, g.reach), (g.yaw + math.pi / 2, g.reach_major)]
    for yaw, reach in options:
        for margin in (config.finger_margin, config.finger_margin / 2):
            half = reach + margin
            if half <= FINGER_MAX and finger_clearance(heights, g.xy, yaw, half) < grasp_z + 0.004:
                return yaw, half, grasp_z
    return g.yaw, min(g.reach + config.finger_margin, FINGER_MAX), grasp_z


def run_trial(method: str, labels_fn: LabelsFn | None, pushed: PushedScene,
              config: TrialConfig = TrialConfig(),
              video: Callable[[np.ndarray], None] | None = None,
              gt: bool = False) -> TrialResult:
    """Segment the pushed scene's clip with a method, then stack greedily.

    Args:
        method: name recorded in the result.
        labels_fn: ``frames -> (H, W) int labels of the last frame``; ignored if ``gt``.
        pushed: from :func:`push_scene` (the same for every method).
        config: trial parameters.
        video: called with the clip's frames and then every frame of the stacking.
        gt: use the simulator's exact instance masks of the last frame (all five objects).

    Raises:
        ValueError: the method's label map does not have the frames' size.
    """
    t0 = time.perf_counter()
    scene = pushed.scene
    sim = StackSim(scene, frame_dt=config.frame_dt)
    res = TrialResult(seed=pushed.seed, index=pushed.index, method=method, n_frames=len(pushed.frames))
    try:
        sim.set_state(pushed.state)
        if video is not None:
            for f in pushed.frames:
                video(f)
        t1 = time.perf_counter()
        labels = sim.segmentation() + 1 if gt else np.asarray(labels_fn(list(pushed.frames)))
        res.segment_seconds = time.perf_counter() - t1
        if labels.shape != (scene.height, scene.width):
            raise ValueError(f"method {method!r} returned labels of shape {labels.shape}, "
                             f"expected {(scene.height, scene.width)}")
        points = sim.camera().backproject(sim.depth())
        masks = _masks(labels, config.min_mask_px)
        res.n_masks = len(masks)
        grasps = [world_grasp(m, points) for m in masks]
        # a mask with nothing standing in it (bare table, floor, wall) is not graspable
        grasps = [g for g in grasps if g is not None and g.top >= config.min_object_height]
        res.log.append(f"{len(masks)} masks, {len(grasps)} with something standing in them")
        sim.recorder = video
        _stack(sim, grasps, points, config, res)
        sim.recorder = None
    finally:
        sim.close()
    res.seconds = time.perf_counter() - t0
    return res


def _stack(sim: StackSim, grasps: list[WorldGrasp], points: np.ndarray, config: TrialConfig,
           res: TrialResult) -> None:
    tower_xy = np.array(sim.scene.tower_xy)
    place_xy = tower_xy  # centre of the tower's top face (measured after every placement)
    place_yaw: float | None = None  # every object goes down with the first one's axes
    stacked: list[int] = []
    rest: dict[int, np.ndarray] = {}
    tower_top = 0.0
    heights = HeightMap(points)
    for k, g in enumerate(grasps):
        if len(stacked) == N_OBJECTS:
            break
        before = sim.object_pos()
        carry_z = tower_top + 0.12 + config.carry_clearance
        yaw, half, grasp_z = _approach(g, heights, config)
        yaw = _nearest_yaw(sim.hand_yaw, yaw)
        sim.set_opening(half)
        sim.move([g.xy[0], g.xy[1], carry_z], yaw, speed=0.4)
        reached = sim.move_down(grasp_z, speed=0.15)
        sim.set_opening(0.0)
        sim.step(0.5)
        sim.move([g.xy[0], g.xy[1], carry_z], speed=0.2)
        sim.step(0.2)
        lifted = [i for i in range(N_OBJECTS)
                  if i not in stacked and sim.object_pos()[i, 2] > before[i, 2] + 0.03]
        if not lifted:
            res.failure = "grasp"
            res.log.append(f"mask {k}: grasp at {g.xy[0]:+.3f},{g.xy[1]:+.3f} lifted nothing"
                           + ("" if reached else " (fingers blocked on the way down)"))
            return
        # each object is held with its grasp axis along the jaws: placing it with the same
        # hand yaw as the first object lines all their principal axes up
        place_yaw = sim.hand_yaw if place_yaw is None else place_yaw
        sim.move([place_xy[0], place_xy[1], carry_z], _nearest_yaw(sim.hand_yaw, place_yaw), speed=0.3)
        if not all(sim.object_pos()[i, 2] > 0.05 for i in lifted):
            res.failure = "grasp"
            res.log.append(f"mask {k}: object {lifted} slipped out while carried")
            return
        sim.move_down(tower_top + grasp_z + 0.008, speed=0.1)
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
        points = sim.camera().backproject(sim.depth())
        heights = HeightMap(points)
        tower_top, place_xy = _tower_top(points, tower_xy)
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
