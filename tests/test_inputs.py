"""Bad and unusual input: clear errors or documented conversions."""

import subprocess
import sys

import cv2
import numpy as np
import pytest

from motionbits import MotionBitsConfig, MotionBitsSegmenter, segment_video
from motionbits.synth import demo_clip

SMALL = MotionBitsConfig(n_nodes=900, max_side=160)


@pytest.fixture(scope="module")
def tiny():
    return demo_clip(n_frames=3, size=(120, 160))


def test_one_frame_is_all_background(tiny):
    res = list(segment_video(tiny.frames[:1], SMALL))
    assert len(res) == 1 and not res[0].labels.any()


@pytest.mark.parametrize("exact", [False, True])
def test_still_video_is_all_background(tiny, exact):
    """Nothing moves: no node is active, and every stage copes with an empty graph."""
    frames = [tiny.frames[0]] * 4
    res = list(segment_video(frames, SMALL.with_(exact=exact)))
    assert all(not r.labels.any() and r.motionbits == [] for r in res)


def test_missing_file():
    with pytest.raises(FileNotFoundError, match="not found"):
        list(segment_video("/nonexistent/video.mp4"))


def test_corrupt_video(tmp_path):
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"this is not a video" * 100)
    with pytest.raises(ValueError, match="bad.mp4"):
        list(segment_video(bad))


def test_empty_inputs(tmp_path):
    with pytest.raises(ValueError, match="empty"):
        list(segment_video(np.zeros((0, 32, 32, 3), np.uint8)))
    with pytest.raises(ValueError, match="empty"):
        list(segment_video([]))
    with pytest.raises(ValueError, match="no images"):
        list(segment_video(tmp_path))


def test_wrong_dtype_and_shape():
    seg = MotionBitsSegmenter(SMALL)
    with pytest.raises(TypeError, match="uint8"):
        seg.update(np.zeros((64, 64, 3), np.float32))
    with pytest.raises(ValueError, match="shape"):
        seg.update(np.zeros((64, 64, 5), np.uint8))
    with pytest.raises(TypeError, match="numpy array"):
        seg.update([[0, 1], [2, 3]])


def test_size_change_mid_stream():
    seg = MotionBitsSegmenter(SMALL)
    seg.update(np.zeros((64, 64, 3), np.uint8))
    with pytest.raises(ValueError, match="reset"):
        seg.update(np.zeros((64, 80, 3), np.uint8))


def test_a_refused_first_frame_is_not_counted():
    seg = MotionBitsSegmenter(SMALL)
    with pytest.raises(ValueError, match="frame 0 is 4000x8"):
        seg.update(np.zeros((8, 4000, 3), np.uint8))
    assert seg.update(np.zeros((64, 64, 3), np.uint8)).frame_index == 0  # a new first frame


def test_grayscale_is_converted(tiny):
    gray = tiny.frames.mean(axis=3).astype(np.uint8)
    res = list(segment_video(gray, SMALL))
    assert res[-1].labels.shape == (120, 160)


def test_video_file_and_image_folder_agree(tiny, tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(tiny.frames):
        cv2.imwrite(str(folder / f"{i:05d}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    from_folder = [r.labels for r in segment_video(folder, SMALL)]
    from_array = [r.labels for r in segment_video(tiny.frames, SMALL)]
    for a, b in zip(from_folder, from_array):
        np.testing.assert_array_equal(a, b)
    video = tmp_path / "clip.mp4"
    w = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), 10, (160, 120))
    for f in tiny.frames:
        w.write(cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    w.release()
    assert len(list(segment_video(video, SMALL))) == len(tiny.frames)


def test_config_rejects_bad_values():
    with pytest.raises(ValueError, match="n_nodes"):
        MotionBitsConfig(n_nodes=0)
    with pytest.raises(ValueError, match="mcl_inflation"):
        MotionBitsConfig(mcl_inflation=1.0)


def test_cli_segment_writes_outputs(tiny, tmp_path):
    import json

    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(tiny.frames):
        cv2.imwrite(str(folder / f"{i:05d}.jpg"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "motionbits.cli", "segment", str(folder), "--out", str(out),
           "--nodes", "900", "--max-side", "160", "--quiet"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    labels = sorted((out / "labels").glob("*.png"))
    assert [p.name for p in labels] == [f"{i:05d}.png" for i in range(3)]
    lab = cv2.imread(str(labels[-1]), cv2.IMREAD_UNCHANGED)
    assert lab.dtype == np.uint16 and lab.shape == (120, 160)
    assert (out / "overlay.mp4").stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 3 and "stages_median" in summary["timings_ms"]
    missing = subprocess.run([sys.executable, "-m", "motionbits.cli", "segment", "/no/such.mp4",
                              "--out", str(out)], capture_output=True, text=True)
    assert missing.returncode == 2 and "not found" in missing.stderr


def test_cli_segment_window(tmp_path):
    """--start / --every / --frames pick a window; label files keep the video's indices."""
    import json

    clip = demo_clip(n_frames=9, size=(120, 160))
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(clip.frames):
        cv2.imwrite(str(folder / f"{i:05d}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    out = tmp_path / "out"
    base = [sys.executable, "-m", "motionbits.cli", "segment", str(folder), "--out", str(out),
            "--nodes", "900", "--max-side", "160", "--quiet"]
    subprocess.run(base + ["--start", "2", "--every", "2", "--frames", "3"], check=True,
                   capture_output=True, text=True)
    assert sorted(p.name for p in (out / "labels").glob("*.png")) == ["00002.png", "00004.png", "00006.png"]
    assert json.loads((out / "summary.json").read_text())["frame_indices"] == [2, 4, 6]
    bad = subprocess.run(base + ["--start", "20"], capture_output=True, text=True)
    assert bad.returncode == 2 and "past the last frame" in bad.stderr
