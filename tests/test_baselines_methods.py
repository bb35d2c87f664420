"""Baselines and the method registry on small synthetic clips (no MuJoCo needed)."""

import argparse
import importlib
import json

import cv2
import numpy as np
import pytest
from PIL import Image

import motionbits
from motionbits.baselines import available_methods, make_method, register_method
from motionbits.eval import evaluate_frame, write_label_map


def _texture(rng, h, w, blur=1.5):
    t = rng.random((h, w, 3)).astype(np.float32)
    t = cv2.GaussianBlur(t, (0, 0), blur)
    t = (t - t.min()) / (t.max() - t.min())
    return (t * 255).astype(np.uint8)


def make_clip(moves, n=6, h=96, w=128, size=28, seed=0):
    """Textured squares over a static textured background; ``moves`` = [(y, x, dy, dx)].

    Returns frames and the last frame's GT (square k labelled k + 1)."""
    rng = np.random.default_rng(seed)
    bg = _texture(rng, h, w)
    texs = [_texture(rng, size, size) for _ in moves]
    frames, gt = [], None
    for t in range(n):
        f = bg.copy()
        gt = np.zeros((h, w), np.int32)
        for k, ((y, x, dy, dx), tex) in enumerate(zip(moves, texs)):
            yy, xx = int(round(y + dy * t)), int(round(x + dx * t))
            f[yy : yy + size, xx : xx + size] = tex
            gt[yy : yy + size, xx : xx + size] = k + 1
        frames.append(f)
    return frames, gt


def test_flow_cc_finds_two_separate_movers():
    frames, gt = make_clip([(10, 10, 0, 3), (55, 70, 2, -2)])
    pred = make_method("flow-cc")(frames)
    assert pred.shape == gt.shape and pred.dtype == np.int32
    s = evaluate_frame(pred, gt)
    assert s.n_pred == 2
    assert s.iou.min() > 0.5  # the trail of the moved region lowers IoU, but both are found


def test_affine_ransac_separates_touching_bodies():
    # Two squares side by side, moving apart vertically (touching at the start).
    frames, gt = make_clip([(30, 20, -2, 0), (30, 48, 2, 0)], h=96, w=128)
    aff = evaluate_frame(make_method("affine-ransac")(frames), gt)
    assert aff.n_pred >= 2 and aff.f1.min() > 0.5


def test_static_clip_gives_empty_prediction():
    frames, _ = make_clip([(10, 10, 0, 0)])
    for name in ("flow-cc", "affine-ransac"):
        assert not make_method(name)(frames).any()


def test_registry_plugins_and_errors():
    assert {"flow-cc", "affine-ransac", "motionbits"} <= set(available_methods())
    register_method("test-oracle-zero", lambda **kw: (lambda frames: np.zeros(frames[-1].shape[:2], np.int32)),
                    "returns nothing", replace=True)
    assert make_method("test-oracle-zero")([np.zeros((9, 9, 3), np.uint8)] * 2).shape == (9, 9)
    with pytest.raises(KeyError, match="available"):
        make_method("no-such-method")
    with pytest.raises(ValueError, match="already registered"):
        register_method("flow-cc", lambda **kw: None)


def test_motionbits_method_takes_last_labels():
    from motionbits.synth import demo_clip

    clip = demo_clip(n_frames=4, size=(120, 160))
    config = motionbits.MotionBitsConfig(n_nodes=900, max_side=240)
    out = make_method("motionbits", config=config)(clip.frames)
    expected = motionbits.MotionBitsSegmenter(config)(clip.frames)[-1]
    assert out.dtype == np.int32 and out.any() and np.array_equal(out, expected)
    exact = make_method("motionbits", config={"n_nodes": 900, "max_side": 240}, exact=True)
    assert exact.config == config.with_(exact=True)


def _run(module, argv):
    parser = argparse.ArgumentParser(prog="motionbits")
    importlib.import_module(module).register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.func(args)


def test_benchmark_runner_and_command(tmp_path, capsys):
    from motionbits.eval.benchmark import run_benchmark

    for i, moves in enumerate([[(10, 10, 0, 3)], [(20, 30, 2, 2), (60, 90, -1, -3)]]):
        frames, gt = make_clip(moves, seed=i)
        scene = tmp_path / "data" / "toy" / f"s{i}"
        (scene / "frames").mkdir(parents=True)
        for t, f in enumerate(frames):
            Image.fromarray(f).save(scene / "frames" / f"{t:05d}.png")
        write_label_map(scene / "gt.png", gt)
        (scene / "meta.json").write_text("{}")

    from motionbits.eval.dataset import discover_scenes, load_frames, load_ground_truth

    answers = {load_frames(sc)[-1].tobytes(): load_ground_truth(sc)[0]
               for sc in discover_scenes(tmp_path / "data")}

    def oracle(frames):  # knows the answer (frames are lossless PNGs)
        return answers[frames[-1].tobytes()]

    def not_installed(frames):
        raise ImportError("needs a package that is not installed")

    res, spf = run_benchmark(tmp_path / "data", {"oracle": oracle, "flow-cc": make_method("flow-cc"),
                                                 "absent": not_installed},
                             save_pred=tmp_path / "pred", progress=False)
    assert set(res) == {"oracle", "flow-cc"}  # the method that cannot run is skipped
    assert res["oracle"]["macro"]["F1"] == 1.0 and res["oracle"]["macro"]["BF1"] == 1.0
    assert res["oracle"]["false_positives"] == {"static_fp": 0.0, "static_fp_scene": 0.0,
                                                "spurious": 0.0}
    assert 0.0 < res["flow-cc"]["macro"]["F1"] <= 1.0
    assert spf["flow-cc"] > 0
    assert (tmp_path / "pred" / "flow-cc" / "toy" / "s1.png").is_file()

    out = tmp_path / "b.json"
    assert _run("motionbits.commands.benchmark",
                ["benchmark", "--data", str(tmp_path / "data"), "--methods", "flow-cc",
                 "--json", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "flow-cc" in text and "s/frame" in text and "sFP" in text
    assert json.loads(out.read_text())["methods"]["flow-cc"]["macro"]["F1"] == pytest.approx(
        res["flow-cc"]["macro"]["F1"])
    # Saved predictions are readable by 'motionbits eval'.
    assert _run("motionbits.commands.eval",
                ["eval", "--pred", str(tmp_path / "pred" / "flow-cc"), "--gt",
                 str(tmp_path / "data"), "--quiet"]) == 0
    with pytest.raises(ValueError, match="unknown method"):
        _run("motionbits.commands.benchmark", ["benchmark", "--data", str(tmp_path / "data"),
                                               "--methods", "nope"])
