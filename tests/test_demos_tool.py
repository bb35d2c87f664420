"""The agent tool (demos.tool): JSON contents checked against the masks and the generated
clip's known motions, argument checks, the OpenAI schema, and the VLM choice."""

from __future__ import annotations

import inspect
import json

import numpy as np
import pytest

pytest.importorskip("av")
pytest.importorskip("pycocotools")

from pycocotools import mask as coco_mask  # noqa: E402

from demos import VLMError, ask_about_motion, make_vlm, openai_tools, segment_moving_bodies  # noqa: E402
from demos.vlm import check_vlm_spec  # noqa: E402
from demos.media import write_demo_clip  # noqa: E402
from demos.segmentation import MAX_NODES, segment_window  # noqa: E402
from demos.tool import answer_question  # noqa: E402
from motionbits import grasp_from_mask  # noqa: E402
from motionbits.video_writer import write_h264  # noqa: E402

N_FRAMES, SIZE, NODES = 8, (240, 320), 900


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> str:
    return str(write_demo_clip(tmp_path_factory.mktemp("tool") / "clip.mp4", n_frames=N_FRAMES, size=SIZE))


@pytest.fixture(scope="module")
def result(clip, tmp_path_factory) -> dict:
    marked = tmp_path_factory.mktemp("marked") / "marked.png"
    return segment_moving_bodies(clip, n_nodes=NODES, marked_image=marked)


def test_result_is_json_and_masks_agree(result):
    again = json.loads(json.dumps(result))
    assert again == result
    assert result["frame_indices"] == list(range(N_FRAMES)) and result["size"] == list(SIZE)
    bodies = result["motionbits"]
    assert len(bodies) >= 4
    for b in bodies:
        m = coco_mask.decode({"size": b["mask"]["size"], "counts": b["mask"]["counts"].encode()}).astype(bool)
        g = grasp_from_mask(m)
        assert m.sum() == b["area"]
        assert b["grasp"]["center"] == pytest.approx(list(g.centroid), abs=0.01)
        assert b["grasp"]["angle"] == pytest.approx(g.angle, abs=1e-4)
        assert b["grasp"]["width"] == pytest.approx(g.width, abs=0.01)
        # the closing direction is perpendicular to the major axis
        assert abs(np.dot(b["principal_axes"]["major"], b["principal_axes"]["minor"])) < 1e-3
    assert [b["area"] for b in bodies] == sorted((b["area"] for b in bodies), reverse=True)
    assert result["marked_image"].endswith("marked.png")


def test_twist_of_the_translating_quad(result):
    """demo_clip's quad translates by (-2.5, 1.5) px/frame at 640x480, i.e. (-1.25, 0.75) here."""
    start = np.array([470.0, 105.0]) * 0.5  # its centre at frame 0, scaled to 320x240
    expected = start + (N_FRAMES - 1) * np.array([-1.25, 0.75])
    quad = min(result["motionbits"], key=lambda b: np.hypot(*(np.array(b["centroid"]) - expected)))
    assert np.hypot(*(np.array(quad["centroid"]) - expected)) < 6
    assert quad["twist"]["vx"] == pytest.approx(-1.25, abs=0.35)
    assert quad["twist"]["vy"] == pytest.approx(0.75, abs=0.35)
    assert abs(quad["twist"]["omega"]) < 0.01
    # it moves in every frame: once found, it is reported moving up to the last frame
    moved = quad["moved_frames"]
    assert len(moved) >= N_FRAMES - 3 and moved == list(range(moved[0], N_FRAMES))


@pytest.mark.parametrize("kwargs, words", [
    ({"every": 0}, "every must be >= 1"),
    ({"frames": 1}, "frames must be >= 2"),
    ({"n_nodes": "many"}, "n_nodes must be an integer"),
    ({"n_nodes": 1_000_000}, "n_nodes must be <= 40000"),  # would run out of memory
    ({"start": 100}, "need at least 2 frames"),
    ({"marked_image": "/nonexistent/dir/x.png"}, "does not exist"),
    ({"marked_image": "x.gif"}, "must end in .png or .jpg"),
])
def test_bad_arguments(clip, kwargs, words):
    with pytest.raises((ValueError, FileNotFoundError), match=words):
        segment_moving_bodies(clip, **{"n_nodes": 100, "frames": 2, **kwargs})


@pytest.mark.parametrize("marked, words", [
    (123, "marked_image must be a .png or .jpg path, got 123"),
    ("", "marked_image must be a .png or .jpg path, got ''"),
    (["x.png"], "marked_image must be a .png or .jpg path"),
    ("x.gif", "must end in .png or .jpg"),
])
def test_bad_marked_image_is_refused_before_segmenting(clip, monkeypatch, marked, words):
    monkeypatch.setattr("demos.tool.segment_window", lambda *a, **k: pytest.fail("segmented first"))
    with pytest.raises(ValueError, match=words):
        segment_moving_bodies(clip, marked_image=marked)


def test_unwritable_marked_image(clip, tmp_path):
    (tmp_path / "x.png").mkdir()  # a folder where the image should go
    with pytest.raises(ValueError, match="could not write marked_image .*x.png"):
        segment_moving_bodies(clip, n_nodes=100, frames=2, marked_image=tmp_path / "x.png")


def test_bad_videos(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not a video")
    with pytest.raises(ValueError, match="could not open"):
        segment_moving_bodies(str(text))
    with pytest.raises(FileNotFoundError, match="not found"):
        segment_moving_bodies(str(tmp_path / "missing.mp4"))
    one = write_h264([np.full((64, 64, 3), 90, np.uint8)], tmp_path / "one.mp4")
    with pytest.raises(ValueError, match="at least 2 frames"):
        segment_moving_bodies(str(one))
    with pytest.raises(ValueError, match="question must be a non-empty"):
        ask_about_motion(str(one), "  ")


def test_thin_video_says_its_smallest_size(tmp_path, monkeypatch):
    """The segmenter's 'crop it or raise max_side' is for library users: a tool user can
    only change the video, so the message gives the size it needs, before segmenting."""
    import demos.segmentation
    from PIL import Image

    class Refuses:
        def __init__(self, *a, **k):
            pass

        def update(self, frame):
            pytest.fail("segmented a frame that is too thin")

    monkeypatch.setattr(demos.segmentation, "MotionBitsSegmenter", Refuses)
    for i in range(2):
        Image.fromarray(np.full((8, 1000, 3), 60 * i, np.uint8)).save(tmp_path / f"{i}.png")
    with pytest.raises(ValueError) as err:
        segment_moving_bodies(str(tmp_path), n_nodes=100)
    assert str(err.value) == ("the video's frames are 1000x8, too thin to segment: with a longer side of "
                              "1000 px the shorter side must be at least 31 px; crop the video to a less "
                              "elongated region")


def test_large_frames_are_refused_before_decoding(tmp_path, monkeypatch):
    """Frames over MAX_VIDEO_SIDE are refused from a video file's header, before any frame
    is decoded, and in a folder of images once the first one is (whatever ``start``); not
    after decoding the window at full size."""
    import demos.segmentation
    from PIL import Image

    decoded = []

    def counting(path):
        for frame in iter_frames(path):
            decoded.append(frame.shape)
            yield frame

    from motionbits import iter_frames
    monkeypatch.setattr(demos.segmentation, "iter_frames", counting)
    for i in range(4):
        Image.fromarray(np.full((100, 2000, 3), 60 * i, np.uint8)).save(tmp_path / f"{i}.png")
    for start in (0, 2):
        decoded.clear()
        with pytest.raises(ValueError) as err:
            segment_moving_bodies(str(tmp_path), start=start, frames=2, n_nodes=100)
        assert str(err.value).startswith("the video's frames are 2000x100, over the limit of 1920 px on the "
                                         "longer side (the segmenter works at 640 px anyway); downscale it")
        assert decoded == [(100, 2000, 3)]
    wide = write_h264([np.full((100, 2000, 3), 60 * i, np.uint8) for i in range(2)], tmp_path / "wide.mp4")
    decoded.clear()
    with pytest.raises(ValueError, match="frames are 2000x100, over the limit of 1920 px"):
        ask_about_motion(str(wide), "What moved?", n_nodes=100)
    assert decoded == []


def test_min_short_side_is_the_segmenters_limit():
    """``min_short_side`` (the size the demos' message names) is exactly where the
    segmenter starts accepting frames."""
    from motionbits import MotionBitsConfig, MotionBitsSegmenter
    from motionbits.segmenter import min_short_side

    for long_side, max_side in [(4000, 640), (1000, 640), (300, 640), (900, 160)]:
        need = min_short_side(long_side, max_side)
        config = MotionBitsConfig(n_nodes=100, max_side=max_side)
        with pytest.raises(ValueError, match="raise max_side"):  # the core's message, unchanged
            MotionBitsSegmenter(config).update(np.zeros((need - 1, long_side, 3), np.uint8))
        MotionBitsSegmenter(config).update(np.zeros((need, long_side, 3), np.uint8))


def test_folder_of_mixed_sizes(tmp_path):
    from PIL import Image

    for i, (h, w) in enumerate([(64, 64), (64, 64), (48, 80)]):
        Image.fromarray(np.full((h, w, 3), 40 * i, np.uint8)).save(tmp_path / f"{i}.png")
    with pytest.raises(ValueError, match="frame 2 is 80x48 but frame 0 is 64x64: all frames .* same size"):
        segment_moving_bodies(str(tmp_path), n_nodes=100)
    assert segment_moving_bodies(str(tmp_path), frames=2, n_nodes=100)["frame_indices"] == [0, 1]


def test_openai_schema_matches_the_functions():
    tools = {t["function"]["name"]: t["function"] for t in openai_tools()}
    for fn in (segment_moving_bodies, ask_about_motion):
        params = inspect.signature(fn).parameters
        schema = tools[fn.__name__]["parameters"]
        assert set(schema["properties"]) == set(params) - {"vlm"}  # the VLM is the server's choice
        assert set(schema["required"]) == {n for n, p in params.items() if p.default is p.empty}
        assert schema["properties"]["n_nodes"]["maximum"] == MAX_NODES
        for name, prop in schema["properties"].items():
            if "default" in prop:
                assert prop["default"] == params[name].default, name


def test_check_vlm_spec_loads_nothing(tmp_path):
    for ok in ["stub", " STUB ", "", "stub:some text", "openai:http://localhost:8000/v1@m"]:
        check_vlm_spec(ok)  # no error, nothing loaded, nothing contacted
    for bad, words in [("nonsense", "cannot read VLM spec"), (5, "a VLM spec is a string"),
                       (str(tmp_path), "not a transformers model folder"),
                       ("qwen2.5-vl:" + str(tmp_path / "no-such-model"), "could not load"),
                       ("openai:localhost@m", "must start with http")]:
        with pytest.raises(VLMError, match=words):
            check_vlm_spec(bad)


def test_internvideo25_loads_the_remote_code_of_a_local_folder(tmp_path, monkeypatch):
    """``internvideo2.5:FOLDER`` is offered by the demos, and that checkpoint exists only as
    remote code: naming the kind with a local folder is the opt-in, so it loads with
    ``trust_remote_code=True``; a hub id (code downloaded and run unread) is refused, at
    start too. Other kinds never get ``trust_remote_code``."""
    from vlm_adapters import InternVideo25Adapter, Qwen2_5_VLAdapter

    calls = []

    def record(cls, path, **kw):
        calls.append((cls.__name__, path, kw.get("trust_remote_code", False)))
        return "loaded"

    for cls in (InternVideo25Adapter, Qwen2_5_VLAdapter):
        monkeypatch.setattr(cls, "from_pretrained", classmethod(record))
    assert make_vlm(f"internvideo2.5:{tmp_path}") == "loaded"
    check_vlm_spec(f"internvideo2.5:{tmp_path}")
    assert make_vlm(f"qwen2.5-vl:{tmp_path}") == "loaded"
    assert calls == [("InternVideo25Adapter", str(tmp_path), True), ("Qwen2_5_VLAdapter", str(tmp_path), False)]
    for check in (make_vlm, check_vlm_spec):
        with pytest.raises(VLMError, match="run their own Python code, so give the local folder"):
            check("internvideo2.5:OpenGVLab/InternVideo2_5_Chat_8B")
    assert len(calls) == 2


def test_an_answer_with_a_lone_surrogate_is_returned_encodable(clip):
    """What the tool returns is written as UTF-8 JSON (the MCP server does): a lone
    surrogate in the VLM's text is replaced, not passed on to crash there."""
    seg = segment_window(clip, frames=3, n_nodes=100)
    ans = answer_question(seg, "What moved?", "stub:It is [1] \ud800.")
    assert ans.answer == "It is [1] \ufffd."
    json.dumps({"answer": ans.answer}, ensure_ascii=False).encode("utf-8")


def test_vlm_choice_errors(tmp_path, clip):
    with pytest.raises(VLMError, match="could not load the VLM 'nonsense': cannot read VLM spec"):
        make_vlm("nonsense")
    with pytest.raises(VLMError, match="a VLM spec is a string"):
        make_vlm(5)
    assert make_vlm("  ").name == make_vlm(" STUB ").name == "stub"
    with pytest.raises(VLMError, match="not a transformers model folder"):
        make_vlm(str(tmp_path))
    with pytest.raises(VLMError, match="could not load"):
        make_vlm("qwen2.5-vl:" + str(tmp_path / "no-such-model"))
    seg = segment_window(clip, frames=3, n_nodes=100)
    down = make_vlm("openai:http://127.0.0.1:9/v1@some-model", timeout=5)  # nothing listens on port 9
    with pytest.raises(VLMError, match="did not answer"):
        answer_question(seg, "What moved?", down)
    scripted = answer_question(seg, "What moved?", "stub:Nothing, really.")
    assert scripted.answer == "Nothing, really." and scripted.cited_ids == []
    for fails, words in [(None, "it returned NoneType, not text"), ({"answer": "[1]"}, "returned dict"),
                         (ValueError("height:16 must be larger than factor:28"), "larger than factor"),
                         (KeyError("choices"), "'choices'")]:
        with pytest.raises(VLMError, match=f"the VLM did not answer: .*{words}"):
            answer_question(seg, "What moved?", _Scripted(fails))
    with pytest.raises(TypeError, match="vlm must be a VLM spec or have generate"):
        answer_question(seg, "What moved?", 5)


class _Scripted:
    """A VLM that returns, or raises, what it is given."""

    def __init__(self, out):
        self.out = out

    def generate(self, frames, prompt, system=None, **gen):
        if isinstance(self.out, Exception):
            raise self.out
        return self.out


def test_window_memory_limit(clip, monkeypatch):
    import demos.segmentation

    monkeypatch.setattr(demos.segmentation, "MAX_WINDOW_PIXELS", 3 * SIZE[0] * SIZE[1])
    with pytest.raises(ValueError, match="at most 3 frames of this size"):
        segment_moving_bodies(clip, frames=5, n_nodes=100)
    with pytest.raises(ValueError, match="more than 3 frames of 320x240"):
        segment_moving_bodies(clip, n_nodes=100)


def test_window_errors_come_before_segmenting(clip, monkeypatch):
    import demos.segmentation

    class Refuses:
        def __init__(self, config):
            pass

        def update(self, frame):
            pytest.fail("segmented before the window was checked")

    monkeypatch.setattr(demos.segmentation, "MotionBitsSegmenter", Refuses)
    monkeypatch.setattr(demos.segmentation, "MAX_WINDOW_PIXELS", 3 * SIZE[0] * SIZE[1])
    with pytest.raises(ValueError, match="more than 3 frames of 320x240"):
        segment_moving_bodies(clip, n_nodes=100)
    with pytest.raises(ValueError, match="found 1 from frame 7"):
        segment_moving_bodies(clip, start=7, n_nodes=100)
