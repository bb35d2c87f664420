"""Ground truth of the MuJoCo benchmark generator, on tiny low-resolution scenes."""

import json

import numpy as np
import pytest

mjb = pytest.importorskip("motionbits.synth.mujoco_backend")
_REASON = mjb.render_check()
pytestmark = pytest.mark.skipif(_REASON is not None, reason=f"MuJoCo cannot render: {_REASON}")

W, H = 96, 72


def _roots(xml):
    mujoco = mjb.import_mujoco()
    model = mujoco.MjModel.from_xml_string(xml)
    names = [model.body(i).name for i in range(model.nbody)]
    return model, names


def _handmade_plan():
    from motionbits.synth.mujoco_scenes import Camera, ScenePlan

    xml = """<mujoco><option timestep="0.002"/>
    <visual><global offwidth="96" offheight="72"/></visual>
    <worldbody><light pos="0 0 2" dir="0 0 -1"/>
      <geom name="table" type="box" pos="0 0 -0.02" size="0.4 0.4 0.02" rgba=".6 .6 .6 1"/>
      <geom name="static" type="box" pos="0.15 -0.15 0.03" size="0.03 0.03 0.03" rgba="0 0 1 1"/>
      <body name="objA" pos="0 0 0.021"><freejoint/>
        <geom type="box" size="0.03 0.03 0.02" rgba="1 0 0 1"/>
        <geom type="box" pos="0 0.045 0" size="0.015 0.015 0.02" rgba="0 1 0 1"/>
        <body name="fixA" pos="0 -0.045 0"><geom type="box" size="0.015 0.015 0.02" rgba="1 1 0 1"/></body>
      </body>
      <body name="objB" pos="0 0.22 0.021"><freejoint/><geom type="box" size="0.03 0.03 0.02" rgba="1 0 1 1"/></body>
      <body name="pusher" mocap="true" pos="-0.2 0 0.01">
        <geom type="box" pos="0 0 0.02" size="0.01 0.04 0.02" rgba="0 1 1 1"/>
      </body>
    </worldbody></mujoco>"""
    return ScenePlan(
        track="robot", xml=xml, init_qpos={}, camera=Camera((0.0, 0.05, 0.0), 0.9, 90.0, -89.0),
        n_frames=8, frame_dt=0.1, start=np.array([-0.12, 0.0, 0.004]),
        end=np.array([0.02, 0.0, 0.004]), yaw=0.0, target=("objA", "composite"),
        parts=(("objA", "composite"), ("objB", "block")),
    )


def test_handmade_scene_labels_exactly_the_moved_rigid_bodies():
    from motionbits.synth.mujoco_sim import MOVED_M, simulate

    plan = _handmade_plan()
    clip = simulate(plan, width=W, height=H)
    model, names = _roots(plan.xml)
    assert clip.valid
    by_name = {names[r]: lab for r, lab in clip.label_of_root.items()}
    assert set(by_name) == {"objA", "pusher"}  # B and the static box did not move
    assert clip.deviation[names.index("objA")] >= MOVED_M
    assert clip.deviation[names.index("objB")] < 1e-3
    geom_body = model.geom_bodyid[np.maximum(clip.geom_ids, 0)]
    seen = clip.geom_ids >= 0
    # Every visible pixel of objA's two geoms and of its jointless child carries A's label.
    a_pix = seen & np.isin(geom_body, [names.index("objA"), names.index("fixA")])
    assert np.count_nonzero(a_pix) > 20
    assert set(np.unique(clip.gt[a_pix])) == {by_name["objA"]}
    child_pix = seen & (geom_body == names.index("fixA"))
    assert child_pix.any() and set(np.unique(clip.gt[child_pix])) == {by_name["objA"]}
    # Bodies that did not move, the table and the static box are background.
    for still in ("objB", "world"):
        pix = seen & (geom_body == names.index(still))
        assert pix.any() and not clip.gt[pix].any()
    assert not clip.gt[~seen].any()


@pytest.fixture(scope="module")
def tiny_tracks(tmp_path_factory):
    from motionbits.synth.mujoco_moribo import generate_track

    out = tmp_path_factory.mktemp("synth")
    for track in ("robot", "hand"):
        generate_track(track, 1, seed=3, out=out, width=W, height=H, n_frames=6, progress=False)
    return out


@pytest.mark.parametrize("track", ["robot", "hand"])
def test_generated_scene_is_moribo_and_consistent(tiny_tracks, track):
    from motionbits.eval import read_label_map
    from motionbits.eval.dataset import discover_scenes, load_frames

    scenes = [s for s in discover_scenes(tiny_tracks) if s.track == track]
    assert len(scenes) == 1
    scene = scenes[0]
    frames = load_frames(scene)
    gt = read_label_map(scene.path / "gt.png")
    meta = json.loads((scene.path / "meta.json").read_text())
    assert len(frames) == 6 and frames[0].shape == (H, W, 3) and gt.shape == (H, W)
    labels = set(np.unique(gt)) - {0}
    assert labels <= {int(k) for k in meta["labels"]}
    kinds = {v["kind"] for v in meta["labels"].values()}
    assert ("gripper" if track == "robot" else "hand") in kinds  # the pusher always moves
    assert len(kinds) >= 2  # and so does something it pushed
    for v in meta["labels"].values():
        assert v["max_deviation_m"] >= meta["thresholds_m"]["moved"]


def test_generator_is_deterministic_and_rigid_bodies_are_single_labels():
    from motionbits.synth.mujoco_moribo import generate_scene

    clip1, plan, _ = generate_scene("hand", seed=5, index=2, width=W, height=H, n_frames=4)
    clip2, _, _ = generate_scene("hand", seed=5, index=2, width=W, height=H, n_frames=4)
    np.testing.assert_array_equal(clip1.gt, clip2.gt)
    np.testing.assert_array_equal(clip1.frames, clip2.frames)
    model, names = _roots(plan.xml)
    seen = clip1.geom_ids >= 0
    root = model.body_weldid[model.geom_bodyid[np.maximum(clip1.geom_ids, 0)]]
    # One label per rigid body, and labelled bodies are exactly the moved roots.
    for r in np.unique(root[seen]):
        labs = np.unique(clip1.gt[seen & (root == r)])
        assert labs.size == 1
        assert (labs[0] > 0) == (int(r) in clip1.label_of_root)
        if r == 0:
            assert labs[0] == 0  # everything welded to the world is background
    # Jointless links ('fix*') are never their own rigid body.
    for i, name in enumerate(names):
        if name.startswith("fix"):
            assert model.body_weldid[i] != i
