"""The tower-stacking scene of Supplement B as an MJCF model (pure string building).

Five glued composite objects -- each two to four boxes of one height, every box its own
colour and texture, glued edge to edge into one free body (a polyomino) -- compactly
arranged on a plain table; a fixed RGB-D camera 75 cm above the table, tilted 60 degrees
from vertical (Supplement B); a parallel gripper (a free body pulled by a weld constraint to a mocap target) whose two fingers are slide
joints driven by position actuators with a force limit: a grasp holds by contact
friction only, nothing is welded to the hand.

Lengths in metres, the table top is z = 0. Body names: ``obj0`` ... ``obj4`` (the
composites), ``hand`` (the gripper), fingers ``finger_l`` / ``finger_r``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from motionbits.synth.mujoco_mjcf import MJCFScene, fmt

__all__ = ["CAMERA", "N_OBJECTS", "SHAPES", "CameraSpec", "StackScene", "build_scene"]

N_OBJECTS = 5
#: Polyominoes (cell coordinates) the composites are drawn from.
SHAPES = {
    "domino": ((0, 0), (1, 0)),
    "I3": ((0, 0), (1, 0), (2, 0)),
    "L3": ((0, 0), (1, 0), (0, 1)),
    "T4": ((0, 0), (1, 0), (2, 0), (1, 1)),
    "L4": ((0, 0), (1, 0), (2, 0), (0, 1)),
    "S4": ((0, 0), (1, 0), (1, 1), (2, 1)),
    "O4": ((0, 0), (1, 0), (0, 1), (1, 1)),
}
FINGER_MAX = 0.075  # m: travel of each finger (max opening 15 cm)
FINGER_LEN = 0.06  # m: finger length below the palm
TABLE_HALF = (0.5, 0.4)
TOWER_XY = (0.17, 0.03)  # where the tower is built (a free spot right of the objects)
CLUSTER_XY = (-0.1, 0.0)  # centre of the objects' arrangement


@dataclass(frozen=True)
class CameraSpec:
    """A fixed pinhole camera: ``height`` m above the table, optical axis ``tilt_deg`` from
    vertical, looking at ``lookat`` (on the table), vertical field of view ``fovy_deg``."""

    lookat: tuple[float, float, float] = (0.02, 0.0, 0.0)
    height: float = 0.75  # Supplement B: ~75 cm above the tabletop
    tilt_deg: float = 60.0  # Supplement B: 60 degrees from the vertical axis
    fovy_deg: float = 22.0  # ours: frames the 60 cm x 40 cm work area at 640x480

    def pose(self) -> tuple[np.ndarray, np.ndarray]:
        """``(position (3,), xyaxes (6,))`` in MuJoCo's convention (camera looks along -z)."""
        t = math.radians(self.tilt_deg)
        pos = np.array(self.lookat) + np.array([0.0, -self.height * math.tan(t), self.height])
        x = np.array([1.0, 0.0, 0.0])
        y = np.array([0.0, math.cos(t), math.sin(t)])  # camera up
        return pos, np.concatenate([x, y])


CAMERA = CameraSpec()


@dataclass(frozen=True)
class StackScene:
    """One drawn scene.

    Attributes:
        xml: the MJCF model.
        objects: body names of the composites.
        shapes: polyomino name of each composite.
        cell: edge of a composite's cells in metres.
        heights: height of each composite.
        tower_xy: where the tower goes.
        camera: the camera.
        width, height: render size.
    """

    xml: str
    objects: tuple[str, ...]
    shapes: tuple[str, ...]
    cell: tuple[float, ...]
    heights: tuple[float, ...]
    tower_xy: tuple[float, float]
    camera: CameraSpec
    width: int
    height: int


def _composite(s: MJCFScene, name: str, cells: tuple[tuple[int, int], ...], cell: float,
               h: float, xy: np.ndarray, yaw: float, rng: np.random.Generator) -> str:
    """A free body made of one box per cell, each with its own colour, centred on its
    centroid (= centre of mass: equal boxes)."""
    c = np.asarray(cells, float)
    c -= c.mean(axis=0)
    hues = rng.permutation(8)[: len(cells)]
    geoms = []
    for (cx, cy), hue in zip(c, hues):
        rgb = _palette(int(hue), rng)
        mat = s.material(kind=("noise", "flat", "gradient")[int(rng.integers(3))], rgb=rgb,
                         repeat=1.0)
        geoms.append(f'<geom type="box" pos="{fmt(cx * cell, cy * cell, 0)}" '
                     f'size="{fmt(cell / 2 - 1e-4, cell / 2 - 1e-4, h / 2)}" material="{mat}" '
                     f'density="300" friction="1.0 0.02 0.0005" condim="4"/>')
    return (f'<body name="{name}" pos="{fmt(xy[0], xy[1], h / 2 + 0.0005)}" euler="0 0 {yaw:.4f}">'
            f'<freejoint/>{"".join(geoms)}</body>')


def _palette(i: int, rng: np.random.Generator) -> np.ndarray:
    """Eight well separated saturated colours, slightly jittered."""
    base = np.array([
        [0.85, 0.15, 0.12], [0.1, 0.55, 0.2], [0.15, 0.3, 0.85], [0.95, 0.8, 0.1],
        [0.6, 0.2, 0.7], [0.95, 0.5, 0.1], [0.1, 0.7, 0.75], [0.9, 0.9, 0.88],
    ])[i]
    return np.clip(base + rng.uniform(-0.06, 0.06, 3), 0, 1)


def _arrange(rng: np.random.Generator, radii: list[float]) -> list[np.ndarray] | None:
    """Compact, non-overlapping footprint centres (discs of ``radii``) around the cluster
    centre: each new object sits 1-3 cm (between bounding discs) from one already placed."""
    centre = np.array(CLUSTER_XY)
    placed: list[tuple[np.ndarray, float]] = []
    for r in radii:
        for _ in range(400):
            if not placed:
                xy = centre + rng.uniform(-0.02, 0.02, 2)
            else:
                anchor, ra = placed[int(rng.integers(len(placed)))]
                ang = rng.uniform(0, 2 * np.pi)
                xy = anchor + (ra + r + rng.uniform(0.01, 0.03)) * np.array([np.cos(ang), np.sin(ang)])
            if abs(xy[0] - centre[0]) > 0.16 or abs(xy[1] - centre[1]) > 0.12:
                continue
            if all(np.linalg.norm(xy - p) >= r + rp + 0.005 for p, rp in placed):
                placed.append((xy, r))
                break
        else:
            return None
    return [p for p, _ in placed]


def build_scene(rng: np.random.Generator, *, width: int = 640, height: int = 480,
                camera: CameraSpec = CAMERA) -> StackScene:
    """Draw the five composites and their compact arrangement; assemble the model."""
    s = MJCFScene(rng, width=width, height=height)
    names = tuple(f"obj{i}" for i in range(N_OBJECTS))
    shape_names = list(SHAPES)
    while True:
        shapes = tuple(shape_names[int(i)] for i in rng.integers(len(shape_names), size=N_OBJECTS))
        cells = tuple(float(rng.uniform(0.03, 0.036)) for _ in names)
        heights = tuple(float(rng.uniform(0.024, 0.03)) for _ in names)
        radii = []
        for sh, cl in zip(shapes, cells):
            c = np.asarray(SHAPES[sh], float)
            c -= c.mean(axis=0)
            radii.append(float(np.max(np.linalg.norm(c, axis=1)) * cl + cl * 0.71))
        centres = _arrange(rng, radii)
        if centres is not None:
            break
    bodies = [
        _composite(s, n, SHAPES[sh], cl, h, xy, float(rng.uniform(0, np.pi)), rng)
        for n, sh, cl, h, xy in zip(names, shapes, cells, heights, centres)
    ]
    # Table and floor: one colour each with fine, faint speckle -- texture for optical flow,
    # too fine and faint to form regions of their own for a colour segmenter.
    table_rgb = np.array([0.62, 0.6, 0.57]) + rng.uniform(-0.05, 0.05, 3)
    s.assets.append(f'<texture name="tabletex" type="2d" builtin="flat" rgb1="{fmt(*table_rgb)}" '
                    f'rgb2="{fmt(*table_rgb)}" mark="random" random="0.4" '
                    f'markrgb="{fmt(*(table_rgb * 0.8))}" width="256" height="256"/>'
                    '<material name="tablemat" texture="tabletex" texrepeat="2 2" specular="0.1"/>'
                    '<texture name="floortex" type="2d" builtin="flat" rgb1="0.3 0.3 0.32" '
                    'rgb2="0.3 0.3 0.32" mark="random" random="0.4" markrgb="0.22 0.22 0.24" '
                    'width="512" height="512"/>'
                    '<material name="floormat" texture="floortex" texrepeat="4 4"/>')
    pos, xyaxes = camera.pose()
    hx, hy = TABLE_HALF
    world = [
        '<light name="key" pos="0.3 -0.6 1.6" dir="-0.2 0.35 -1" diffuse="0.6 0.6 0.6" castshadow="false"/>',
        '<light name="fill" pos="-0.6 0.4 1.4" dir="0.4 -0.2 -1" diffuse="0.3 0.3 0.3" castshadow="false"/>',
        '<geom name="floor" type="plane" pos="0 0 -0.75" size="3 3 0.1" material="floormat"/>',
        f'<geom name="table" type="box" pos="0 0 -0.02" size="{fmt(hx, hy, 0.02)}" material="tablemat" '
        'friction="0.6 0.02 0.0005"/>',
        f'<camera name="cam" pos="{fmt(*pos)}" xyaxes="{fmt(*xyaxes)}" fovy="{camera.fovy_deg:.3f}"/>',
        *bodies,
        _gripper(s),
    ]
    xml = (
        '<mujoco model="motionbits_stacking"><compiler angle="radian"/>'
        '<option timestep="0.002" gravity="0 0 -9.81" cone="elliptic" impratio="10"/>'
        f'<visual><global offwidth="{width}" offheight="{height}"/>'
        '<headlight ambient="0.35 0.35 0.35" diffuse="0.3 0.3 0.3" specular="0.05 0.05 0.05"/></visual>'
        f'<asset>{"".join(s.assets)}</asset>'
        f'<worldbody>{"".join(world)}</worldbody>'
        '<actuator>'
        f'<position name="act_l" joint="finger_l" kp="800" ctrlrange="0 {FINGER_MAX}" forcerange="-12 12"/>'
        f'<position name="act_r" joint="finger_r" kp="800" ctrlrange="0 {FINGER_MAX}" forcerange="-12 12"/>'
        '</actuator>'
        # the hand is a dynamic body pulled to the mocap target: contacts then see its true
        # velocity, so friction can lift an object (a mocap body in contact cannot)
        '<equality><weld body1="hand_target" body2="hand" solref="0.01 1"/></equality>'
        '</mujoco>'
    )
    return StackScene(xml=xml, objects=names, shapes=shapes, cell=cells, heights=heights,
                      tower_xy=TOWER_XY, camera=camera, width=width, height=height)


def _gripper(s: MJCFScene) -> str:
    """The hand (dynamic, gravity-compensated, welded to the mocap body ``hand_target``);
    its origin is the fingertips' centre. Fingers close along the hand's x."""
    dark = s.material(kind="noise", rgb=np.array([0.25, 0.25, 0.28]), repeat=3.0)
    metal = s.material(kind="gradient", rgb=np.array([0.7, 0.7, 0.72]), repeat=1.0)
    finger = (f'type="box" size="{fmt(0.006, 0.013, FINGER_LEN / 2)}" material="{metal}" '
              'friction="1.5 0.05 0.001" condim="4" density="1000" '
              'solref="0.004 1" solimp="0.95 0.99 0.001"')
    fl = FINGER_LEN
    return (
        '<body name="hand_target" mocap="true" pos="0.35 -0.3 0.45"/>'
        '<body name="hand" pos="0.35 -0.3 0.45" gravcomp="1"><freejoint name="hand"/>'
        f'<geom type="box" pos="{fmt(0, 0, fl + 0.012)}" size="{fmt(FINGER_MAX + 0.02, 0.018, 0.012)}" material="{dark}"/>'
        f'<geom type="cylinder" pos="{fmt(0, 0, fl + 0.06)}" size="0.02 0.04" material="{dark}"/>'
        '<body name="finger_l" gravcomp="1"><joint name="finger_l" type="slide" axis="-1 0 0" range="0 '
        f'{FINGER_MAX}" damping="40" armature="0.5"/><geom pos="{fmt(-0.006, 0, fl / 2)}" {finger}/></body>'
        '<body name="finger_r" gravcomp="1"><joint name="finger_r" type="slide" axis="1 0 0" range="0 '
        f'{FINGER_MAX}" damping="40" armature="0.5"/><geom pos="{fmt(0.006, 0, fl / 2)}" {finger}/></body>'
        '</body>'
    )
