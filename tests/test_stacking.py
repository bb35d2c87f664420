"""Tower stacking (paper Table 3, Supplement B): camera geometry, the per-colour baseline,
the table/JSON layout, and one short simulated trial with ground-truth masks."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from motionbits.baselines import make_method
from motionbits.cli import main
from motionbits.stacking.perception import (
    HeightMap,
    PinholeCamera,
    finger_clearance,
    world_grasp,
)
from motionbits.stacking.run import format_table, summarise
from motionbits.stacking.trial import TrialResult


def _camera(w=64, h=48, fovy=30.0):
    t = math.radians(60)
    rot = np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]], float)
    return PinholeCamera(width=w, height=h, fovy_deg=fovy, pos=np.array([0.0, -1.3, 0.75]), rot=rot)


def _table_depth(cam: PinholeCamera, box=None) -> np.ndarray:
    """Depth along the optical axis of the plane z = 0 (and a box top at z = h if given)."""
    h, w = cam.height, cam.width
    u = np.arange(w) + 0.5 - w / 2
    v = np.arange(h) + 0.5 - h / 2
    rays = np.stack([u[None, :] / cam.focal * np.ones((h, 1)), -v[:, None] / cam.focal * np.ones((1, w)),
                     -np.ones((h, w))], axis=-1) @ cam.rot.T  # world direction per unit depth
    depth = -cam.pos[2] / rays[..., 2]
    if box is not None:
        (x0, x1, y0, y1, top) = box
        d_top = (top - cam.pos[2]) / rays[..., 2]
        p = cam.pos + rays * d_top[..., None]
        inside = (p[..., 0] > x0) & (p[..., 0] < x1) & (p[..., 1] > y0) & (p[..., 1] < y1)
        depth = np.where(inside, d_top, depth)
    return depth


def test_backproject_project_round_trip_and_table_plane():
    cam = _camera()
    pts = cam.backproject(_table_depth(cam))
    assert np.abs(pts[..., 2]).max() < 1e-9  # every pixel lands on the table plane
    uv = cam.project(pts.reshape(-1, 3))
    grid = np.stack(np.meshgrid(np.arange(64) + 0.5, np.arange(48) + 0.5), -1).reshape(-1, 2)
    np.testing.assert_allclose(uv, grid, atol=1e-6)


def test_world_grasp_of_a_box_top_ignores_the_table():
    cam = _camera(640, 480, fovy=22.0)  # the stacking scene's camera
    box = (-0.06, 0.02, 0.0, 0.03, 0.03)  # 8 cm along x, 3 cm along y, top 3 cm high
    pts = cam.backproject(_table_depth(cam, box))
    mask = np.zeros((480, 640), bool)
    mask[pts[..., 2] > 0.02] = True
    mask |= np.roll(mask, 3, axis=0)  # spill onto the table, as a sloppy mask would
    g = world_grasp(mask, pts)
    assert g.xy == pytest.approx((-0.02, 0.015), abs=0.004)
    assert abs(math.cos(g.yaw - math.pi / 2)) > 0.99  # jaws close across the 3 cm side (y)
    assert g.width == pytest.approx(0.03, abs=0.005)
    assert g.top == pytest.approx(0.03, abs=1e-6)
    assert world_grasp(np.roll(mask, 120, axis=1) & (pts[..., 2] < 0.001), pts) is None
    heights = HeightMap(pts)
    assert finger_clearance(heights, g.xy, g.yaw, 0.03) == pytest.approx(0.0, abs=1e-6)
    assert finger_clearance(heights, g.xy, g.yaw + math.pi / 2, 0.01) == pytest.approx(0.03)


def test_per_colour_splits_a_glued_object_by_colour():
    img = np.full((60, 80, 3), 120, np.uint8)  # grey table touching the border: dropped
    img[20:40, 20:40] = (200, 30, 30)
    img[20:40, 40:60] = (30, 30, 200)  # glued to the red part
    labels = make_method("per-colour")([img])
    assert labels.dtype == np.int32 and labels.shape == (60, 80)
    assert len(np.unique(labels[labels > 0])) == 2
    assert labels[30, 30] != labels[30, 50] and labels[0, 0] == 0


def test_summary_json_and_table_layout():
    rs = [TrialResult(0, 0, "m", stacked=5, success=True), TrialResult(0, 1, "m", stacked=2, failure="grasp"),
          TrialResult(0, 2, "m", stacked=3, failure="stack")]
    s = summarise({"m": rs})
    m = s["methods"]["m"]
    assert (m["success"], m["trials"], m["stacked_mean"]) == (1, 3, pytest.approx(10 / 3))
    assert m["failures"] == {"grasp": 1, "stack": 1}
    json.dumps(s)
    text = format_table(s)
    assert "1 / 3" in text and "grasp 1, stack 1" in text and "10 (3.3/trial)" in text


def test_cli_rejects_unknown_method(capsys):
    assert main(["stack", "--trials", "1", "--methods", "no-such-method"]) == 2
    assert "unknown method" in capsys.readouterr().err


mjb = pytest.importorskip("motionbits.synth.mujoco_backend")
_REASON = mjb.render_check()


@pytest.mark.skipif(_REASON is not None, reason=f"MuJoCo cannot render: {_REASON}")
def test_short_trial_stacks_a_ground_truth_mask_then_runs_out_of_masks():
    from motionbits.stacking.sim import StackSim
    from motionbits.stacking.trial import TrialConfig, push_scene, run_trial

    cfg = TrialConfig(width=320, height=240, frame_dt=0.5)
    pushed = push_scene(0, 0, cfg)
    assert pushed.frames[0].shape == (240, 320, 3) and pushed.pushed >= 4
    sim = StackSim(pushed.scene)
    sim.set_state(pushed.state)
    seg = sim.segmentation()  # exact object index per pixel of the last frame
    sim.close()
    one = (seg == np.bincount(seg[seg >= 0]).argmax()).astype(np.int32)  # largest object only
    r = run_trial("one-gt-mask", lambda frames: one, pushed, cfg)
    assert (r.stacked, r.failure, r.success) == (1, "masks", False), r.log
    assert r.n_frames == len(pushed.frames) and r.n_masks == 1
