"""Simulate a :class:`ScenePlan`, render its frames, and derive exact ground truth.

Ground truth of the last frame (MotionBit definition, paper eq. 4): a pixel gets the label
of its rigid body if that body *moved at some time during the clip*.

* Pixel -> geom: MuJoCo's segmentation rendering (exact per-pixel geom ids).
* Geom -> rigid body: ``model.geom_bodyid`` then ``model.body_weldid`` (the root of the
  chain of jointless links it is welded to), so glued composites are one body and
  jointless child links merge into their parent; anything welded to the world is static.
* Moved: max over frames t of the displacement of the corners of the body's bounding box,
  ``max_t max_c |R_t c + x_t - (R_0 c + x_0)|`` (an upper bound of the displacement of any
  of its points, since displacement is affine in the point); not first-vs-last, so a body
  that moves and comes back counts. Bodies above ``MOVED_M`` are labelled; below
  ``STATIC_M`` they are background; in between they are written to the ignore mask.
* Agents: the mocap ``pusher`` of the robot and hand tracks is a rigid body like any other
  (labelled when it moved); every body under a mocap agent ``agent*`` (the harder tracks'
  articulated hands and grippers) is written to the ignore mask.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from motionbits.synth.mujoco_agents import AGENT_PREFIX
from motionbits.synth.mujoco_backend import import_mujoco
from motionbits.synth.mujoco_choreo import ChoreoDriver
from motionbits.synth.mujoco_scenes import ScenePlan
from motionbits.synth.scene_flow import FrameGeometry, gl_camera

__all__ = ["SimulatedClip", "simulate", "agent_roots", "MOVED_M", "STATIC_M", "SETTLE_S"]

MOVED_M = 0.005  # m: a body moved if some point moved this far (~3 px at 1 m, 480x640)
STATIC_M = 0.001  # m: below this a body is static; between the two it is ignored
SETTLE_S = 0.6  # s of simulation before the first frame (objects come to rest)
_MAX_SPEED = 3.0  # m/s: faster means the simulation blew up
_SUBSTEP_LIMIT = 400


@dataclass
class SimulatedClip:
    """Result of one simulated clip.

    Attributes:
        frames: (T, H, W, 3) uint8 RGB.
        gt: (H, W) int32 labels of the last frame, 0 = background, 1..K = moved bodies.
        ignore: (H, W) bool, pixels of bodies whose motion was ambiguous.
        geom_ids: (H, W) int32 geom id per pixel of the last frame (-1 = nothing).
        root_of_geom: (ngeom,) int32 rigid-body root (``body_weldid``) of every geom.
        deviation: (nbody,) float64 max deviation of every root body in metres (0 for
            non-roots).
        label_of_root: {root body id: label}.
        body_names: name of every body.
        valid: False if the simulation blew up or something fell off the table.
        info: extra facts for meta.json.
        geometry: per frame depth, geom ids, body poses and camera (``record_geometry``).
        geom_body: (ngeom,) int32 body of every geom (``model.geom_bodyid``).
        body_root: (nbody,) int32 rigid-body root of every body (``model.body_weldid``).
    """

    frames: np.ndarray
    gt: np.ndarray
    ignore: np.ndarray
    geom_ids: np.ndarray
    root_of_geom: np.ndarray
    deviation: np.ndarray
    label_of_root: dict[int, int]
    body_names: list[str]
    valid: bool
    info: dict = field(default_factory=dict)
    geometry: list[FrameGeometry] | None = None
    geom_body: np.ndarray | None = None
    body_root: np.ndarray | None = None


def _frame_geometry(mujoco, renderer, data, width: int, height: int) -> FrameGeometry:
    """Depth, geom ids, body poses and camera of the scene last passed to ``update_scene``."""
    camera = gl_camera(renderer.scene.camera[0], width, height)
    renderer.enable_depth_rendering()
    depth = renderer.render().astype(np.float32)
    renderer.enable_segmentation_rendering()
    seg = renderer.render()
    renderer.disable_segmentation_rendering()
    geom_ids = np.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
    return FrameGeometry(depth, geom_ids.astype(np.int32), data.xpos.copy(),
                         data.xmat.reshape(-1, 3, 3).copy(), camera)


def agent_roots(model) -> set[int]:
    """Rigid-body roots (``body_weldid``) of every body under a mocap agent ``agent*``: the
    agent's pixels are ignored in the ground truth (its fingers are several rigid links)."""
    out = set()
    for b in range(1, model.nbody):
        top = model.body(int(model.body_rootid[b])).name
        if top.startswith(AGENT_PREFIX) and model.body_weldid[b] != 0:
            out.add(int(model.body_weldid[b]))
    return out


def _yaw_quat(yaw: float) -> np.ndarray:
    return np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])


def _root_corners(mujoco, model, data) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per root body: bounding-box corners of all its geoms in the root's frame (at frame 0)."""
    roots: dict[int, list[np.ndarray]] = {}
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T  # (8, 3)
    for g in range(model.ngeom):
        root = int(model.body_weldid[model.geom_bodyid[g]])
        if root == 0:
            continue
        aabb = model.geom_aabb[g]
        local = aabb[:3] + signs * aabb[3:]
        world = data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T
        x0, r0 = data.xpos[root], data.xmat[root].reshape(3, 3)
        roots.setdefault(root, []).append((world - x0) @ r0)
    return {r: np.concatenate(c) for r, c in roots.items()}


def _set_camera(cam, c) -> None:
    cam.lookat[:] = c.lookat
    cam.distance, cam.azimuth, cam.elevation = c.distance, c.azimuth, c.elevation


def simulate(plan: ScenePlan, *, width: int = 640, height: int = 480,
             n_frames: int | None = None, record_geometry: bool = False) -> SimulatedClip:
    """Settle the scene, move the pusher along its plan, render every frame.

    Args:
        plan: from :func:`compose_scene`.
        width, height: render size.
        n_frames: override the plan's clip length (tests use short clips).
        record_geometry: also render depth and geom ids of every frame and keep the body
            poses and camera (``clip.geometry``, for the exact flow).
    """
    mujoco = import_mujoco()
    model = mujoco.MjModel.from_xml_string(plan.xml, plan.assets or None)
    data = mujoco.MjData(model)
    for name, q in plan.init_qpos.items():
        data.qpos[model.joint(name).qposadr[0]] = q
    driver = None
    if plan.script is None:  # robot / hand tracks: one straight push of ``pusher``
        pusher = model.body("pusher")
        mocap = int(model.body_mocapid[pusher.id])
        data.mocap_pos[mocap] = plan.start
        data.mocap_quat[mocap] = _yaw_quat(plan.yaw)
    else:
        driver = ChoreoDriver(mujoco, model, data, plan.script)
        driver.apply(0.0)
    mujoco.mj_forward(model, data)
    # Settle: gravity brings objects to rest; joint friction holds articulated parts.
    for _ in range(int(round(SETTLE_S / model.opt.timestep))):
        mujoco.mj_step(model, data)
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)

    T = int(n_frames or plan.n_frames)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    _set_camera(cam, plan.camera)
    corners = _root_corners(mujoco, model, data)
    roots = sorted(corners)
    x0 = {r: data.xpos[r].copy() for r in roots}
    r0 = {r: data.xmat[r].reshape(3, 3).copy() for r in roots}
    start_w = {r: corners[r] @ r0[r].T + x0[r] for r in roots}
    deviation = np.zeros(model.nbody)
    steps = max(1, min(_SUBSTEP_LIMIT, int(round(plan.frame_dt / model.opt.timestep))))
    frames = np.zeros((T, height, width, 3), np.uint8)
    # A script written for plan.n_frames frames plays whole in a shorter or longer clip.
    script_rate = (plan.n_frames - 1) / max(T - 1, 1)
    valid = True
    geometry: list[FrameGeometry] = []
    renderer = mujoco.Renderer(model, height, width)
    try:
        for k in range(T):
            if k > 0:
                for j in range(steps):
                    if driver is None:
                        s = ((k - 1) * steps + j + 1) / ((T - 1) * steps)
                        ease = 0.5 - 0.5 * np.cos(np.pi * s)
                        data.mocap_pos[mocap] = plan.start + ease * (plan.end - plan.start)
                    else:
                        driver.apply((k - 1 + (j + 1) / steps) * script_rate)
                    mujoco.mj_step(model, data)
                if not np.all(np.isfinite(data.qpos)) or np.abs(data.qvel).max(initial=0) > 50:
                    valid = False
            if driver is not None:  # render the exact scripted state of time k
                driver.apply(k * script_rate)
                mujoco.mj_forward(model, data)
            for r in roots:
                now = corners[r] @ data.xmat[r].reshape(3, 3).T + data.xpos[r]
                deviation[r] = max(deviation[r], float(np.linalg.norm(now - start_w[r], axis=1).max()))
            if plan.cameras is not None:  # a moving camera; a script's time scale
                _set_camera(cam, plan.cameras[min(int(round(k * script_rate)), len(plan.cameras) - 1)])
            renderer.update_scene(data, camera=cam)
            frames[k] = renderer.render()
            if record_geometry:
                geometry.append(_frame_geometry(mujoco, renderer, data, width, height))
        renderer.enable_segmentation_rendering()
        renderer.update_scene(data, camera=cam)
        seg = renderer.render()
        renderer.disable_segmentation_rendering()
    finally:
        renderer.close()

    geom_type = int(mujoco.mjtObj.mjOBJ_GEOM)
    geom_ids = np.where(seg[..., 1] == geom_type, seg[..., 0], -1).astype(np.int32)
    root_of_geom = model.body_weldid[model.geom_bodyid].astype(np.int32)
    agents = agent_roots(model)
    moved = [r for r in roots if deviation[r] >= MOVED_M and r not in agents]
    unsure = [r for r in roots if STATIC_M <= deviation[r] < MOVED_M or r in agents]
    label_of_root = {r: i + 1 for i, r in enumerate(moved)}
    lut_label = np.zeros(model.nbody + 1, np.int32)  # index nbody: "no geom"
    lut_ignore = np.zeros(model.nbody + 1, bool)
    for r, lab in label_of_root.items():
        lut_label[r] = lab
    lut_ignore[unsure] = True
    pix_root = np.where(geom_ids >= 0, root_of_geom[np.maximum(geom_ids, 0)], model.nbody)
    gt = lut_label[pix_root]
    ignore = lut_ignore[pix_root]

    # Plausibility: nothing fell off the table, nothing flew.
    for r in roots:
        if r in agents or model.body(r).name == "pusher":
            continue
        if data.xpos[r][2] < -0.05 or deviation[r] > plan.max_travel:
            valid = False
    speed_ok = np.abs(data.qvel).max(initial=0) < _MAX_SPEED * 10
    valid = bool(valid and speed_ok)
    names = [model.body(i).name for i in range(model.nbody)]
    return SimulatedClip(
        frames=frames, gt=gt.astype(np.int32), ignore=ignore, geom_ids=geom_ids,
        root_of_geom=root_of_geom, deviation=deviation, label_of_root=label_of_root,
        body_names=names, valid=valid, geometry=geometry or None,
        geom_body=model.geom_bodyid.astype(np.int32), body_root=model.body_weldid.astype(np.int32),
        info={"sim_steps_per_frame": steps, "timestep": float(model.opt.timestep),
              "agent_roots": sorted(agents)},
    )
