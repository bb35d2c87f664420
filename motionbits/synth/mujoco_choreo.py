"""Scripted motion for generated scenes: agents on keyframed paths, carried objects, kicks.

A :class:`Choreography` says, in frame units (time ``k`` is frame ``k``), where every
mocap-driven agent is, how far its fingers are closed, which object it carries when, and
which objects get a push of velocity. :class:`ChoreoDriver` applies it to a MuJoCo
``MjData`` before each simulation step and before each rendered frame.

Carries are kinematic (the carried object is welded to the agent's hand from the grasp to
the release: its free joint follows the agent's pose exactly), which keeps pick-and-place
deterministic and stable without tuning grasp physics; the fingers still close and open.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["AgentPath", "Carry", "Kick", "Choreography", "ChoreoDriver", "yaw_quat"]


def yaw_quat(yaw: float) -> np.ndarray:
    """(4,) MuJoCo quaternion (w, x, y, z) of a rotation by ``yaw`` radians about z."""
    return np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def _quat_to_mat(q: np.ndarray) -> np.ndarray:
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _rot_z(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class AgentPath:
    """A mocap agent's keyframed path; between keyframes it eases in and out (smoothstep).

    Attributes:
        body: name of the mocap body.
        times: (N,) increasing keyframe times in frames.
        positions: (N, 3) origin of the agent (its grasp point) in metres.
        yaws: (N,) heading in radians.
        grips: (N,) finger closure, 0 = open, 1 = closed.
        actuators: ``(actuator name, ctrl when open, ctrl when closed)`` per finger actuator.
    """

    body: str
    times: tuple[float, ...]
    positions: np.ndarray
    yaws: np.ndarray
    grips: np.ndarray
    actuators: tuple[tuple[str, float, float], ...] = ()

    def at(self, t: float) -> tuple[np.ndarray, float, float]:
        """``(position (3,), yaw, grip)`` at time ``t`` (held constant outside the keyframes)."""
        times = np.asarray(self.times, float)
        if t <= times[0]:
            i, u = 0, 0.0
        elif t >= times[-1]:
            i, u = len(times) - 2, 1.0
        else:
            i = int(np.searchsorted(times, t, side="right") - 1)
            u = (t - times[i]) / (times[i + 1] - times[i])
        e = u * u * (3 - 2 * u)
        p = self.positions[i] + e * (self.positions[i + 1] - self.positions[i])
        yaw = float(self.yaws[i] + e * (self.yaws[i + 1] - self.yaws[i]))
        grip = float(self.grips[i] + e * (self.grips[i + 1] - self.grips[i]))
        return p, yaw, grip


@dataclass(frozen=True)
class Carry:
    """``agent`` holds free body ``body`` rigidly from ``t_grasp`` to ``t_release`` (frames)."""

    agent: str
    body: str
    t_grasp: float
    t_release: float


@dataclass(frozen=True)
class Kick:
    """At time ``t`` (frames) free body ``body`` gets ``velocity``: (6,) linear (m/s) then
    angular (rad/s), world frame."""

    body: str
    t: float
    velocity: tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class Choreography:
    """Everything that moves by script in one clip."""

    agents: tuple[AgentPath, ...]
    carries: tuple[Carry, ...] = ()
    kicks: tuple[Kick, ...] = ()


class ChoreoDriver:
    """Applies a :class:`Choreography` to a model's state.

    Args:
        mujoco: the mujoco module.
        model, data: the simulation.
        script: what to play.
    """

    def __init__(self, mujoco, model, data, script: Choreography):
        self._model, self._data, self._script = model, data, script
        self._mocap = {a.body: int(model.body_mocapid[model.body(a.body).id]) for a in script.agents}
        self._paths = {a.body: a for a in script.agents}
        self._act = {a.body: [(model.actuator(n).id, lo, hi) for n, lo, hi in a.actuators]
                     for a in script.agents}
        self._free_adr = {}
        for c in [*script.carries, *script.kicks]:
            jnt = int(model.body(c.body).jntadr[0])
            if jnt < 0 or model.jnt_type[jnt] != mujoco.mjtJoint.mjJNT_FREE:
                raise ValueError(f"body {c.body!r} has no free joint; it cannot be carried or kicked")
            self._free_adr[c.body] = (int(model.jnt_qposadr[jnt]), int(model.jnt_dofadr[jnt]))
        self._rel: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # carry index -> relative pose
        self._kicked: set[int] = set()

    def apply(self, t: float) -> None:
        """Set agents, fingers, carried and kicked objects for time ``t`` (frames)."""
        d = self._data
        poses = {}
        for name, path in self._paths.items():
            p, yaw, grip = path.at(t)
            poses[name] = (p, yaw)
            d.mocap_pos[self._mocap[name]] = p
            d.mocap_quat[self._mocap[name]] = yaw_quat(yaw)
            for act, lo, hi in self._act[name]:
                d.ctrl[act] = lo + grip * (hi - lo)
        for i, c in enumerate(self._script.carries):
            if not c.t_grasp <= t < c.t_release:
                continue
            qa, va = self._free_adr[c.body]
            p, yaw = poses[c.agent]
            if i not in self._rel:
                rel_p = _rot_z(yaw).T @ (d.qpos[qa:qa + 3] - p)
                rel_q = _quat_mul(yaw_quat(-yaw), d.qpos[qa + 3:qa + 7])
                self._rel[i] = (rel_p, rel_q)
            rel_p, rel_q = self._rel[i]
            d.qpos[qa:qa + 3] = p + _rot_z(yaw) @ rel_p
            d.qpos[qa + 3:qa + 7] = _quat_mul(yaw_quat(yaw), rel_q)
            d.qvel[va:va + 6] = 0.0
        for i, k in enumerate(self._script.kicks):
            if i not in self._kicked and t >= k.t:
                qa, va = self._free_adr[k.body]
                v = np.asarray(k.velocity, float)
                # A free joint's angular velocity is in the body frame.
                d.qvel[va:va + 3] = v[:3]
                d.qvel[va + 3:va + 6] = _quat_to_mat(d.qpos[qa + 3:qa + 7]).T @ v[3:]
                self._kicked.add(i)
