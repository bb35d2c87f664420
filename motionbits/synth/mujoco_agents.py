"""MJCF for the harder tracks: natural textures, articulated agents, rolling objects.

:class:`NaturalScene` extends :class:`~motionbits.synth.mujoco_mjcf.MJCFScene` (the robot
and hand tracks' builder, left unchanged) with

* procedural wood / marble / fabric / granite textures (PNG assets, see
  :mod:`motionbits.synth.textures`) on the table, wall, floor and half the objects;
* agents, all mocap bodies named ``agent<i>`` whose whole subtree is the agent (its pixels
  are ignored in the ground truth): an articulated hand (four two-link fingers and a thumb
  on position-controlled hinges), a parallel gripper (two position-controlled slide
  fingers) and a rigid pusher (flat hand); agent geoms collide with objects, not with each
  other;
* balls that roll (small rolling friction), for kicked objects;
* every light casting shadows, a 4096 shadow map (1024 for renders under 320 px).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from motionbits.synth.mujoco_mjcf import MJCFScene, Part, fmt
from motionbits.synth.textures import NATURAL_KINDS, natural_texture, png_bytes

__all__ = ["NaturalScene", "AgentSpec", "AGENT_PREFIX"]

AGENT_PREFIX = "agent"
_AGENT_GEOM = 'contype="2" conaffinity="1"'  # hits objects (contype 1), not other agents


@dataclass(frozen=True)
class AgentSpec:
    """What a choreography needs to know about a built agent.

    Attributes:
        name: mocap body name.
        kind: ``"hand"``, ``"gripper"`` or ``"pusher"``.
        actuators: ``(name, ctrl open, ctrl closed)`` of the finger actuators.
        bodies: names of all bodies of the agent (for contact exclusions).
        reach: height of the palm's underside above the agent's origin (the fingertips).
    """

    name: str
    kind: str
    actuators: tuple[tuple[str, float, float], ...]
    bodies: tuple[str, ...]
    reach: float


@dataclass
class NaturalScene(MJCFScene):
    """Scene builder with natural textures and articulated agents (see module doc)."""

    files: dict[str, bytes] = field(default_factory=dict)
    actuators: list[str] = field(default_factory=list)
    excludes: list[tuple[str, str]] = field(default_factory=list)
    p_natural: float = 0.5
    _agents: int = 0

    # ----- appearance -------------------------------------------------------------------
    def natural_material(self, kind: str | None = None, repeat: float = 1.0,
                         cube: bool = True, size: int = 256) -> str:
        """A material on a procedural natural texture (random kind unless given)."""
        self._n += 1
        n = self._n
        kind = kind or NATURAL_KINDS[int(self.rng.integers(len(NATURAL_KINDS)))]
        fname = f"tex{n}_{kind}.png"
        self.files[fname] = png_bytes(natural_texture(kind, self.rng, size))
        ttype = "cube" if cube else "2d"
        self.assets.append(f'<texture name="tex{n}" type="{ttype}" file="{fname}"/>')
        spec = self.rng.uniform(0.05, 0.4)
        self.assets.append(
            f'<material name="mat{n}" texture="tex{n}" texrepeat="{repeat:.2f} {repeat:.2f}" '
            f'texuniform="{"false" if cube else "true"}" specular="{spec:.2f}" '
            f'shininess="{self.rng.uniform(0.1, 0.5):.2f}"/>'
        )
        return f"mat{n}"

    def material(self, kind: str | None = None, rgb: np.ndarray | None = None,
                 repeat: float | None = None, cube: bool = True) -> str:
        """Like the base class, but a natural texture with probability ``p_natural`` when
        neither a kind nor a colour is asked for."""
        if kind is None and rgb is None and self.rng.random() < self.p_natural:
            return self.natural_material(cube=cube)
        return super().material(kind, rgb, repeat, cube)

    # ----- environment ------------------------------------------------------------------
    def table(self, half: tuple[float, float] = (0.55, 0.4)) -> None:
        """Table (wood, marble, fabric or granite top), floor and wall, all natural."""
        hx, hy = half
        top = self.natural_material(cube=False, repeat=float(self.rng.uniform(1.2, 2.5)), size=512)
        floor = self.natural_material("wood", cube=False, repeat=float(self.rng.uniform(0.4, 1.0)),
                                      size=512)
        wall = self.natural_material(("fabric", "marble", "granite")[int(self.rng.integers(3))],
                                     cube=False, repeat=float(self.rng.uniform(0.5, 1.5)), size=512)
        legs = self.natural_material("wood")
        self.world += [
            f'<geom name="floor" type="plane" pos="0 0 -0.75" size="4 4 0.1" material="{floor}"/>',
            f'<geom name="wall" type="plane" pos="0 1.4 0" zaxis="0 -1 0" size="4 3 0.1" '
            f'material="{wall}"/>',
            f'<geom name="table" type="box" pos="0 0 -0.02" size="{fmt(hx, hy, 0.02)}" material="{top}"/>',
        ]
        for sx in (-1, 1):
            for sy in (-1, 1):
                self.world.append(
                    f'<geom name="leg{sx}{sy}" type="box" '
                    f'pos="{fmt(sx * (hx - 0.04), sy * (hy - 0.04), -0.39)}" size="0.025 0.025 0.37" '
                    f'material="{legs}"/>')

    def lights(self, n: int) -> None:
        """``n`` lights from above, all casting shadows, one strong key light."""
        for i in range(n):
            pos = np.array([self.rng.uniform(-1.2, 1.2), self.rng.uniform(-1.2, 0.8),
                            self.rng.uniform(1.0, 2.2)])
            d = self.rng.uniform(0.55, 0.85) if i == 0 else self.rng.uniform(0.2, 0.4)
            self.world.append(
                f'<light name="light{i}" pos="{fmt(*pos)}" dir="{fmt(*(-pos / np.linalg.norm(pos)))}" '
                f'diffuse="{fmt(d, d, d * self.rng.uniform(0.85, 1.0))}" castshadow="true"/>')

    # ----- objects ----------------------------------------------------------------------
    def ball(self, xy: np.ndarray) -> Part:
        """A free ball that rolls (rolling friction ~0.002-0.004 m)."""
        self._n += 1
        name = f"obj{self._n}"
        mat = self.material()
        r = float(self.rng.uniform(0.022, 0.035))
        roll = self.rng.uniform(0.002, 0.004)
        self.world.append(
            f'<body name="{name}" pos="{fmt(xy[0], xy[1], r + 0.001)}"><freejoint/>'
            f'<geom type="sphere" size="{r:.4f}" material="{mat}" density="300" condim="6" '
            f'friction="0.8 0.005 {roll:.4f}"/></body>')
        part = Part(name, "ball", np.asarray(xy, float), r, 2 * r)
        self.parts.append(part)
        return part

    # ----- agents -----------------------------------------------------------------------
    def _agent_name(self) -> str:
        name = f"{AGENT_PREFIX}{self._agents}"
        self._agents += 1
        return name

    def _skin(self) -> str:
        skin = np.array([0.85, 0.65, 0.5]) * self.rng.uniform(0.55, 1.1) + self.rng.uniform(-0.05, 0.05, 3)
        return super().material(kind="flat", rgb=np.clip(skin, 0, 1))

    def _sleeve(self) -> str:
        return self.material()

    def articulated_hand(self) -> AgentSpec:
        """A hand: palm and forearm (the mocap body), four fingers of two hinged links and
        an opposing thumb, all curling under position control. Origin: the fingertips."""
        a = self._agent_name()
        skin, sleeve = self._skin(), self._sleeve()
        g = _AGENT_GEOM
        joint = 'damping="0.02" armature="0.002" limited="true"'
        bodies, acts, xml = [a], [], []
        palm_z = 0.058
        for i, x in enumerate((-0.027, -0.009, 0.009, 0.027)):
            l1, l2 = 0.028 + 0.004 * (0 < i < 3), 0.024
            n1, n2 = f"{a}_f{i}a", f"{a}_f{i}b"
            bodies += [n1, n2]
            xml.append(
                f'<body name="{n1}" pos="{fmt(x, 0.012, palm_z)}">'
                f'<joint name="{n1}" type="hinge" axis="-1 0 0" range="-0.5 1.3" {joint}/>'
                f'<geom type="capsule" fromto="{fmt(0, 0, 0, 0, 0, -l1)}" size="0.0085" material="{skin}" {g}/>'
                f'<body name="{n2}" pos="{fmt(0, 0, -l1)}">'
                f'<joint name="{n2}" type="hinge" axis="-1 0 0" range="0 1.4" {joint}/>'
                f'<geom type="capsule" fromto="{fmt(0, 0, 0, 0, 0, -l2)}" size="0.008" material="{skin}" {g}/>'
                f'</body></body>')
            acts += [(n1, -0.35, 0.55), (n2, 0.05, 0.6)]
        t1 = f"{a}_thumb"
        bodies.append(t1)
        xml.append(
            f'<body name="{t1}" pos="{fmt(0.03, -0.02, palm_z + 0.01)}">'
            f'<joint name="{t1}" type="hinge" axis="1 0 0" range="-0.6 1.3" {joint}/>'
            f'<geom type="capsule" fromto="{fmt(0, 0, 0, 0, -0.01, -0.05)}" size="0.0095" material="{skin}" {g}/>'
            f'</body>')
        acts.append((t1, -0.45, 0.5))
        self.world.append(
            f'<body name="{a}" mocap="true" pos="0 -0.8 0.4">'
            f'<geom type="box" pos="{fmt(0, 0, palm_z + 0.04)}" size="0.042 0.016 0.04" material="{skin}" {g}/>'
            f'<geom type="capsule" fromto="{fmt(0, 0, palm_z + 0.08, 0, -0.08, 0.5)}" size="0.027" '
            f'material="{sleeve}" {g}/>'
            f'{"".join(xml)}</body>')
        spec = []
        for jn, lo, hi in acts:
            self.actuators.append(f'<position name="{jn}" joint="{jn}" kp="0.6" ctrlrange="-1 1.5"/>')
            spec.append((jn, lo, hi))
        return AgentSpec(a, "hand", tuple(spec), tuple(bodies), palm_z)

    def parallel_gripper(self, closed_gap: float = 0.02) -> AgentSpec:
        """A parallel-jaw gripper on a forearm; two slide fingers under position control
        (open: 5 cm from the centre; closed: ``closed_gap`` + finger half width)."""
        a = self._agent_name()
        m1, m2 = (super().material(rgb=self.colour(0.1, 0.4)),
                  super().material(rgb=self.colour(0.5, 0.9)))
        g = _AGENT_GEOM
        bodies, acts, fingers = [a], [], []
        for side, sgn in (("L", -1), ("R", 1)):
            n = f"{a}_finger{side}"
            bodies.append(n)
            fingers.append(
                f'<body name="{n}" pos="{fmt(sgn * 0.05, 0, 0.034)}">'
                f'<joint name="{n}" type="slide" axis="{sgn * -1} 0 0" range="0 0.045" '
                f'damping="2" armature="0.02" limited="true"/>'
                f'<geom type="box" size="0.007 0.016 0.034" material="{m2}" {g}/></body>')
            acts.append((n, 0.0, float(np.clip(0.05 - closed_gap - 0.007, 0.0, 0.045))))
        self.world.append(
            f'<body name="{a}" mocap="true" pos="0 -0.8 0.4">'
            f'<geom type="box" pos="0 0 0.078" size="0.062 0.02 0.012" material="{m1}" {g}/>'
            f'<geom type="cylinder" pos="0 0 0.105" size="0.022 0.018" material="{m2}" {g}/>'
            f'<geom type="capsule" fromto="0 0 0.12 0 -0.08 0.5" size="0.024" material="{m1}" {g}/>'
            f'{"".join(fingers)}</body>')
        for jn, _, _ in acts:
            self.actuators.append(f'<position name="{jn}" joint="{jn}" kp="300" ctrlrange="0 0.045"/>')
        return AgentSpec(a, "gripper", tuple(acts), tuple(bodies), 0.066)

    def rigid_pusher(self) -> AgentSpec:
        """A flat rigid hand (palm, four stiff fingers, forearm) for sweeps."""
        a = self._agent_name()
        skin, sleeve = self._skin(), self._sleeve()
        g = _AGENT_GEOM
        fingers = "".join(
            f'<geom type="capsule" fromto="{fmt(x, 0, 0.075, x, 0, 0.012)}" size="0.0085" '
            f'material="{skin}" {g}/>' for x in (-0.027, -0.009, 0.009, 0.027))
        self.world.append(
            f'<body name="{a}" mocap="true" pos="0 -0.8 0.4">'
            f'<geom type="box" pos="0 0 0.11" size="0.042 0.014 0.04" material="{skin}" {g}/>{fingers}'
            f'<geom type="capsule" fromto="0.045 0 0.12 0.06 -0.01 0.06" size="0.01" material="{skin}" {g}/>'
            f'<geom type="capsule" fromto="0 0 0.15 0 -0.08 0.5" size="0.026" material="{sleeve}" {g}/>'
            '</body>')
        return AgentSpec(a, "pusher", (), (a,), 0.075)

    def exclude_contacts(self, agent: AgentSpec, body: str) -> None:
        """No contacts between any part of ``agent`` and ``body`` (a carried object)."""
        self.excludes += [(b, body) for b in agent.bodies]

    # ----- assembly ---------------------------------------------------------------------
    def xml(self, timestep: float = 0.002) -> str:
        amb = self.rng.uniform(0.08, 0.2)
        excl = "".join(f'<exclude body1="{a}" body2="{b}"/>' for a, b in self.excludes)
        return (
            '<mujoco model="motionbits_scene">'
            '<compiler angle="radian"/>'
            f'<option timestep="{timestep}" gravity="0 0 -9.81" integrator="implicitfast"/>'
            f'<visual><global offwidth="{self.width}" offheight="{self.height}"/>'
            f'<quality shadowsize="{4096 if max(self.width, self.height) >= 320 else 1024}"/>'
            f'<headlight ambient="{fmt(amb, amb, amb)}" diffuse="0.15 0.15 0.15" specular="0.03 0.03 0.03"/>'
            '</visual>'
            f'<asset>{"".join(self.assets)}</asset>'
            f'<worldbody>{"".join(self.world)}</worldbody>'
            f'<contact>{excl}</contact>'
            f'<actuator>{"".join(self.actuators)}</actuator>'
            '</mujoco>'
        )
