"""The web demo's callbacks without a browser: every kind of bad input becomes a one-line
message, and the outputs of a good run are what the page shows."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest
from PIL import Image

pytest.importorskip("av")
pytest.importorskip("pycocotools")

from demos.app import DemoConfig, DemoLimits, _Handlers, highlight  # noqa: E402
from demos.media import write_demo_clip  # noqa: E402
from motionbits.video_writer import write_h264  # noqa: E402


def _handlers(tmp_path, **config) -> _Handlers:
    return _Handlers(DemoConfig(**config), tmp_path)


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> str:
    return str(write_demo_clip(tmp_path_factory.mktemp("app") / "clip.mp4", n_frames=6, size=(120, 160)))


def _status_of_run(h, path, **kw):
    args = {"n_nodes": 400, "start": 0, "frames": 0, "every": 1, **kw}
    out = h.run(path, args["n_nodes"], args["start"], args["frames"], args["every"], progress=lambda *a, **k: None)
    return out


@pytest.mark.parametrize("case, words", [
    ("none", "no video"),
    ("missing", "video not found"),
    ("text", "not a video"),
    ("empty", "not a video"),
    ("one_frame", "has 1 frame"),
    ("too_large", "over the limit of 100 px"),
    ("window", "start frame 50 is past the end"),
    ("too_long", "the window holds 6 frames, over the limit of 3 at 160x120"),
    ("thin", "frames are 1000x16, too thin to segment: with a longer side of 1000 px the shorter "
             "side must be at least 31 px; crop the video"),
])
def test_bad_input_is_a_readable_message(tmp_path, clip, case, words):
    limits = {"too_large": DemoLimits(max_side=100), "too_long": DemoLimits(max_frames=3)}
    h = _handlers(tmp_path, limits=limits.get(case, DemoLimits()))
    paths = {"none": None, "missing": tmp_path / "gone.mp4", "text": tmp_path / "a.txt", "empty": tmp_path / "empty.mp4",
             "one_frame": tmp_path / "one.mp4", "too_large": clip, "window": clip, "too_long": clip,
             "thin": tmp_path / "thin.mp4"}
    (tmp_path / "a.txt").write_text("hello")
    (tmp_path / "empty.mp4").write_bytes(b"")
    write_h264([np.zeros((32, 32, 3), np.uint8)], tmp_path / "one.mp4")
    write_h264([np.full((16, 1000, 3), 40 * i, np.uint8) for i in range(3)], tmp_path / "thin.mp4")
    out = _status_of_run(h, None if paths[case] is None else str(paths[case]),
                         start=50 if case == "window" else 0)
    assert out[:5] == (None, [], None, None, None)
    status = out[5]
    assert status.startswith("**Error:**") and words in status, status
    assert "\n" not in status and "Traceback" not in status
    assert "max_side" not in status  # a segmenter setting the page does not offer


@pytest.mark.parametrize("fields, words", [
    ({"n_nodes": None}, "Graph nodes must be a whole number, got None"),
    ({"n_nodes": "many"}, "Graph nodes must be a whole number, got 'many'"),
    ({"n_nodes": float("inf")}, "Graph nodes must be a whole number, got inf"),
    ({"start": float("nan")}, "Start frame must be a whole number, got nan"),
    ({"frames": 2.5}, "Frames must be a whole number, got 2.5"),
    ({"every": 0}, "step (0) >= 1"),
    ({"start": -1}, "start (-1) and frames (0) must be >= 0"),
])
def test_bad_fields_are_named(tmp_path, clip, fields, words):
    status = _status_of_run(_handlers(tmp_path), clip, **fields)[5]
    assert status.startswith("**Error:**") and words in status, status


def test_run_then_ask(tmp_path, clip):
    h = _handlers(tmp_path)
    progress = []
    video, rows, zip_path, summary_path, seg, status = h.run(
        clip, 400, 0, 0, 1, progress=lambda value, **k: progress.append(value))
    assert "MotionBits in the last frame" in status
    assert progress[0] == (0, 6) and progress[-1] == (6, 6)
    import av

    with av.open(video) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name == "h264" and stream.frames == 6
    summary = json.loads(open(summary_path).read())
    assert [r[1] for r in rows] == [m["id"] for m in summary["motionbits"]]
    with zipfile.ZipFile(zip_path) as zf:
        assert zf.namelist() == [f"{i:05d}.png" for i in range(6)]
        last = np.asarray(Image.open(zf.open("00005.png")))
    assert np.array_equal(last, seg.label_maps[-1])

    answer, image, cited = h.ask(seg, "Which body is largest?")
    largest = summary["motionbits"][0]
    assert f"[{largest['mark']}]" in answer and f"(id {largest['id']})" in cited
    inside = seg.label_maps[-1] == largest["id"]
    assert np.array_equal(image[inside], highlight(seg, [largest["id"]])[inside])
    assert image[~inside].mean() < 0.5 * seg.frames[-1][~inside].mean()  # the rest is dimmed
    # ids that are in no label map (beyond int32 too) mark nothing
    assert np.array_equal(highlight(seg, [2**40, -1]), highlight(seg, []))

    assert h.ask(None, "hi")[2].startswith("**Error:** run the segmentation first")
    assert h.ask(seg, " ")[2].startswith("**Error:** type a question")
    assert h.ask(seg, 5)[2] == "**Error:** the question must be text, got int 5"


@pytest.mark.parametrize("vlm, words", [
    ("qwen2.5-vl:/no/such/model", "could not load the VLM"),
    ("openai:http://127.0.0.1:9/v1@m", "did not answer"),
])
def test_vlm_failures_are_messages(tmp_path, clip, vlm, words):
    h = _handlers(tmp_path, vlm=vlm)
    seg = h.run(clip, 100, 0, 3, 1, progress=lambda *a, **k: None)[4]
    answer, image, status = h.ask(seg, "What moved?")
    assert answer == "" and image is None
    assert status.startswith("**Error:**") and words in status and "\n" not in status, status
