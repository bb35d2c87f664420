"""vlm_adapters without torch: import cost, frames, StubVLM, phrase parsing, label maps, the method."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import vlm_adapters as va
from vlm_adapters import (
    MOVED_OBJECTS_PROMPT,
    PAPER_QUESTION,
    Detections,
    StubVLM,
    TextGrounder,
    VLMAdapter,
    extract_noun_phrases,
    make_vlm_yoloe_method,
    masks_to_label_map,
    phrases_from_answer,
)
from vlm_adapters.base import MissingDependencyError, check_local_path, require, sample_frames, to_rgb_frames


def test_import_is_cheap_and_lazy():
    code = (
        "import sys, vlm_adapters as v\n"
        "heavy = [m for m in ('torch', 'transformers', 'ultralytics', 'PIL', 'somprompt', "
        "'motionbits.segmenter', 'cv2') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
        "for n in v.__all__: getattr(v, n)\n"  # every public name resolves...
        "heavy = [m for m in ('torch', 'transformers', 'ultralytics') if m in sys.modules]\n"
        "assert not heavy, heavy\n"  # ...still without torch
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_public_names_and_protocol():
    assert set(va.__all__) <= set(dir(va))
    with pytest.raises(AttributeError):
        va.NoSuchThing  # noqa: B018
    assert isinstance(StubVLM("x"), VLMAdapter)
    assert isinstance(va.OpenAICompatibleVLM("http://localhost:1/v1", "m"), VLMAdapter)


def test_frames_normalisation():
    from PIL import Image

    rgb = np.zeros((4, 5, 3), np.uint8)
    rgb[..., 0] = 200
    out = to_rgb_frames([rgb, Image.fromarray(rgb).convert("RGBA"), rgb[..., 0], np.dstack([rgb, rgb[..., :1]])])
    assert all(f.shape == (4, 5, 3) and f.dtype == np.uint8 for f in out)
    assert all(int(f[0, 0, 0]) == 200 for f in out)
    # one frame policy everywhere (motionbits.as_rgb_array): floats are refused, not guessed at
    with pytest.raises(TypeError, match="uint8"):
        to_rgb_frames([rgb.astype(np.float32) / 255.0])
    assert len(to_rgb_frames(np.zeros((3, 4, 5, 3), np.uint8))) == 3
    with pytest.raises(ValueError, match="empty"):
        to_rgb_frames([])
    with pytest.raises(ValueError, match="RGB"):
        to_rgb_frames([np.zeros((4, 5, 2), np.uint8)])


def test_sample_frames_keeps_the_last():
    frames = list(range(20))
    picked = sample_frames(frames, 5)
    assert len(picked) == 5 and picked[0] == 0 and picked[-1] == 19
    assert sample_frames(frames, None) == frames and sample_frames(frames, 50) == frames
    # the docstring's promise holds for one frame too, as in somprompt
    from somprompt import sample_frame_indices

    assert sample_frames(range(10), 1) == [9] == sample_frame_indices(10, 1)
    for n in range(1, 12):
        assert sample_frames(list(range(10)), n) == sample_frame_indices(10, n)


def test_missing_extra_message(monkeypatch):
    monkeypatch.setitem(sys.modules, "transformers", None)  # makes `import transformers` fail
    with pytest.raises(MissingDependencyError, match=r'pip install "motionbits\[vlm\]"'):
        require("transformers", "vlm", "Qwen2_5_VLAdapter")
    with pytest.raises(MissingDependencyError, match="Qwen2_5_VLAdapter"):
        va.Qwen2_5_VLAdapter.from_pretrained("Qwen/Qwen2.5-VL-7B-Instruct")


def test_missing_ultralytics_names_the_yoloe_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "ultralytics", None)
    with pytest.raises(MissingDependencyError, match=r"motionbits\[yoloe\]"):
        va.YOLOEGrounder.from_pretrained("yoloe-11l-seg.pt")


def test_check_local_path(tmp_path):
    assert check_local_path("Qwen/Qwen2.5-VL-7B-Instruct") == "Qwen/Qwen2.5-VL-7B-Instruct"  # hub id passes
    assert check_local_path(str(tmp_path)) == str(tmp_path)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        check_local_path(str(tmp_path / "missing"))
    with pytest.raises(FileNotFoundError):
        check_local_path("./models/nothing-here")


def test_stub_vlm_scripts_and_records():
    vlm = StubVLM(["first", "second"])
    frames = [np.zeros((6, 8, 3), np.uint8)] * 3
    assert vlm.generate(frames, "q1") == "first"
    assert vlm.generate(frames[:1], "q2", system="s") == "second"
    assert vlm.generate(frames, "q3") == "first"  # cycles
    assert [(c.num_frames, c.frame_size, c.prompt, c.system) for c in vlm.calls[:2]] == [
        (3, (6, 8), "q1", None), (1, (6, 8), "q2", "s")]
    assert StubVLM(lambda fr, p: f"{len(fr)}:{p}").generate_batch([frames, frames[:2]], "q") == ["3:q", "2:q"]
    with pytest.raises(TypeError, match="script returned NoneType, not str"):  # not the answer "None"
        StubVLM(lambda fr, p: None).generate(frames, "q")
    with pytest.raises(TypeError, match="responses must be strings, got NoneType"):
        StubVLM(["fine", None])
    once = StubVLM(["only"], cycle=False)
    once.generate(frames, "q")
    with pytest.raises(IndexError):
        once.generate(frames, "q")


# --------------------------------------------------------------------------- phrases


def test_prompt_is_the_one_template():
    from somprompt import load_prompt

    assert MOVED_OBJECTS_PROMPT.startswith(PAPER_QUESTION)
    assert MOVED_OBJECTS_PROMPT == load_prompt("moved_rigid_bodies")
    assert "- <name>: <description>" in MOVED_OBJECTS_PROMPT


def test_one_parser_formats():
    from somprompt import parse_named_objects

    answer = (
        "Here is what moved:\n"
        "- Red block: a small cube pushed by the gripper\n"
        "* **Laptop lid** - rotates about its hinge\n"
        "2. the drawer: slides outwards\n"
        "- red block: duplicate line\n"
        "Some closing remark without the format."
    )
    mentions = parse_named_objects(answer)
    assert [m.name for m in mentions] == ["red block", "laptop lid", "drawer"]
    assert mentions[0].description == "a small cube pushed by the gripper"
    assert parse_named_objects("no list here") == []
    # the VLM -> YOLOE path reads the same names as the set-of-mark parser
    assert phrases_from_answer(answer) == ["red block", "laptop lid", "drawer"]
    marked = "- [2] The Laptop lid: hinge\n- [1][3] **red block** - pushed"
    assert phrases_from_answer(marked) == [o.name for o in parse_named_objects(marked)] == ["laptop lid", "red block"]


def test_free_text_fallback_and_none():
    assert extract_noun_phrases("The red block slid left and the drawer opened.") == ["red block", "drawer"]
    text = "In the video, a robot arm pushes the wooden cube toward the blue bowl."
    assert phrases_from_answer(text) == ["robot arm", "wooden cube", "blue bowl"]
    assert phrases_from_answer("- none: nothing moved") == []
    assert phrases_from_answer("- a: x\n- b: y\n- c: z", max_phrases=2) == ["a", "b"]
    # a lone surrogate (free text or list) is replaced before it reaches the detector's encoder
    assert phrases_from_answer("- red \ud800block: slid") == ["red \ufffdblock"]
    assert phrases_from_answer("The red \ud800block slid left.") == ["red block"]


# --------------------------------------------------------------------------- label maps


def _box(h, w, y0, y1, x0, x1):
    m = np.zeros((h, w), bool)
    m[y0:y1, x0:x1] = True
    return m


def test_masks_to_label_map_order_and_overlap():
    h, w = 10, 12
    masks = np.stack([_box(h, w, 0, 5, 0, 6), _box(h, w, 3, 8, 4, 10), _box(h, w, 8, 10, 0, 2)])
    labels = masks_to_label_map(masks, np.array([0.5, 0.9, 0.7]))
    assert labels.dtype == np.int32 and labels.shape == (h, w)
    assert set(np.unique(labels)) == {0, 1, 2, 3}
    assert (labels[masks[1]] == 1).all()  # best score -> label 1, wins the overlap
    assert (labels[masks[2]] == 2).all()
    assert (labels[masks[0] & ~masks[1]] == 3).all()
    # an instance fully hidden by a better one is dropped; labels stay 1..K without gaps
    hidden = np.stack([_box(h, w, 0, 4, 0, 4), _box(h, w, 1, 3, 1, 3)])
    assert set(np.unique(masks_to_label_map(hidden, [0.9, 0.1]))) == {0, 1}
    assert masks_to_label_map(masks, [0.5, 0.9, 0.7], max_instances=1).max() == 1
    assert masks_to_label_map(np.zeros((0, 4, 5), bool)).shape == (4, 5)
    for scores in ([0.9], [0.5, 0.9, 0.7, 0.1], [[0.5, 0.9, 0.7]]):  # not one score per mask
        with pytest.raises(ValueError, match="3 masks but scores of shape"):
            masks_to_label_map(masks, scores)


class _BoxDetector:
    """Stub PhraseDetector: each known phrase has a fixed box and score."""

    def __init__(self, boxes):
        self.boxes = boxes  # phrase -> (y0, y1, x0, x1, score)
        self.seen: list[list[str]] = []

    def detect(self, image, phrases):
        self.seen.append(list(phrases))
        h, w = image.shape[:2]
        hits = [p for p in phrases if p in self.boxes]
        masks = [_box(h, w, *self.boxes[p][:4]) for p in hits]
        return Detections(np.stack(masks) if masks else np.zeros((0, h, w), bool),
                          [self.boxes[p][4] for p in hits], hits)


def test_text_grounder_with_stub_detector_places_labels_exactly():
    det = _BoxDetector({"red block": (2, 6, 2, 8, 0.6), "drawer": (10, 20, 5, 25, 0.9)})
    grounder = TextGrounder(det)
    image = np.zeros((24, 32, 3), np.uint8)
    labels = grounder.ground("- red block: cube\n- drawer: slides\n- ghost: not detectable", image)
    assert det.seen == [["red block", "drawer", "ghost"]]
    expected = np.zeros((24, 32), np.int32)
    expected[10:20, 5:25] = 1  # drawer: higher score -> 1
    expected[2:6, 2:8] = 2
    np.testing.assert_array_equal(labels, expected)
    assert grounder.ground("- none: nothing moved", image).max() == 0
    assert det.seen[-1] == ["red block", "drawer", "ghost"]  # no detector call for an empty list
    # a detector's wrong result is an error, not a label map of another size
    grounder.detector.detect = lambda image, phrases: Detections(np.ones((1, 48, 64), bool), [0.9], ["x"])
    with pytest.raises(ValueError, match="returned masks of 64x48 for an image of 32x24"):
        grounder.ground("- red block: cube", image)
    grounder.detector.detect = lambda image, phrases: None
    with pytest.raises(TypeError, match="_BoxDetector.detect must return Detections, got NoneType"):
        grounder.ground("- red block: cube", image)


def test_vlm_yoloe_method_end_to_end_with_stubs():
    vlm = StubVLM("- red block: the cube that slid")
    det = _BoxDetector({"red block": (1, 4, 1, 5, 0.8)})
    method = make_vlm_yoloe_method(vlm, TextGrounder(det), num_frames=4)
    video = np.zeros((10, 8, 9, 3), np.uint8)
    video[-1, 0, 0] = 255  # mark the final frame
    labels = method(video)
    assert labels.shape == (8, 9) and labels.dtype == np.int32
    assert labels[1:4, 1:5].min() == 1 and labels.sum() == 12
    assert vlm.calls[0].num_frames == 4 and vlm.calls[0].prompt == MOVED_OBJECTS_PROMPT
    assert method.last_phrases == ["red block"] and method.name == "stub+yoloe"


def test_internvideo25_needs_explicit_trust_remote_code():
    with pytest.raises(ValueError, match="trust_remote_code=True"):
        va.InternVideo25Adapter.from_pretrained("OpenGVLab/InternVideo2_5_Chat_8B")
