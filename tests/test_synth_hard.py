"""Harder generated tracks: natural textures, scripted agents, moving cameras, exact flow."""

import json

import cv2
import numpy as np
import pytest

from motionbits.synth.textures import NATURAL_KINDS, natural_texture

W, H = 96, 72


@pytest.mark.parametrize("kind", NATURAL_KINDS)
def test_natural_textures_are_seeded_and_textured(kind):
    a = natural_texture(kind, np.random.default_rng(4), 64)
    b = natural_texture(kind, np.random.default_rng(4), 64)
    c = natural_texture(kind, np.random.default_rng(5), 64)
    assert a.shape == (64, 64, 3) and a.dtype == np.uint8
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.astype(float).std() > 4  # not a flat colour
    with pytest.raises(ValueError, match="unknown texture kind"):
        natural_texture("plastic", np.random.default_rng(0))


def test_agent_path_eases_between_keyframes():
    from motionbits.synth.mujoco_choreo import AgentPath

    path = AgentPath("agent0", (0.0, 2.0, 4.0), np.array([[0, 0, 0], [1, 0, 0], [1, 2, 0]], float),
                     np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 1.0]))
    p, yaw, grip = path.at(1.0)  # halfway between keyframes: smoothstep(0.5) = 0.5
    np.testing.assert_allclose(p, [0.5, 0, 0])
    assert grip == pytest.approx(0.5)
    p, _, _ = path.at(0.5)  # eased: slower than linear near a keyframe
    assert p[0] < 0.25
    p, yaw, _ = path.at(9.0)  # held after the last keyframe
    np.testing.assert_allclose(p, [1, 2, 0])
    assert yaw == pytest.approx(1.0)


def test_camera_paths():
    from motionbits.synth.camera_paths import _forward, camera_path
    from motionbits.synth.mujoco_scenes import Camera

    base = Camera((0.0, 0.05, 0.0), 1.0, 90.0, -45.0)
    assert camera_path("static", base, 5, np.random.default_rng(0)) == (base,) * 5
    pan = camera_path("pan", base, 6, np.random.default_rng(1))
    pos = [np.asarray(c.lookat) - c.distance * _forward(c.azimuth, c.elevation) for c in pan]
    np.testing.assert_allclose(pos, [pos[0]] * 6, atol=1e-9)  # turns in place
    assert abs(pan[-1].azimuth - base.azimuth) >= 8
    orbit = camera_path("orbit", base, 6, np.random.default_rng(2))
    assert all(c.lookat == base.lookat for c in orbit) and abs(orbit[-1].azimuth - 90) >= 15
    shake = camera_path("shake", base, 6, np.random.default_rng(3))
    assert len({c.azimuth for c in shake}) == 6
    with pytest.raises(ValueError, match="unknown camera mode"):
        camera_path("dolly", base, 3, np.random.default_rng(0))


# ----- everything below needs MuJoCo and an offscreen renderer -------------------------
mjb = pytest.importorskip("motionbits.synth.mujoco_backend")
_REASON = mjb.render_check()
needs_render = pytest.mark.skipif(_REASON is not None, reason=f"MuJoCo cannot render: {_REASON}")


def _textured_plan(cameras):
    """A checkered table, a static box, a pushed textured box and a camera path."""
    from motionbits.synth.mujoco_scenes import Camera, ScenePlan

    xml = f"""<mujoco><option timestep="0.002"/>
    <visual><global offwidth="{4 * W}" offheight="{4 * H}"/></visual>
    <asset>
      <texture name="t" type="2d" builtin="checker" rgb1=".9 .8 .6" rgb2=".3 .4 .5" width="64" height="64"/>
      <material name="m" texture="t" texrepeat="6 6" texuniform="true"/>
      <texture name="c" type="cube" builtin="checker" rgb1="1 .2 .1" rgb2=".1 .2 1" width="32" height="32"/>
      <material name="mc" texture="c"/>
    </asset>
    <worldbody><light pos="0 -0.3 2" dir="0 0.15 -1"/>
      <geom name="table" type="box" pos="0 0 -0.02" size="0.5 0.5 0.02" material="m"/>
      <geom name="static" type="box" pos="0.15 0.15 0.04" size="0.04 0.04 0.04" material="mc"/>
      <body name="objA" pos="0 0 0.031"><freejoint/>
        <geom type="box" size="0.05 0.05 0.03" material="mc"/></body>
      <body name="pusher" mocap="true" pos="-0.2 0 0.01">
        <geom type="box" pos="0 0 0.02" size="0.01 0.05 0.02" rgba="0 1 1 1"/></body>
    </worldbody></mujoco>"""
    return ScenePlan(
        track="robot", xml=xml, init_qpos={}, camera=cameras[0], n_frames=len(cameras),
        frame_dt=0.1, start=np.array([-0.09, 0.0, 0.004]), end=np.array([0.02, 0.0, 0.004]),
        yaw=0.0, target=("objA", "block"), parts=(("objA", "block"),), cameras=tuple(cameras),
    )


@needs_render
@pytest.mark.parametrize("moving_camera", [False, True])
def test_oracle_flow_warps_previous_frame_onto_current(moving_camera):
    """Pulling frame t-1 back along the exact flow t -> t-1 reproduces frame t on static
    and rigidly moving pixels; the flow points where it should (sub-pixel)."""
    from motionbits.synth.mujoco_moribo import scene_flows
    from motionbits.synth.mujoco_scenes import Camera
    from motionbits.synth.mujoco_sim import simulate

    w, h = 2 * W, 2 * H
    cams = [Camera((0.0, 0.0, 0.0), 0.8, 90.0 + (2.0 * k if moving_camera else 0.0),
                   -60.0 + (1.0 * k if moving_camera else 0.0)) for k in range(3)]
    clip = simulate(_textured_plan(cams), width=w, height=h, record_geometry=True)
    flows = scene_flows(clip)
    assert len(flows) == 2
    names = clip.body_names
    cols, rows = np.meshgrid(np.arange(w), np.arange(h))
    for k, f in enumerate(flows, start=1):
        back, ok = f["backward"], f["backward_valid"]
        assert back.shape == (h, w, 2) and ok.dtype == bool and ok.mean() > 0.8
        prev, cur = clip.frames[k - 1].astype(np.float32), clip.frames[k].astype(np.float32)
        root = clip.body_root[clip.geom_body[np.maximum(clip.geometry[k].geom_ids, 0)]]
        box = ok & (root == names.index("objA"))
        world = ok & (root == 0)
        assert np.hypot(*back[box].T).mean() > 1.0  # the box moved
        err_by_shift = []
        for dx, dy in ((0, 0), (0.5, 0), (0, 0.5), (-0.5, 0), (0, -0.5)):
            warped = cv2.remap(prev, (cols + back[..., 0] + dx).astype(np.float32),
                               (rows + back[..., 1] + dy).astype(np.float32), cv2.INTER_LINEAR)
            err_by_shift.append(np.abs(warped - cur).mean(-1))
        err, still = err_by_shift[0], np.abs(prev - cur).mean(-1)
        # Small photometric error where flow is exact; much smaller than doing nothing.
        assert np.median(err[world]) < 2.0 and np.median(err[box]) < 4.0
        assert err[box].mean() < 0.5 * still[box].mean()
        if moving_camera:
            assert err[world].mean() < 0.5 * still[world].mean()
        # Half a pixel off in any direction is worse: the pixel-centre convention is right.
        assert all(e[ok].mean() > err[ok].mean() for e in err_by_shift[1:])
        # The forward flow is the inverse map: going k-1 -> k -> k-1 returns home.
        fwd, fok = f["forward"], f["forward_valid"]
        mx, my = (cols + fwd[..., 0]).astype(np.float32), (rows + fwd[..., 1]).astype(np.float32)
        back_at = cv2.remap(back, mx, my, cv2.INTER_LINEAR)
        loop = np.hypot(*(fwd + back_at).transpose(2, 0, 1))
        assert np.median(loop[fok]) < 0.1


@pytest.fixture(scope="module")
def tiny_pickplace(tmp_path_factory):
    from motionbits.synth.mujoco_moribo import generate_track

    out = tmp_path_factory.mktemp("hard")
    generate_track("pickplace", 1, seed=0, out=out, width=W, height=H, n_frames=5,
                   progress=False, camera="shake", flow=True)
    return out / "pickplace-shake" / "scene_0000"


@needs_render
def test_pickplace_scene_ignores_agents_and_labels_movers(tiny_pickplace):
    from motionbits.eval import read_label_map

    meta = json.loads((tiny_pickplace / "meta.json").read_text())
    gt = read_label_map(tiny_pickplace / "gt.png")
    ignore = read_label_map(tiny_pickplace / "ignore.png") > 0 if (
        tiny_pickplace / "ignore.png").is_file() else np.zeros_like(gt, bool)
    assert meta["track"] == "pickplace" and meta["agents_ignored"]
    assert meta["camera_motion"]["mode"] == "shake" and len(meta["camera_motion"]["cameras"]) == 16
    script = meta["script"]
    assert script["carries"] and len(script["agents"]) + len(script["kicks"]) >= 2
    carried = script["carries"][0]["body"]
    assert carried in {v["body"] for v in meta["labels"].values()}  # carried -> labelled
    assert all(v["kind"] not in ("hand", "gripper") for v in meta["labels"].values())
    assert all(b.startswith("agent") for b in meta["ignored_bodies"])
    assert not (gt[ignore] > 0).any()
    assert len(sorted((tiny_pickplace / "flow").glob("*.npz"))) == 4
    assert meta["flow"]["max_px_per_frame"]["bodies"] > 0


@needs_render
def test_pickplace_is_deterministic_and_agents_are_never_labelled():
    from motionbits.synth.mujoco_moribo import generate_scene
    from motionbits.synth.mujoco_sim import agent_roots

    a, plan, _ = generate_scene("pickplace", seed=2, index=1, width=W, height=H, n_frames=2)
    b, _, _ = generate_scene("pickplace", seed=2, index=1, width=W, height=H, n_frames=2)
    np.testing.assert_array_equal(a.frames, b.frames)
    np.testing.assert_array_equal(a.gt, b.gt)
    mujoco = mjb.import_mujoco()
    model = mujoco.MjModel.from_xml_string(plan.xml, plan.assets)
    agents = agent_roots(model)
    assert agents and 0 not in agents
    root = a.root_of_geom[np.maximum(a.geom_ids, 0)]
    on_agent = (a.geom_ids >= 0) & np.isin(root, list(agents))
    assert not a.gt[on_agent].any() and a.ignore[on_agent].all()


@needs_render
def test_stored_flow_backend_and_oracle_method(tiny_pickplace):
    from motionbits.baselines import make_method
    from motionbits.baselines.oracle_flow import StoredFlow, load_flow_pair
    from motionbits.eval.benchmark import run_benchmark
    from motionbits.eval.dataset import discover_scenes, load_frames

    scene = discover_scenes(tiny_pickplace)[0]
    frames = load_frames(scene)
    backend = StoredFlow(scene.path, frames)
    backend.frame = 2
    pair = load_flow_pair(scene.path, 2)
    np.testing.assert_array_equal(backend(frames[1], frames[2]), pair["forward"])
    np.testing.assert_array_equal(backend(frames[2], frames[1]), pair["backward"])
    half = [cv2.resize(f, (W // 2, H // 2), interpolation=cv2.INTER_AREA) for f in frames[1:3]]
    small = backend(half[1], half[0])  # argument order and size are read from the frames
    assert small.shape == (H // 2, W // 2, 2)
    ref = cv2.resize(pair["backward"], (W // 2, H // 2), interpolation=cv2.INTER_LINEAR) * 0.5
    np.testing.assert_allclose(small, ref, atol=1e-5)
    results, _ = run_benchmark(tiny_pickplace.parent, {"oracle": make_method("motionbits-oracle-flow")},
                               progress=False)
    assert "pickplace-shake" in results["oracle"]["tracks"]
    with pytest.raises(ValueError, match="needs the scene folder"):
        make_method("motionbits-oracle-flow")(frames)
    # --option values arrive as strings: converted and checked as for ``motionbits``
    oracle = make_method("motionbits-oracle-flow", merge_agree="0", camera_reflow="true")
    assert oracle.config.merge_agree == 0.0 and oracle.config.camera_reflow is True
    assert make_method("motionbits-oracle-flow").config.camera_reflow is False
    with pytest.raises(ValueError, match="unknown MotionBitsConfig field"):
        make_method("motionbits-oracle-flow", no_such_field="1")
    with pytest.raises(FileNotFoundError, match="--flow"):
        load_flow_pair(tiny_pickplace.parent, 1)
