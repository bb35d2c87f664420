"""MoRiBo folders, prediction lookup and the ``motionbits eval`` command."""

import argparse
import importlib
import json

import numpy as np
import pytest
from PIL import Image

from motionbits.eval import read_label_map, write_label_map
from motionbits.eval.dataset import discover_scenes, evaluate_dataset


def run_command(module: str, argv: list[str]) -> int:
    """Run one subcommand through argparse as ``motionbits`` does, without importing the
    other subcommand modules (they live on other branches)."""
    parser = argparse.ArgumentParser(prog="motionbits")
    sub = parser.add_subparsers(dest="command")
    importlib.import_module(module).register(sub)
    args = parser.parse_args(argv)
    return int(args.func(args) or 0)


def make_scene(root, name, gt, ignore=None):
    scene = root / name
    (scene / "frames").mkdir(parents=True)
    for i in range(2):
        Image.fromarray(np.zeros(gt.shape + (3,), np.uint8)).save(scene / "frames" / f"{i:05d}.jpg")
    write_label_map(scene / "gt.png", gt)
    if ignore is not None:
        Image.fromarray(ignore.astype(np.uint8) * 255).save(scene / "ignore.png")
    (scene / "meta.json").write_text("{}")
    return scene


def squares(shape, *boxes):
    lab = np.zeros(shape, np.int32)
    for k, (y, x, s) in enumerate(boxes, 1):
        lab[y : y + s, x : x + s] = k * 1000  # 16-bit labels beyond 255
    return lab


def test_label_map_roundtrip_16bit(tmp_path):
    lab = np.array([[0, 1, 65535], [300, 2, 0]], np.int32)
    write_label_map(tmp_path / "x.png", lab)
    np.testing.assert_array_equal(read_label_map(tmp_path / "x.png"), lab)
    Image.fromarray(np.zeros((3, 3, 3), np.uint8)).save(tmp_path / "rgb.png")
    with pytest.raises(ValueError, match="RGB"):
        read_label_map(tmp_path / "rgb.png")


@pytest.fixture
def dataset(tmp_path):
    shape = (40, 48)
    gt_root, pred_root = tmp_path / "gt", tmp_path / "pred"
    gt_a = squares(shape, (5, 5, 10), (20, 25, 10))
    gt_b = squares(shape, (8, 8, 12))
    make_scene(gt_root / "robot", "a", gt_a)
    ign = np.zeros(shape, bool)
    ign[30:, 30:] = True
    make_scene(gt_root / "hand", "b", gt_b, ignore=ign)
    # robot/a as a plain PNG: first object perfect, second missed.
    pred_a = np.where(gt_a == 1000, 7, 0)
    write_label_map(pred_root / "robot" / "a.png", pred_a)
    # hand/b as a segment output folder: the last labels/ map is perfect plus a false
    # positive in the ignored corner; an earlier map is garbage.
    write_label_map(pred_root / "hand" / "b" / "labels" / "00000.png", np.ones(shape, np.int32))
    last = np.where(gt_b > 0, 3, 0)
    last[32:36, 32:36] = 4
    write_label_map(pred_root / "hand" / "b" / "labels" / "00001.png", last)
    return gt_root, pred_root


def test_discover_tracks(dataset):
    gt_root, _ = dataset
    keys = [s.key for s in discover_scenes(gt_root)]
    assert keys == ["hand/b", "robot/a"]
    assert [s.key for s in discover_scenes(gt_root / "robot")] == ["robot/a"]


def test_evaluate_dataset_per_track_and_average(dataset):
    gt_root, pred_root = dataset
    res = evaluate_dataset(gt_root, pred_root, progress=False)
    assert res["tracks"]["robot"]["macro"]["F1"] == pytest.approx(0.5)
    assert res["tracks"]["hand"]["macro"]["F1"] == pytest.approx(1.0)
    assert res["tracks"]["hand"]["pooled"]["P"] == pytest.approx(1.0)  # FP is ignored
    assert res["macro"]["F1"] == pytest.approx(0.75)  # mean over tracks
    assert res["per_scene"]["robot/a"]["n_gt"] == 2
    # hand/b's labels/00000.png (all ones) is not the one scored: no false positive.
    assert res["tracks"]["hand"]["false_positives"]["spurious"] == 0.0


def test_eval_command_prints_table_and_json(dataset, tmp_path, capsys):
    gt_root, pred_root = dataset
    out = tmp_path / "scores.json"
    assert run_command("motionbits.commands.eval",
                       ["eval", "--pred", f"mine={pred_root}", "--gt", str(gt_root),
                        "--json", str(out), "--quiet", "--pooled"]) == 0
    text = capsys.readouterr().out
    assert "average over tracks" in text and "mine" in text and "Boundary" in text
    assert "  50.0" in text and "100.0" in text
    data = json.loads(out.read_text())
    assert set(data) >= {"macro", "pooled", "per_scene"}
    assert set(data["macro"]) >= {"P", "R", "F1", "mIoU", "BP", "BR", "BF1"}
    assert data["macro"] == pytest.approx(evaluate_dataset(gt_root, pred_root, progress=False)["macro"])
    assert data["macro"]["F1"] == pytest.approx(0.75)
    # hand/b: the false positive lies in the ignored corner; robot/a: none. No spurious.
    assert "sFP" in text and "Spur" in text
    fp = data["false_positives"]
    assert fp["static_fp"] == 0.0 and fp["spurious"] == 0.0
    assert data["tracks"]["hand"]["false_positives"]["static_fp_scene"] == 0.0
    assert data["per_scene"]["robot/a"]["false_positives"]["static_pixels"] == 40 * 48 - 200


def test_errors(dataset, tmp_path):
    gt_root, pred_root = dataset
    (pred_root / "robot" / "a.png").unlink()
    with pytest.raises(FileNotFoundError, match="no prediction for scene robot/a"):
        evaluate_dataset(gt_root, pred_root, progress=False)
    res = evaluate_dataset(gt_root, pred_root, missing="empty", progress=False)
    assert res["tracks"]["robot"]["macro"]["F1"] == 0.0
    write_label_map(pred_root / "robot" / "a.png", np.zeros((5, 5), np.int32))
    with pytest.raises(ValueError, match="robot/a.*shape"):
        evaluate_dataset(gt_root, pred_root, progress=False)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no MoRiBo scene"):
        discover_scenes(tmp_path / "empty")
    (gt_root / "robot" / "a" / "gt.png").unlink()
    with pytest.raises(FileNotFoundError, match="gt.png"):
        evaluate_dataset(gt_root, pred_root, progress=False)


def test_segment_output_past_99999_frames_uses_the_last(tmp_path):
    """`segment` names frame 100000 '100000.png': it is the last, not '99999.png' (was:
    string order picked 99999.png)."""
    from motionbits.eval.dataset import read_prediction

    last = np.zeros((4, 4), np.int32)
    last[1:3, 1:3] = 7
    write_label_map(tmp_path / "run" / "labels" / "99999.png", np.ones((4, 4), np.int32))
    write_label_map(tmp_path / "run" / "labels" / "100000.png", last)
    (tmp_path / "run" / "labels" / "._100001.png").write_bytes(b"\x00\x05\x16\x07")  # macOS AppleDouble
    assert np.array_equal(read_prediction(tmp_path / "run"), last)
