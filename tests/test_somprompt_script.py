"""scripts/render_marks_example.py on a synthetic video and label folder."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "render_marks_example.py"


def test_render_marks_example(tmp_path):
    video = tmp_path / "clip.mp4"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), 10, (128, 96))
    labels_dir = tmp_path / "run" / "labels"
    labels_dir.mkdir(parents=True)
    for t in range(4):
        frame = np.full((96, 128, 3), 90, np.uint8)
        writer.write(frame)
        lm = np.zeros((48, 64), np.uint16)  # label maps at half the video resolution
        lm[5:25, 5 + 3 * t:25 + 3 * t] = 300  # 16-bit ids
        lm[30:45, 40:60] = 2
        Image.fromarray(lm).save(labels_dir / f"{t:05d}.png")
    writer.release()
    out = tmp_path / "marks.png"
    run = subprocess.run(
        [sys.executable, str(SCRIPT), str(video), str(labels_dir), str(out), "--max-side", "200",
         "--gif", str(tmp_path / "marks.gif")],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, run.stderr
    img = cv2.imread(str(out))
    assert img.shape == (96, 128, 3)  # not beyond the video's resolution
    assert (np.abs(img.astype(int) - 90).sum(axis=2) > 30).sum() > 200  # marks drawn
    meta = json.loads(out.with_suffix(".json").read_text())
    assert [m["obj_id"] for m in meta["marks"]] == [2, 300]
    assert meta["marks"][1]["frames_seen"] == [0, 1, 2, 3]
    with Image.open(tmp_path / "marks.gif") as gif:
        assert gif.n_frames == 4


def test_render_marks_example_reports_missing_labels(tmp_path):
    run = subprocess.run([sys.executable, str(SCRIPT), "x.mp4", str(tmp_path), str(tmp_path / "o.png")],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode != 0 and "no label maps" in run.stderr
