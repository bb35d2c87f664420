"""MJCF building blocks for generated tabletop scenes: textures, objects, furniture, pushers.

Pure string building, no MuJoCo import. Every function takes a ``numpy.random.Generator``
(or explicit parameters) so a scene is determined by its seed. Lengths in metres; the table
top is the plane z = 0, the camera looks at the table from the -y side.

Naming conventions the simulator relies on (``mujoco_sim.py``):
    body ``obj*``      free rigid objects (``freejoint``), incl. glued composites
    body ``art*``      articulated parts (hinge / slide joint)
    body ``fix*``      links without joint: welded to their parent (same rigid body)
    body ``pusher``    the mocap-driven gripper or hand
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["MJCFScene", "Part", "fmt"]


def fmt(*values: float) -> str:
    """Space-separated numbers with 4 decimals (MJCF vectors)."""
    return " ".join(f"{float(v):.4f}" for v in values)


@dataclass
class Part:
    """One thing placed in the scene, with what the motion planner needs to know about it.

    Attributes:
        name: body name (or name prefix for static geoms).
        kind: ``"block"``, ``"composite"``, ``"drawer"``, ``"door"``, ``"laptop"``, ``"static"``.
        xy: (2,) centre on the table.
        radius: footprint radius (for placement and push planning).
        height: height of its lowest box above the table (push height).
        push: for articulated parts, ``(point, direction, distance)`` of a push that moves them.
    """

    name: str
    kind: str
    xy: np.ndarray
    radius: float
    height: float
    push: tuple[np.ndarray, np.ndarray, float] | None = None


@dataclass
class MJCFScene:
    """Accumulates assets and bodies; :meth:`xml` assembles the model.

    Args:
        rng: random generator for textures and colours.
        width, height: offscreen buffer size (at least the render size).
    """

    rng: np.random.Generator
    width: int = 640
    height: int = 480
    assets: list[str] = field(default_factory=list)
    world: list[str] = field(default_factory=list)
    parts: list[Part] = field(default_factory=list)
    init_qpos: dict[str, float] = field(default_factory=dict)
    _n: int = 0

    # ----- appearance -------------------------------------------------------------------
    def colour(self, lo: float = 0.1, hi: float = 0.95) -> np.ndarray:
        return self.rng.uniform(lo, hi, 3)

    def material(self, kind: str | None = None, rgb: np.ndarray | None = None,
                 repeat: float | None = None, cube: bool = True) -> str:
        """A random procedural texture (checker, gradient, noise, flat) and its material."""
        self._n += 1
        name = f"mat{self._n}"
        kinds = ("checker", "gradient", "noise", "flat", "checker")
        kind = kind or kinds[int(self.rng.integers(len(kinds)))]
        c1 = self.colour() if rgb is None else np.asarray(rgb)
        c2 = np.clip(c1 * self.rng.uniform(0.3, 0.7) + self.rng.uniform(0, 0.4, 3), 0, 1)
        ttype = "cube" if cube else "2d"
        size = 64
        if kind == "checker":
            tex = (f'<texture name="tex{self._n}" type="{ttype}" builtin="checker" '
                   f'rgb1="{fmt(*c1)}" rgb2="{fmt(*c2)}" width="{size}" height="{size}"/>')
        elif kind == "gradient":
            tex = (f'<texture name="tex{self._n}" type="{ttype}" builtin="gradient" '
                   f'rgb1="{fmt(*c1)}" rgb2="{fmt(*c2)}" width="{size}" height="{size}"/>')
        else:  # noise: random marks on a flat colour; "flat": a few marks only
            frac = self.rng.uniform(0.2, 0.5) if kind == "noise" else 0.03
            mark = np.clip(c1 + self.rng.uniform(-0.4, 0.4, 3), 0, 1)
            tex = (f'<texture name="tex{self._n}" type="{ttype}" builtin="flat" '
                   f'rgb1="{fmt(*c1)}" rgb2="{fmt(*c2)}" mark="random" random="{frac:.3f}" '
                   f'markrgb="{fmt(*mark)}" width="{size}" height="{size}"/>')
        rep = repeat if repeat is not None else float(self.rng.uniform(1, 4))
        spec = self.rng.uniform(0.05, 0.5)
        self.assets.append(tex)
        self.assets.append(
            f'<material name="{name}" texture="tex{self._n}" texrepeat="{rep:.2f} {rep:.2f}" '
            f'texuniform="true" specular="{spec:.2f}" shininess="{self.rng.uniform(0.1, 0.6):.2f}"/>'
        )
        return name

    # ----- environment ------------------------------------------------------------------
    def table(self, half: tuple[float, float] = (0.45, 0.35)) -> None:
        """Static textured table (top at z = 0), floor and a back wall."""
        tmat = self.material(cube=False, repeat=float(self.rng.uniform(2, 8)))
        fmat = self.material(cube=False, repeat=float(self.rng.uniform(4, 12)))
        wmat = self.material(cube=False, repeat=float(self.rng.uniform(2, 8)))
        hx, hy = half
        self.world += [
            f'<geom name="floor" type="plane" pos="0 0 -0.75" size="3 3 0.1" material="{fmat}"/>',
            f'<geom name="wall" type="plane" pos="0 1.2 0" zaxis="0 -1 0" size="3 2 0.1" '
            f'material="{wmat}"/>',
            f'<geom name="table" type="box" pos="0 0 -0.02" size="{fmt(hx, hy, 0.02)}" '
            f'material="{tmat}"/>',
        ]
        for sx in (-1, 1):
            for sy in (-1, 1):
                self.world.append(
                    f'<geom name="leg{sx}{sy}" type="box" pos="{fmt(sx * (hx - 0.04), sy * (hy - 0.04), -0.39)}" '
                    f'size="0.02 0.02 0.37" rgba="{fmt(*self.colour(0.1, 0.5))} 1"/>'
                )

    def lights(self, n: int) -> None:
        for i in range(n):
            pos = np.array([self.rng.uniform(-1, 1), self.rng.uniform(-1.2, 0.6), self.rng.uniform(1.2, 2.5)])
            d = self.rng.uniform(0.35, 0.75)
            self.world.append(
                f'<light name="light{i}" pos="{fmt(*pos)}" dir="{fmt(*(-pos / np.linalg.norm(pos)))}" '
                f'diffuse="{fmt(d, d, d * self.rng.uniform(0.85, 1.0))}" castshadow="{"true" if i == 0 else "false"}"/>'
            )

    # ----- things on the table ----------------------------------------------------------
    def static_object(self, xy: np.ndarray) -> Part:
        """A distractor fixed to the world (box or cylinder): never moves."""
        self._n += 1
        name = f"static{self._n}"
        mat = self.material()
        h = self.rng.uniform(0.03, 0.09)
        if self.rng.random() < 0.5:
            s = self.rng.uniform(0.025, 0.05, 2)
            geom = f'type="box" size="{fmt(s[0], s[1], h)}"'
            r = float(np.hypot(*s))
        else:
            r = float(self.rng.uniform(0.025, 0.045))
            geom = f'type="cylinder" size="{fmt(r, h)}"'
        self.world.append(f'<geom name="{name}" {geom} pos="{fmt(xy[0], xy[1], h)}" material="{mat}"/>')
        part = Part(name, "static", np.asarray(xy, float), r, 2 * h)
        self.parts.append(part)
        return part

    def free_block(self, xy: np.ndarray) -> Part:
        """A textured free box or cylinder."""
        self._n += 1
        name = f"obj{self._n}"
        mat = self.material()
        yaw = self.rng.uniform(0, np.pi)
        if self.rng.random() < 0.7:
            s = np.array([self.rng.uniform(0.02, 0.045), self.rng.uniform(0.02, 0.045),
                          self.rng.uniform(0.015, 0.04)])
            geom = f'<geom type="box" size="{fmt(*s)}" material="{mat}" density="400"/>'
            r, h = float(np.hypot(s[0], s[1])), float(2 * s[2])
        else:
            rad, hh = self.rng.uniform(0.02, 0.035), self.rng.uniform(0.02, 0.04)
            geom = f'<geom type="cylinder" size="{fmt(rad, hh)}" material="{mat}" density="400"/>'
            r, h = float(rad), float(2 * hh)
        self.world.append(
            f'<body name="{name}" pos="{fmt(xy[0], xy[1], h / 2 + 0.001)}" euler="0 0 {yaw:.4f}">'
            f'<freejoint/>{geom}</body>'
        )
        part = Part(name, "block", np.asarray(xy, float), r, h)
        self.parts.append(part)
        return part

    def composite(self, xy: np.ndarray) -> Part:
        """A glued composite: one free body made of 2-3 differently coloured geoms.

        Shapes: an L of two boxes, a tower of two or three blocks, a mug (cylinder + handle),
        a hammer-like box with a bar. One of them carries a jointless child body (``fix``):
        a fixed link that must merge into its parent.
        """
        self._n += 1
        name = f"obj{self._n}"
        mats = [self.material() for _ in range(3)]
        yaw = self.rng.uniform(0, np.pi)
        shape = ("L", "tower", "mug", "bar")[int(self.rng.integers(4))]
        a = self.rng.uniform(0.02, 0.035)
        if shape == "L":
            b = self.rng.uniform(0.015, 0.025)
            geoms = (f'<geom type="box" size="{fmt(a, b, b)}" material="{mats[0]}" density="400"/>'
                     f'<geom type="box" pos="{fmt(a - b, a + b, 0)}" size="{fmt(b, a, b)}" material="{mats[1]}" density="400"/>')
            r, h, z0 = float(np.hypot(a, 2 * a)), float(2 * b), float(b)
        elif shape == "tower":
            n = 2 + int(self.rng.random() < 0.5)
            hs = [self.rng.uniform(0.012, 0.022) for _ in range(n)]
            z, gs = 0.0, []
            for i, hh in enumerate(hs):
                s = a * (1.0 - 0.15 * i)
                gs.append(f'<geom type="box" pos="0 0 {z + hh:.4f}" size="{fmt(s, s, hh)}" material="{mats[i]}" density="400"/>')
                z += 2 * hh
            geoms = "".join(gs)
            r, h, z0 = float(a * 1.42), float(2 * hs[0]), 0.0
        elif shape == "mug":
            hh = self.rng.uniform(0.025, 0.04)
            geoms = (f'<geom type="cylinder" size="{fmt(a, hh)}" material="{mats[0]}" density="400"/>'
                     f'<body name="fix{self._n}" pos="{fmt(a + 0.008, 0, 0)}">'
                     f'<geom type="box" size="{fmt(0.008, 0.005, hh * 0.6)}" material="{mats[1]}" density="400"/></body>')
            r, h, z0 = float(a + 0.016), float(2 * hh), float(hh)
        else:  # bar
            b = self.rng.uniform(0.012, 0.018)
            L = self.rng.uniform(0.05, 0.08)
            geoms = (f'<geom type="box" size="{fmt(a, a, b * 1.5)}" material="{mats[0]}" density="400"/>'
                     f'<geom type="capsule" fromto="{fmt(a, 0, 0, a + L, 0, 0)}" size="{b * 0.8:.4f}" material="{mats[1]}" density="300"/>'
                     f'<geom type="box" pos="{fmt(a + L, 0, 0)}" size="{fmt(b, b * 1.6, b * 1.2)}" material="{mats[2]}" density="400"/>')
            r, h, z0 = float(a + L / 2 + 0.02), float(3 * b), float(b * 1.6)
        self.world.append(
            f'<body name="{name}" pos="{fmt(xy[0], xy[1], z0 + 0.002)}" euler="0 0 {yaw:.4f}">'
            f'<freejoint/>{geoms}</body>'
        )
        part = Part(name, "composite", np.asarray(xy, float), r, h)
        self.parts.append(part)
        return part

    # ----- articulated furniture (bodies without joint are welded to their parent) -------
    def drawer(self, xy: np.ndarray) -> Part:
        """A static cabinet with a drawer (slide joint) left open; the drawer has a jointless
        handle link. Push: close the drawer (+y)."""
        self._n += 1
        n = self._n
        cmat, dmat, hmat = self.material(), self.material(), self.material()
        w, d, hh = self.rng.uniform(0.07, 0.1), 0.08, self.rng.uniform(0.05, 0.07)
        q0 = self.rng.uniform(0.05, 0.09)
        x, y = xy
        t = 0.006
        dd = d - 2 * t
        self.world.append(
            f'<body name="fixcab{n}" pos="{fmt(x, y, 0)}">'
            f'<geom type="box" pos="{fmt(0, 0, 2 * hh + t)}" size="{fmt(w + t, d, t)}" material="{cmat}"/>'
            f'<geom type="box" pos="{fmt(-w - t, 0, hh + t)}" size="{fmt(t, d, hh + t)}" material="{cmat}"/>'
            f'<geom type="box" pos="{fmt(w + t, 0, hh + t)}" size="{fmt(t, d, hh + t)}" material="{cmat}"/>'
            f'<geom type="box" pos="{fmt(0, d, hh + t)}" size="{fmt(w, t, hh + t)}" material="{cmat}"/>'
            f'<body name="art{n}" pos="{fmt(0, 0, hh + 0.002)}">'
            f'<joint name="slide{n}" type="slide" axis="0 1 0" range="{-d * 1.2:.4f} 0.002" '
            f'damping="3" frictionloss="0.3" armature="0.05"/>'
            f'<geom type="box" pos="0 0 {-hh + t:.4f}" size="{fmt(w - t - 0.003, dd, t)}" material="{dmat}"/>'
            f'<geom type="box" pos="{fmt(0, -d - t, 0)}" size="{fmt(w + t, t, hh - 0.003)}" material="{dmat}"/>'
            f'<geom type="box" pos="{fmt(-w + 2 * t + 0.003, 0, 0)}" size="{fmt(t, dd, hh * 0.7)}" material="{dmat}"/>'
            f'<geom type="box" pos="{fmt(w - 2 * t - 0.003, 0, 0)}" size="{fmt(t, dd, hh * 0.7)}" material="{dmat}"/>'
            f'<geom type="box" pos="{fmt(0, dd - t, 0)}" size="{fmt(w - t - 0.003, t, hh * 0.7)}" material="{dmat}"/>'
            f'<body name="fixhandle{n}" pos="{fmt(0, -d - 2 * t - 0.008, 0)}">'
            f'<geom type="box" size="{fmt(w * 0.5, 0.006, 0.008)}" material="{hmat}"/></body>'
            f'</body></body>'
        )
        self.init_qpos[f"slide{n}"] = -q0
        front = np.array([x, y - d - 2 * t - q0 - 0.014, hh + 0.002])  # handle face
        part = Part(f"art{n}", "drawer", np.asarray(xy, float), float(np.hypot(w, d + 0.1)),
                    float(2 * hh), push=(front, np.array([0.0, 1.0, 0.0]), q0 - 0.005))
        self.parts.append(part)
        return part

    def door_cabinet(self, xy: np.ndarray) -> Part:
        """A static cabinet whose door (hinge about z at its left edge) stands ajar.
        Push: on the door's outer face, towards closing."""
        self._n += 1
        n = self._n
        cmat, dmat, kmat = self.material(), self.material(), self.material()
        w, d, hh = self.rng.uniform(0.07, 0.1), 0.07, self.rng.uniform(0.07, 0.1)
        theta0 = self.rng.uniform(np.radians(35), np.radians(65))
        x, y = xy
        t = 0.006
        hinge = np.array([x - w, y - d - t])
        self.world.append(
            f'<body name="fixcab{n}" pos="{fmt(x, y, 0)}">'
            f'<geom type="box" pos="{fmt(0, 0, 2 * hh + t)}" size="{fmt(w + t, d, t)}" material="{cmat}"/>'
            f'<geom type="box" pos="{fmt(-w, 0, hh)}" size="{fmt(t, d, hh)}" material="{cmat}"/>'
            f'<geom type="box" pos="{fmt(w, 0, hh)}" size="{fmt(t, d, hh)}" material="{cmat}"/>'
            f'<geom type="box" pos="{fmt(0, d, hh)}" size="{fmt(w, t, hh)}" material="{cmat}"/></body>'
            f'<body name="art{n}" pos="{fmt(hinge[0], hinge[1], hh + 0.003)}">'
            f'<joint name="hinge{n}" type="hinge" axis="0 0 1" range="-1.6 0.05" damping="0.3" '
            f'frictionloss="0.03" armature="0.01"/>'
            f'<geom type="box" pos="{fmt(w, -t, 0)}" size="{fmt(w, t * 0.8, hh - 0.004)}" material="{dmat}"/>'
            f'<body name="fixknob{n}" pos="{fmt(1.7 * w, -3 * t, 0)}">'
            f'<geom type="capsule" fromto="0 0 -0.015 0 0 0.015" size="0.005" material="{kmat}"/></body>'
            f'</body>'
        )
        self.init_qpos[f"hinge{n}"] = -theta0  # negative: free edge swings towards -y (front)
        # Door direction at angle -theta0: (cos, -sin); outer-face normal points (-sin, -cos).
        u = np.array([np.cos(theta0), -np.sin(theta0)])
        normal_out = np.array([-np.sin(theta0), -np.cos(theta0)])
        p = hinge + 1.5 * w * u + normal_out * 1.8 * t  # on the door's outer face
        point = np.array([p[0], p[1], hh + 0.003])
        direction = np.array([-normal_out[0], -normal_out[1], 0.0])
        dist = 1.5 * w * (theta0 - np.radians(8))
        part = Part(f"art{n}", "door", np.asarray(xy, float), float(np.hypot(w, d) + 2 * w),
                    float(2 * hh), push=(point, direction, float(dist)))
        self.parts.append(part)
        return part

    def laptop(self, xy: np.ndarray) -> Part:
        """A laptop: static base (jointless link) and a lid on a hinge along x at the back
        edge, partly open. Push: on the screen, towards opening (+y)."""
        self._n += 1
        n = self._n
        bmat, lmat, smat = self.material(), self.material(), self.material(kind="gradient")
        w, d, t = self.rng.uniform(0.08, 0.11), self.rng.uniform(0.06, 0.075), 0.007
        phi0 = self.rng.uniform(np.radians(55), np.radians(80))
        x, y = xy
        self.world.append(
            f'<body name="fixbase{n}" pos="{fmt(x, y, t)}">'
            f'<geom type="box" size="{fmt(w, d, t)}" material="{bmat}"/>'
            f'<body name="art{n}" pos="{fmt(0, d, t)}">'
            f'<joint name="lid{n}" type="hinge" axis="1 0 0" range="-2.2 0.05" damping="0.05" '
            f'frictionloss="0.3" armature="0.005"/>'
            f'<geom type="box" pos="{fmt(0, -d, 0.004)}" size="{fmt(w, d, 0.004)}" material="{lmat}"/>'
            f'<geom type="box" pos="{fmt(0, -d, -0.0007)}" size="{fmt(w * 0.9, d * 0.88, 0.0006)}" material="{smat}"/>'
            f'</body></body>'
        )
        self.init_qpos[f"lid{n}"] = -phi0  # negative: the lid rotates up from closed
        # Lid point at 75% of its length, on the screen side.
        s = 0.92 * 2 * d
        hinge = np.array([x, y + d, 2 * t])
        # On the screen face (the lid's -z side, facing forward and down when open), near the
        # top edge: the lid leans towards the pusher, so a lower contact would let the
        # pusher's fingers hit the lid above it before the clip starts.
        point = hinge + np.array([0, -s * np.cos(phi0), s * np.sin(phi0)])
        point += 0.0015 * np.array([0, -np.sin(phi0), -np.cos(phi0)])
        part = Part(f"art{n}", "laptop", np.asarray(xy, float), float(np.hypot(w, d)),
                    float(2 * t), push=(point, np.array([0.0, 1.0, 0.0]), float(self.rng.uniform(0.04, 0.07))))
        self.parts.append(part)
        return part

    # ----- pushers ---------------------------------------------------------------------
    def gripper(self) -> None:
        """A parallel-jaw gripper on a forearm, mocap-driven (one rigid body: the fingers are
        jointless links). Its origin is the fingertip centre."""
        m1, m2 = self.material(rgb=self.colour(0.1, 0.4)), self.material(rgb=self.colour(0.5, 0.9))
        self.world.append(
            '<body name="pusher" mocap="true" pos="0 -0.6 0.3">'
            f'<geom type="box" pos="0 0 0.075" size="0.045 0.02 0.012" material="{m1}" friction="0.4"/>'
            f'<geom type="cylinder" pos="0 0 0.1" size="0.02 0.02" material="{m2}"/>'
            f'<geom type="capsule" fromto="0 0 0.12 0 -0.07 0.5" size="0.022" material="{m1}"/>'
            f'<body name="fixfingerL" pos="-0.032 0 0.032"><geom type="box" size="0.008 0.015 0.032" material="{m2}" friction="0.4"/></body>'
            f'<body name="fixfingerR" pos="0.032 0 0.032"><geom type="box" size="0.008 0.015 0.032" material="{m2}" friction="0.4"/></body>'
            '</body>'
        )

    def hand(self) -> None:
        """A rigid hand-like pusher: palm, four fingers pointing down, thumb, forearm."""
        skin = np.array([0.85, 0.65, 0.5]) * self.rng.uniform(0.6, 1.1) + self.rng.uniform(-0.05, 0.05, 3)
        skin = np.clip(skin, 0, 1)
        mat = self.material(kind="flat", rgb=skin)
        sleeve = self.material()
        fingers = "".join(
            f'<geom type="capsule" fromto="{fmt(x, 0, 0.075, x, 0, 0.012)}" size="0.0085" material="{mat}" friction="0.4"/>'
            for x in (-0.027, -0.009, 0.009, 0.027)
        )
        self.world.append(
            '<body name="pusher" mocap="true" pos="0 -0.6 0.3">'
            f'<geom type="box" pos="0 0 0.11" size="0.042 0.014 0.04" material="{mat}"/>'
            f'{fingers}'
            f'<geom type="capsule" fromto="0.045 0 0.12 0.06 -0.01 0.06" size="0.01" material="{mat}"/>'
            f'<geom type="capsule" fromto="0 0 0.15 0 -0.07 0.5" size="0.026" material="{sleeve}"/>'
            '</body>'
        )

    # ----- assembly ---------------------------------------------------------------------
    def xml(self, timestep: float = 0.002) -> str:
        amb = self.rng.uniform(0.15, 0.35)
        return (
            '<mujoco model="motionbits_scene">'
            '<compiler angle="radian"/>'  # joint ranges and euler angles are in radians
            f'<option timestep="{timestep}" gravity="0 0 -9.81"/>'
            f'<visual><global offwidth="{self.width}" offheight="{self.height}"/>'
            f'<quality shadowsize="1024"/>'
            f'<headlight ambient="{fmt(amb, amb, amb)}" diffuse="0.25 0.25 0.25" specular="0.05 0.05 0.05"/></visual>'
            f'<asset>{"".join(self.assets)}</asset>'
            f'<worldbody>{"".join(self.world)}</worldbody>'
            '</mujoco>'
        )
