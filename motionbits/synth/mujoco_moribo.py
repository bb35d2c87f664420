"""Write MuJoCo clips as MoRiBo-format scenes, one track at a time.

Scene folder: ``frames/00000.jpg ...`` (RGB, JPEG quality 95), ``gt.png`` (16-bit labels of
the last frame), ``ignore.png`` (only if some body's motion was ambiguous: 255 = ignored) and
``meta.json`` (seed, camera, labels -> bodies, max deviations, the push). Deterministic for
a seed on one machine (same MuJoCo build and renderer).
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
from PIL import Image
from tqdm import tqdm

from motionbits.synth.camera_paths import CAMERA_MODES, camera_path
from motionbits.synth.mujoco_backend import import_mujoco
from motionbits.synth.mujoco_scenes import TRACKS, ScenePlan, compose_scene
from motionbits.synth.mujoco_sim import MOVED_M, STATIC_M, SimulatedClip, simulate
from motionbits.synth.scene_flow import flow_between

__all__ = ["generate_scene", "write_scene", "generate_track", "scene_seed", "scene_flows",
           "CAMERA_CHOICES", "FLOW_CONVENTION"]

CAMERA_CHOICES = (*CAMERA_MODES, "moving")  # "moving": pan, orbit or shake, drawn per scene
_CAMERA_STREAM = 7919  # extra entropy word of the camera's random stream
FLOW_CONVENTION = (
    "flow/NNNNN.npz (N = frame k >= 1), float16 pixels (dx, dy): 'backward' = flow(frame k, "
    "frame k-1) on frame k's pixels (where each pixel of k was in k-1), 'forward' = flow(frame "
    "k-1, frame k) on frame k-1's pixels; 'backward_valid' / 'forward_valid' = the point is "
    "visible in the other frame (not occluded, in view). Same convention as motionbits.flow: "
    "flow(a, b)[y, x] = position in b of pixel (x, y) of a, minus (x, y).")

_MAX_ATTEMPTS = 12
GENERATOR_VERSION = 1


def scene_seed(seed: int, track: str, index: int, attempt: int = 0) -> list[int]:
    """Entropy of scene ``index`` of ``track`` (independent streams per scene and attempt)."""
    return [int(seed), TRACKS.index(track), int(index), int(attempt)]


def generate_scene(track: str, seed: int, index: int = 0, *, width: int = 640, height: int = 480,
                   n_frames: int | None = None, camera: str = "static",
                   flow: bool = False) -> tuple[SimulatedClip, ScenePlan, dict]:
    """Draw, simulate and render one scene; retry other draws until one is plausible.

    A draw is kept if the simulation stayed plausible (nothing exploded or fell off the
    table) and the push moved at least one body besides the pusher. The camera path is
    drawn from its own random stream, so a scene's content does not depend on ``camera``.

    Args:
        camera: one of :data:`CAMERA_CHOICES`.
        flow: also render depth and geom ids of every frame (``clip.geometry``) for
            :func:`scene_flows`.

    Returns:
        ``(clip, plan, meta)``; ``meta`` is what ``meta.json`` holds.

    Raises:
        RuntimeError: no plausible draw in a dozen attempts (should not happen).
    """
    if track not in TRACKS:
        raise ValueError(f"unknown track {track!r}; choose one of {TRACKS}")
    if camera not in CAMERA_CHOICES:
        raise ValueError(f"unknown camera {camera!r}; choose one of {CAMERA_CHOICES}")
    mujoco = import_mujoco()
    reasons = []
    for attempt in range(_MAX_ATTEMPTS):
        rng = np.random.default_rng(scene_seed(seed, track, index, attempt))
        try:
            plan = compose_scene(track, rng, width=width, height=height)
        except ValueError as exc:
            reasons.append(str(exc))
            continue
        mode = camera
        if camera != "static":
            cam_rng = np.random.default_rng([*scene_seed(seed, track, index, attempt), _CAMERA_STREAM])
            if camera == "moving":
                mode = ("pan", "orbit", "shake")[int(cam_rng.integers(3))]
            plan = dataclasses.replace(plan, cameras=camera_path(mode, plan.camera, plan.n_frames, cam_rng))
        clip = simulate(plan, width=width, height=height, n_frames=n_frames, record_geometry=flow)
        movers = [r for r in clip.label_of_root if clip.body_names[r] != "pusher"]
        if clip.valid and movers:
            meta = _meta(clip, plan, track, seed, index, attempt, mujoco.__version__)
            if plan.cameras is not None:
                meta["camera_motion"] = {"mode": mode, "cameras": [asdict(c) for c in plan.cameras]}
            return clip, plan, meta
        reasons.append("implausible simulation" if not clip.valid else "the push moved nothing")
    raise RuntimeError(f"no plausible scene for {track} seed {seed} index {index}: {reasons}")


def _kind(name: str, plan: ScenePlan) -> str:
    if name == "pusher":
        return "gripper" if plan.track == "robot" else "hand"
    return dict(plan.parts).get(name, "link")


def _meta(clip: SimulatedClip, plan: ScenePlan, track: str, seed: int, index: int,
          attempt: int, mj_version: str) -> dict:
    h, w = clip.gt.shape
    labels = {}
    for root, lab in sorted(clip.label_of_root.items(), key=lambda kv: kv[1]):
        name = clip.body_names[root]
        labels[str(lab)] = {
            "body": name, "kind": _kind(name, plan),
            "max_deviation_m": round(float(clip.deviation[root]), 5),
            "pixels": int(np.count_nonzero(clip.gt == lab)),
        }
    ignored = [clip.body_names[r] for r in range(len(clip.body_names))
               if STATIC_M <= clip.deviation[r] < MOVED_M or r in clip.info.get("agent_roots", ())]
    return {
        "format": "MoRiBo", "generator": "motionbits.synth.mujoco", "version": GENERATOR_VERSION,
        "mujoco": mj_version, "track": track, "seed": int(seed), "index": int(index),
        "attempt": int(attempt), "width": int(w), "height": int(h),
        "n_frames": int(clip.frames.shape[0]), "fps": round(1.0 / plan.frame_dt, 3),
        "camera": {**asdict(plan.camera), "fovy_deg": 45.0},
        "push": {"target": plan.target[0], "target_kind": plan.target[1],
                 "start": [round(float(v), 4) for v in plan.start],
                 "end": [round(float(v), 4) for v in plan.end]},
        "thresholds_m": {"moved": MOVED_M, "static": STATIC_M},
        "labels": labels, "ignored_bodies": ignored,
        "parts": [{"name": n, "kind": k} for n, k in plan.parts],
        "gt_definition": "last-frame pixels of every rigid body (geom -> body -> body_weldid) "
                         "whose max deviation over the clip >= thresholds_m.moved",
        **_script_meta(plan),
    }


def _script_meta(plan: ScenePlan) -> dict:
    """The choreography of a scripted scene, in meta.json terms (empty for plain pushes)."""
    if plan.script is None:
        return {}

    def r(v):
        return [round(float(x), 4) for x in np.ravel(v)]

    return {"agents_ignored": True, "script": {
        "agents": [{"body": a.body, "times": r(a.times), "positions": [r(p) for p in a.positions],
                    "yaws": r(a.yaws), "grips": r(a.grips)} for a in plan.script.agents],
        "carries": [{"agent": c.agent, "body": c.body, "t_grasp": round(c.t_grasp, 4),
                     "t_release": round(c.t_release, 4)} for c in plan.script.carries],
        "kicks": [{"body": k.body, "t": round(k.t, 4), "velocity": r(k.velocity)}
                  for k in plan.script.kicks],
    }}


def scene_flows(clip: SimulatedClip) -> list[dict[str, np.ndarray]]:
    """Exact flow between consecutive frames of a clip simulated with ``record_geometry``.

    Returns:
        For k = 1..T-1 a dict: ``backward`` (H, W, 2) float32 = flow(frame k, frame k-1),
        ``forward`` (H, W, 2) float32 = flow(frame k-1, frame k), and their (H, W) bool
        ``backward_valid`` / ``forward_valid`` (see :data:`FLOW_CONVENTION`).
    """
    if clip.geometry is None:
        raise ValueError("the clip was simulated without record_geometry=True: no flow")
    g, gb, br = clip.geometry, clip.geom_body, clip.body_root
    out = []
    for k in range(1, len(g)):
        back, back_ok = flow_between(g[k], g[k - 1], gb, br)
        fwd, fwd_ok = flow_between(g[k - 1], g[k], gb, br)
        out.append({"backward": back, "backward_valid": back_ok,
                    "forward": fwd, "forward_valid": fwd_ok})
    return out


def _flow_stats(clip: SimulatedClip, flows: list[dict[str, np.ndarray]]) -> dict:
    """Largest visible motion in pixels per frame: of the labelled bodies and of the agents."""
    agents = np.asarray(clip.info.get("agent_roots", []), int)
    body_max, agent_max, world_max = 0.0, 0.0, 0.0
    for k, f in enumerate(flows, start=1):
        geo = clip.geometry[k]
        root = clip.body_root[clip.geom_body[np.maximum(geo.geom_ids, 0)]]
        mag = np.hypot(f["backward"][..., 0], f["backward"][..., 1])
        ok = f["backward_valid"]
        is_agent = np.isin(root, agents)
        for mask, name in ((ok & ~is_agent & (root > 0), "body"), (ok & is_agent, "agent"),
                           (ok & (root == 0), "world")):
            if mask.any():
                v = float(mag[mask].max())
                if name == "body":
                    body_max = max(body_max, v)
                elif name == "agent":
                    agent_max = max(agent_max, v)
                else:
                    world_max = max(world_max, v)
    return {"max_px_per_frame": {"bodies": round(body_max, 2), "agents": round(agent_max, 2),
                                 "static_world": round(world_max, 2)}}


def write_scene(folder: str | os.PathLike, clip: SimulatedClip, meta: dict,
                flows: list[dict[str, np.ndarray]] | None = None) -> Path:
    """Write one scene folder in MoRiBo format (plus ``flow/`` if ``flows``); return its path."""
    from motionbits.eval.labelmaps import write_label_map

    folder = Path(folder)
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    for k, frame in enumerate(clip.frames):
        Image.fromarray(frame).save(folder / "frames" / f"{k:05d}.jpg", quality=95)
    write_label_map(folder / "gt.png", clip.gt)
    if clip.ignore.any():
        Image.fromarray(clip.ignore.astype(np.uint8) * 255).save(folder / "ignore.png")
    if flows is not None:
        (folder / "flow").mkdir(exist_ok=True)
        for k, f in enumerate(flows, start=1):
            np.savez_compressed(folder / "flow" / f"{k:05d}.npz",
                                **{n: (a.astype(np.float16) if a.dtype.kind == "f" else a)
                                   for n, a in f.items()})
        meta = {**meta, "flow": {"convention": FLOW_CONVENTION, **_flow_stats(clip, flows)}}
    (folder / "meta.json").write_text(json.dumps(meta, indent=1))
    return folder


def generate_track(track: str, n_scenes: int, seed: int, out: str | os.PathLike, *,
                   width: int = 640, height: int = 480, n_frames: int | None = None,
                   progress: bool = True, camera: str = "static", flow: bool = False) -> list[Path]:
    """Generate ``n_scenes`` scenes of ``track`` into ``out/<track>/scene_NNNN``
    (``out/<track>-<camera>/`` for a moving camera), with ``flow/`` if ``flow``.

    Returns:
        The scene folders, in order.
    """
    if n_scenes < 1:
        raise ValueError(f"n_scenes must be >= 1, got {n_scenes}")
    name = track if camera == "static" else f"{track}-{camera}"
    root = Path(out) / name
    paths = []
    t0 = time.perf_counter()
    for i in tqdm(range(n_scenes), desc=f"synth {name}", unit="scene", disable=not progress):
        clip, _, meta = generate_scene(track, seed, i, width=width, height=height,
                                       n_frames=n_frames, camera=camera, flow=flow)
        flows = scene_flows(clip) if flow else None
        paths.append(write_scene(root / f"scene_{i:04d}", clip, meta, flows))
    if progress:
        dt = time.perf_counter() - t0
        print(f"{name}: {n_scenes} scenes in {dt:.1f} s ({dt / n_scenes:.2f} s/scene) -> {root}")
    return paths
