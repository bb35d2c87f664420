"""The three packages as one toolkit: the README snippet, the shared object type and its
conversions, H.264 videos, `--config` and a run repeated from its summary.json."""

from __future__ import annotations

import json
import subprocess
import sys

import av
import cv2
import numpy as np
import pytest

import motionbits
from motionbits import (
    Instance,
    MotionBitsConfig,
    MotionBitsSegmenter,
    from_supervision,
    instances_from_labels,
    labels_from_instances,
    to_supervision,
)
from motionbits.cli import main
from motionbits.config_file import load_config
from motionbits.synth import demo_clip
from motionbits.video_writer import H264Writer, write_h264
from somprompt import GroundedVQA, MarkRegistry, write_mp4
from vlm_adapters import Detections, StubVLM

SMALL = MotionBitsConfig(n_nodes=900, max_side=240)  # finds 4 MotionBits on the clip below


@pytest.fixture(scope="module")
def clip():
    return demo_clip(n_frames=6, size=(120, 160))


@pytest.fixture(scope="module")
def clip_mp4(clip, tmp_path_factory):
    path = tmp_path_factory.mktemp("clip") / "clip.mp4"
    write_h264(clip.frames, path, fps=10)
    return path


def codec_of(path) -> tuple[str, str]:
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        return stream.codec_context.name, stream.codec_tag


# ------------------------------------------------------------------ the README snippet


def test_readme_snippet_segmenter_plugs_into_grounded_vqa(clip_mp4):
    vqa = GroundedVQA(MotionBitsSegmenter(SMALL), StubVLM("The mug [1] moved."))
    res = vqa(str(clip_mp4), question="Which object moved?")
    assert res.answer == "The mug [1] moved."
    # mark [1] is the first MotionBit to appear; its mask is that id's pixels on the last frame
    first = res.registry.ids[0]
    assert res.cited_ids == [first]
    assert set(res.masks) == {first}
    mask = res.masks[first]
    assert mask.dtype == bool and mask.shape == (120, 160) and mask.any()
    assert np.array_equal(mask, res.label_maps[-1] == first)
    # the labels are the segmenter's on the decoded video, frame for frame
    decoded = list(motionbits.iter_frames(str(clip_mp4)))
    expected = MotionBitsSegmenter(SMALL)(decoded)
    assert all(np.array_equal(a, b) for a, b in zip(res.label_maps, expected))
    [obj] = res.instances
    assert obj.id == first and obj.area == int(mask.sum())


def test_grounded_vqa_reads_a_folder_of_images(clip, tmp_path):
    from somprompt.testing import FixedSegmenter

    for i, frame in enumerate(clip.frames):
        cv2.imwrite(str(tmp_path / f"{i:05d}.png"), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    res = GroundedVQA(FixedSegmenter(clip.labels), StubVLM("[1]"))(str(tmp_path), question="?")
    assert all(np.array_equal(a, b) for a, b in zip(res.frames, clip.frames))
    assert np.array_equal(res.masks[res.cited_ids[0]], clip.labels[-1] == res.cited_ids[0])


def test_segmenter_call_starts_a_new_video_each_time(clip):
    seg = MotionBitsSegmenter(SMALL)
    a = seg(clip.frames)
    b = seg(np.stack(clip.frames))
    assert len(a) == len(clip.frames) and all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not a[0].any() and a[-1].any()  # the first frame is all background


# ------------------------------------------------------------------ one object type


def test_import_motionbits_is_light_and_every_name_resolves():
    code = (
        "import sys, motionbits\n"
        "heavy = [m for m in ('cv2', 'scipy', 'PIL', 'torch', 'motionbits.segmenter', 'somprompt') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
        "for n in motionbits.__all__: getattr(motionbits, n)\n"
        "assert motionbits.MotionBit is motionbits.Instance\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_label_map_instances_round_trip():
    labels = np.zeros((30, 40), np.int32)
    labels[2:10, 5:20] = 3
    labels[15:28, 30:38] = 9
    labels[20, 1] = 9
    objs = instances_from_labels(labels)
    assert [o.id for o in objs] == [3, 9]
    assert objs[0].bbox == (5, 2, 20, 10) and objs[0].area == 8 * 15
    assert objs[1].bbox == (1, 15, 38, 28) and objs[1].area == 13 * 8 + 1
    assert objs[0].centroid == (12.0, 5.5)
    assert np.array_equal(labels_from_instances(objs, labels.shape), labels)


@pytest.mark.filterwarnings("ignore:__array__ implementation:DeprecationWarning")  # inside pycocotools, numpy 2
def test_coco_rle_round_trip_and_json():
    pycocotools_mask = pytest.importorskip("pycocotools.mask")
    rng = np.random.default_rng(0)
    labels = rng.integers(0, 4, (33, 47)).astype(np.int32)
    objs = instances_from_labels(labels, rle=True)
    assert all(o.mask is None and o.rle["size"] == [33, 47] for o in objs)
    json.dumps([o.rle for o in objs])  # JSON-ready
    assert np.array_equal(labels_from_instances(objs, labels.shape), labels)
    # what pycocotools itself computes for the same mask
    m = labels == 2
    assert pycocotools_mask.area(pycocotools_mask.encode(np.asfortranarray(m.astype(np.uint8)))) == objs[1].area


def test_supervision_round_trip():
    pytest.importorskip("supervision")
    labels = np.zeros((20, 30), np.int32)
    labels[1:5, 2:9] = 4
    labels[10:18, 12:25] = 7
    objs = [Instance(o.id, o.bbox, o.area, o.centroid, mask=o.mask, score=0.25 * o.id / 4, name=f"obj{o.id}")
            for o in instances_from_labels(labels)]
    det = to_supervision(objs)
    assert det.tracker_id.tolist() == [4, 7]
    assert det.xyxy.tolist() == [[2, 1, 9, 5], [12, 10, 25, 18]]
    assert det.mask.shape == (2, 20, 30) and list(det.data["class_name"]) == ["obj4", "obj7"]
    back = from_supervision(det)
    assert back == objs  # id, box, area, centroid, score, name (masks are compared below)
    assert all(np.array_equal(a.mask, b.mask) for a, b in zip(back, objs))


def test_motionbits_result_and_detections_give_the_same_type(clip):
    seg = MotionBitsSegmenter(SMALL)
    for frame in clip.frames:
        result = seg.update(frame)
    objs = result.instances()
    assert [o.id for o in objs] == result.ids and objs
    for mb, obj in zip(result.motionbits, objs):
        assert isinstance(mb, Instance) and mb.mask is None and mb.twist is not None
        assert np.array_equal(obj.get_mask(), result.labels == mb.id)
        assert obj.area == int(obj.get_mask().sum()) and obj.first_moved <= obj.last_moved
    with pytest.raises(ValueError, match="no mask"):
        result.motionbits[0].get_mask()
    sv = pytest.importorskip("supervision")
    det = to_supervision(objs)
    assert det.data["twist"].shape == (len(objs), 3)
    back = from_supervision(det)
    np.testing.assert_allclose([o.twist for o in back], [o.twist for o in objs])
    drawn = sv.MaskAnnotator(color_lookup=sv.ColorLookup.TRACK).annotate(clip.frames[-1].copy(), det)
    assert not np.array_equal(drawn, clip.frames[-1])
    det = Detections(np.stack([result.labels == i for i in result.ids]), np.linspace(0.9, 0.5, len(result.ids)),
                     [f"body {i}" for i in result.ids])
    from_det = det.instances()
    assert [o.area for o in from_det] == [o.area for o in objs]
    assert [o.bbox for o in from_det] == [o.bbox for o in objs]
    assert from_det[0].name == f"body {result.ids[0]}" and from_det[0].score == pytest.approx(0.9)


# ------------------------------------------------------------------ browser-playable video


def test_mp4_is_h264_and_reads_back(tmp_path):
    frames = [np.full((31, 45, 3), 30 * t, np.uint8) for t in range(4)]
    path = write_mp4(frames, tmp_path / "marks.mp4", fps=5)
    assert codec_of(path) == ("h264", "avc1")
    with av.open(str(path)) as container:
        decoded = [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]
    assert len(decoded) == 4 and decoded[0].shape == (32, 46, 3)  # padded to even sizes
    assert abs(float(decoded[3][:31, :45].mean()) - 90.0) < 3.0
    with pytest.raises(ValueError, match="no frames"):
        write_h264([], tmp_path / "empty.mp4")
    with H264Writer(tmp_path / "two.mp4") as w, pytest.raises(ValueError, match="the video is 45x31"):
        w.write(frames[0])
        w.write(np.zeros((10, 10, 3), np.uint8))


# ------------------------------------------------------------------ config files and the CLI


def test_config_file_toml_json_and_errors(tmp_path):
    toml = tmp_path / "c.toml"
    toml.write_text('n_nodes = 2500\nexact = true\nflow = "dis-fast"\nmcl_inflation = 2\n')
    c = load_config(toml, max_side=320)
    assert (c.n_nodes, c.exact, c.flow, c.mcl_inflation, c.max_side) == (2500, True, "dis-fast", 2.0, 320)
    js = tmp_path / "c.json"
    js.write_text(json.dumps({"config": {"n_nodes": 400}, "frames": 3}))  # a summary.json
    assert load_config(js).n_nodes == 400
    for text, words in [('n_node = 3', "unknown MotionBitsConfig field.*n_node"),
                        ('n_nodes = "many"', "n_nodes must be int"),
                        ('exact = 1', "exact must be bool"),
                        ('n_nodes = 3', "n_nodes=3"),
                        ('n_nodes = ', "not valid TOML")]:
        toml.write_text(text)
        with pytest.raises(ValueError, match=words):
            load_config(toml)


def test_python_m_motionbits_is_the_cli():
    run = subprocess.run([sys.executable, "-m", "motionbits", "--help"], capture_output=True, text=True)
    assert run.returncode == 0 and "segment" in run.stdout and "usage: motionbits" in run.stdout
    # `bench` and `benchmark`: the help says at once which is which
    assert "SPEED of the segmenter" in run.stdout and "ACCURACY of methods" in run.stdout


def test_summary_reproduces_the_run(clip_mp4, tmp_path):
    (tmp_path / "c.toml").write_text("n_nodes = 900\nmax_side = 240\nmcl_inflation = 1.2\n")
    base = ["segment", str(clip_mp4), "--quiet"]
    assert main(base + ["--config", str(tmp_path / "c.toml"), "--out", str(tmp_path / "a")]) == 0
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["config"] == {**MotionBitsConfig().__dict__, "n_nodes": 900, "max_side": 240,
                                 "mcl_inflation": 1.2}
    assert summary["backend"] == "numpy" and summary["version"] == motionbits.__version__
    assert main(base + ["--config", str(tmp_path / "a" / "summary.json"), "--out", str(tmp_path / "b")]) == 0
    a = sorted((tmp_path / "a" / "labels").glob("*.png"))
    b = sorted((tmp_path / "b" / "labels").glob("*.png"))
    assert len(a) == len(b) == 6
    assert all(np.array_equal(cv2.imread(str(x), -1), cv2.imread(str(y), -1)) for x, y in zip(a, b))
    assert cv2.imread(str(a[-1]), -1).any()
    # the overlay: H.264, numbered as somprompt numbers the same label maps
    assert codec_of(tmp_path / "a" / "overlay.mp4") == ("h264", "avc1")
    registry = MarkRegistry.from_label_maps([cv2.imread(str(p), -1).astype(np.int32) for p in a])
    assert summary["marks"] == {str(i): registry.number(i) for i in registry.ids}
