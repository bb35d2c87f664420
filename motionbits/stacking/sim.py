"""Stepping the stacking scene: the mocap hand's smooth moves, the fingers, the camera.

Every move interpolates the hand's pose with a cosine ease (no jerks for the physics) and,
while a recorder is set, renders one RGB frame every ``frame_dt`` simulated seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from motionbits.stacking.perception import PinholeCamera
from motionbits.stacking.scene import FINGER_MAX, StackScene
from motionbits.synth.mujoco_backend import import_mujoco

__all__ = ["StackSim"]


def _yaw_quat(yaw: float) -> np.ndarray:
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


class StackSim:
    """MuJoCo model, data and renderer of one :class:`StackScene`.

    Args:
        scene: the drawn scene.
        frame_dt: simulated seconds between recorded frames.
    """

    def __init__(self, scene: StackScene, frame_dt: float = 0.1) -> None:
        self.mj = import_mujoco()
        self.scene = scene
        self.model = self.mj.MjModel.from_xml_string(scene.xml)
        self.data = self.mj.MjData(self.model)
        self.frame_dt = frame_dt
        self.object_ids = [self.model.body(n).id for n in scene.objects]
        self.mocap = int(self.model.body_mocapid[self.model.body("hand_target").id])
        self._hand_qpos = int(self.model.joint("hand").qposadr[0])
        self._hand_qvel = int(self.model.joint("hand").dofadr[0])
        self.hand_pos = self.data.mocap_pos[self.mocap].copy()
        self.hand_yaw = 0.0
        self.recorder: Callable[[np.ndarray], None] | None = None
        self._renderer = None
        self._since_frame = 0.0
        self.mj.mj_forward(self.model, self.data)
        self.camera_id = self.model.camera("cam").id

    # ----- rendering -------------------------------------------------------------------
    @property
    def renderer(self):
        if self._renderer is None:
            self._renderer = self.mj.Renderer(self.model, self.scene.height, self.scene.width)
        return self._renderer

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def rgb(self) -> np.ndarray:
        """(H, W, 3) uint8 RGB from the fixed camera."""
        self.renderer.update_scene(self.data, camera="cam")
        return self.renderer.render().copy()

    def depth(self) -> np.ndarray:
        """(H, W) float32 depth along the optical axis, metres."""
        r = self.renderer
        r.enable_depth_rendering()
        try:
            r.update_scene(self.data, camera="cam")
            return r.render().copy()
        finally:
            r.disable_depth_rendering()

    def segmentation(self) -> np.ndarray:
        """(H, W) int32 index of the object (0..4) seen at each pixel, -1 elsewhere.

        Geom -> body -> ``body_weldid`` (the rigid body a geom belongs to), as the
        benchmark generator does.
        """
        r = self.renderer
        r.enable_segmentation_rendering()
        try:
            r.update_scene(self.data, camera="cam")
            seg = r.render()
        finally:
            r.disable_segmentation_rendering()
        geom_type = int(self.mj.mjtObj.mjOBJ_GEOM)
        gid = np.where(seg[..., 1] == geom_type, seg[..., 0], -1)
        root = self.model.body_weldid[self.model.geom_bodyid]
        lut = np.full(self.model.nbody, -1, np.int32)
        for i, b in enumerate(self.object_ids):
            lut[b] = i
        return np.where(gid >= 0, lut[root[np.maximum(gid, 0)]], -1).astype(np.int32)

    def camera(self) -> PinholeCamera:
        """The camera's intrinsics and pose."""
        return PinholeCamera(
            width=self.scene.width, height=self.scene.height,
            fovy_deg=float(self.model.cam_fovy[self.camera_id]),
            pos=self.data.cam_xpos[self.camera_id].copy(),
            rot=self.data.cam_xmat[self.camera_id].reshape(3, 3).copy(),
        )

    # ----- stepping --------------------------------------------------------------------
    def step(self, seconds: float) -> None:
        """Advance the simulation, recording frames if a recorder is set."""
        n = max(1, int(round(seconds / self.model.opt.timestep)))
        for _ in range(n):
            self._step_once()

    def _step_once(self) -> None:
        self.mj.mj_step(self.model, self.data)
        if self.recorder is not None:
            self._since_frame += self.model.opt.timestep
            if self._since_frame >= self.frame_dt - 1e-9:
                self._since_frame = 0.0
                self.recorder(self.rgb())

    def move(self, pos, yaw: float | None = None, speed: float = 0.25) -> None:
        """Move the hand to ``pos`` (3,) and ``yaw`` at about ``speed`` m/s, eased."""
        start, target = self.hand_pos.copy(), np.asarray(pos, float)
        y0 = self.hand_yaw
        y1 = y0 if yaw is None else float(yaw)
        dist = float(np.linalg.norm(target - start))
        duration = max(dist / speed, abs(y1 - y0) / 2.0, 0.05)
        n = max(1, int(round(duration / self.model.opt.timestep)))
        for k in range(1, n + 1):
            s = 0.5 - 0.5 * math.cos(math.pi * k / n)
            self.data.mocap_pos[self.mocap] = start + s * (target - start)
            self.data.mocap_quat[self.mocap] = _yaw_quat(y0 + s * (y1 - y0))
            self._step_once()
        self.hand_pos, self.hand_yaw = target, y1

    def move_down(self, z: float, speed: float = 0.1, blocked: float = 0.006) -> bool:
        """Lower the hand to height ``z``; stop where something blocks it (the hand lags
        its target by more than ``blocked`` m). Returns True if it got there."""
        hand = self.model.body("hand").id
        start = self.hand_pos.copy()
        n = max(1, int(round(abs(start[2] - z) / speed / self.model.opt.timestep)))
        for k in range(1, n + 1):
            target = start.copy()
            target[2] = start[2] + (z - start[2]) * k / n
            self.data.mocap_pos[self.mocap] = target
            self._step_once()
            if self.data.xpos[hand][2] - target[2] > blocked:
                self.hand_pos = self.data.xpos[hand].copy()
                self.data.mocap_pos[self.mocap] = self.hand_pos
                return False
        self.hand_pos = np.array([start[0], start[1], z])
        return True

    def get_state(self) -> tuple[np.ndarray, np.ndarray, float]:
        """Full integration state (for replaying one pushed scene with every method)."""
        spec = self.mj.mjtState.mjSTATE_INTEGRATION
        state = np.zeros(self.mj.mj_stateSize(self.model, spec))
        self.mj.mj_getState(self.model, self.data, state, spec)
        return state, self.hand_pos.copy(), self.hand_yaw

    def set_state(self, saved: tuple[np.ndarray, np.ndarray, float]) -> None:
        state, self.hand_pos, self.hand_yaw = saved
        self.hand_pos = self.hand_pos.copy()
        self.mj.mj_setState(self.model, self.data, state, self.mj.mjtState.mjSTATE_INTEGRATION)
        self.mj.mj_forward(self.model, self.data)

    def place_hand(self, pos, yaw: float = 0.0) -> None:
        """Put the hand somewhere at once (before anything touches it)."""
        self.hand_pos, self.hand_yaw = np.asarray(pos, float), float(yaw)
        self.data.mocap_pos[self.mocap] = self.hand_pos
        self.data.mocap_quat[self.mocap] = _yaw_quat(self.hand_yaw)
        self.data.qpos[self._hand_qpos:self._hand_qpos + 3] = self.hand_pos
        self.data.qpos[self._hand_qpos + 3:self._hand_qpos + 7] = _yaw_quat(self.hand_yaw)
        self.data.qvel[self._hand_qvel:self._hand_qvel + 6] = 0.0
        self.mj.mj_forward(self.model, self.data)

    def set_opening(self, half_width: float) -> None:
        """Finger target: each finger ``half_width`` m from the hand's centre line."""
        q = float(np.clip(half_width, 0.0, FINGER_MAX))
        self.data.ctrl[:] = q

    def relax(self, margin: float = 0.004) -> None:
        """Release without pulling: each finger's target ``margin`` m outside where it is
        (a finger hooked in a notch of the object would drag it along if opened wide)."""
        for name, act in (("finger_l", 0), ("finger_r", 1)):
            q = float(self.data.qpos[self.model.joint(name).qposadr[0]])
            self.data.ctrl[act] = min(q + margin, FINGER_MAX)

    def finger_gap(self) -> float:
        """Current distance between the fingers' inner faces, metres."""
        return float(self.data.qpos[self.model.joint("finger_l").qposadr[0]]
                     + self.data.qpos[self.model.joint("finger_r").qposadr[0]])

    # ----- object state ----------------------------------------------------------------
    def object_pos(self) -> np.ndarray:
        """(5, 3) object centres of mass."""
        return self.data.xipos[self.object_ids].copy()

    def object_up(self) -> np.ndarray:
        """(5,) cosine between every object's z axis and the world's (1 = upright)."""
        return self.data.xmat[self.object_ids][:, 8].copy()

    def object_speed(self) -> np.ndarray:
        """(5,) linear speed of every object, m/s."""
        vel = np.zeros(6)
        out = []
        for b in self.object_ids:
            self.mj.mj_objectVelocity(self.model, self.data, self.mj.mjtObj.mjOBJ_BODY, b, vel, 0)
            out.append(float(np.linalg.norm(vel[3:])))
        return np.array(out)
