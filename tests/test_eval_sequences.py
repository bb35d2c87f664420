"""DAVIS-style sequences cut into MoRiBo scenes (``motionbits scenes davis``)."""

import json
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from motionbits.eval import read_label_map, scenes_from_sequence
from motionbits.eval.dataset import discover_scenes, evaluate_dataset, load_frames

SHARED = Path(os.environ.get("MOTIONBITS_SHARED", Path(__file__).resolve().parents[1] / ".." / "shared"))
CAR = SHARED / "data" / "real" / "davis-car-roundabout"


def make_sequence(root, n=12, h=40, w=100, values=(255,)):
    """A box per value moving right by 2 px/frame; masks as 8-bit PNGs with those values."""
    (root / "frames").mkdir(parents=True)
    (root / "gt").mkdir()
    for t in range(n):
        img = np.full((h, w, 3), 60, np.uint8)
        mask = np.zeros((h, w), np.uint8)
        for i, v in enumerate(values):
            y, x = 4 + 16 * i, 4 + 2 * t
            img[y : y + 10, x : x + 12] = 200
            mask[y : y + 10, x : x + 12] = v
        cv2.imwrite(str(root / "frames" / f"{t:05d}.jpg"), img)
        cv2.imwrite(str(root / "gt" / f"{t:05d}.png"), mask)
    return root


def test_windows_gt_and_meta(tmp_path):
    src = make_sequence(tmp_path / "box")
    scenes = scenes_from_sequence(src, tmp_path / "out", length=5, stride=3)
    assert [s.name for s in scenes] == ["box_00000", "box_00003", "box_00006"]  # 9 + 5 > 12
    last = scenes[-1]
    assert len(list((last / "frames").iterdir())) == 5
    gt = read_label_map(last / "gt.png")
    assert sorted(np.unique(gt)) == [0, 1]  # 255 -> 1
    assert np.argwhere(gt == 1)[:, 1].min() == 4 + 2 * 10  # mask of frame 10 = the window's last
    meta = json.loads((last / "meta.json").read_text())
    assert meta["first_frame"] == 6 and meta["gt_from"] == "00010.png" and meta["labels"] == {"1": 255}
    keys = [s.key for s in discover_scenes(tmp_path / "out")]
    assert keys == ["out/box_00000", "out/box_00003", "out/box_00006"]
    with pytest.raises(ValueError, match="already holds"):
        scenes_from_sequence(src, tmp_path / "out", length=5, stride=3)


def test_resize_and_several_objects(tmp_path):
    src = make_sequence(tmp_path / "two", n=6, h=40, w=100, values=(3, 7))
    (scene,) = scenes_from_sequence(src, tmp_path / "out", length=6, stride=6, max_side=50)
    frames = load_frames(scene)
    assert frames[0].shape == (20, 50, 3)
    gt = read_label_map(scene / "gt.png")
    assert gt.shape == (20, 50) and sorted(np.unique(gt)) == [0, 1, 2]
    # A perfect prediction scores 1 on the scene written.
    res = evaluate_dataset(tmp_path / "out", lambda s: read_label_map(s.path / "gt.png"), progress=False)
    assert res["macro"]["mIoU"] == 1.0 and res["false_positives"]["static_fp"] == 0.0


def test_davis_release_layout(tmp_path):
    seq = make_sequence(tmp_path / "tmp" / "bear", n=5, values=(1, 2))
    root = tmp_path / "DAVIS"
    (root / "JPEGImages" / "480p").mkdir(parents=True)
    (root / "Annotations" / "480p").mkdir(parents=True)
    (seq / "frames").rename(root / "JPEGImages" / "480p" / "bear")
    (seq / "gt").rename(root / "Annotations" / "480p" / "bear")
    (scene,) = scenes_from_sequence(root / "JPEGImages" / "480p" / "bear", tmp_path / "out", length=5)
    assert scene.name == "bear_00000" and read_label_map(scene / "gt.png").max() == 2


def test_bad_input(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        scenes_from_sequence(tmp_path / "nope", tmp_path / "out")
    (tmp_path / "empty" / "frames").mkdir(parents=True)
    with pytest.raises(FileNotFoundError, match="no sequence"):
        scenes_from_sequence(tmp_path / "empty", tmp_path / "out")
    src = make_sequence(tmp_path / "short", n=4)
    with pytest.raises(ValueError, match="fewer than"):
        scenes_from_sequence(src, tmp_path / "out", length=16)
    with pytest.raises(ValueError, match="stride"):
        scenes_from_sequence(src, tmp_path / "out", length=2, stride=0)


@pytest.mark.skipif(not CAR.is_dir(), reason="../shared/data/real/davis-car-roundabout is absent")
def test_davis_car_roundabout(tmp_path):
    from motionbits.cli import main

    assert main(["scenes", "davis", str(CAR), "--out", str(tmp_path / "car")]) == 0
    scenes = discover_scenes(tmp_path / "car")
    assert len(scenes) == 8  # 75 frames: windows start at 0, 8, ..., 56
    gt = read_label_map(scenes[0].path / "gt.png")
    assert gt.shape == (360, 640) and gt.max() == 1 and 0.02 < (gt == 1).mean() < 0.5
