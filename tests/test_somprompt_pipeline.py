"""GroundedVQA end to end with a stub segmenter and the scripted VLM."""

import numpy as np
import pytest
from PIL import Image

from somprompt import GroundedVQA, GroundedVQAResult, PromptError, SetOfMarkRenderer, load_prompt
from somprompt.testing import FixedSegmenter
from vlm_adapters import StubVLM as ScriptedVLM  # the one scripted VLM of the toolkit


def clip(T=10, h=120, w=160):
    rng = np.random.default_rng(3)
    frames, maps = [], []
    for t in range(T):
        frames.append(rng.integers(0, 256, (h, w, 3), dtype=np.uint8))
        lm = np.zeros((h, w), np.int32)
        lm[20:60, 10 + 3 * t:50 + 3 * t] = 21  # a block sliding right
        lm[70:110, 90:130] = 5  # a lid
        maps.append(lm)
    return frames, maps


class ThresholdSegmenter:
    """A toy segmenter that computes something: bright pixels are object 1."""

    def __call__(self, frames):
        return [(f.mean(axis=2) > 200).astype(np.int32) for f in frames]


def test_end_to_end_with_every_intermediate():
    frames, maps = clip()
    seg = FixedSegmenter(maps)
    vlm = ScriptedVLM("The lid [1] stayed closed while the wooden block [2] was pushed to the right. "
                      "There were 3 objects on the table; mark [7] is not visible.")
    vqa = GroundedVQA(seg, vlm, max_side=80, num_frames=4, generation={"max_new_tokens": 64})
    result = vqa(frames, question="Which object was pushed?")
    assert isinstance(result, GroundedVQAResult)
    assert seg.calls == 1 and len(vlm.calls) == 1
    call = vlm.calls[0]
    # the VLM saw the marked frames, at its size, with the rendered prompt and system prompt
    assert call.frames is not result.marked_frames and len(call.frames) == 4
    assert all(f.shape == (60, 80, 3) for f in call.frames)
    assert call.prompt == result.prompt and call.system == result.system
    assert call.gen["max_new_tokens"] == 64
    assert "Which object was pushed?" in result.prompt and "[1], [2]" in result.prompt
    assert result.prompt == load_prompt("som_vqa", num_marks=2, mark_list="[1], [2]",
                                        question="Which object was pushed?", cite_example="[1]")
    assert "[1]" in result.system
    # numbering: both present in frame 0, ascending id -> 5 is [1], 21 is [2]
    assert result.registry.number(5) == 1 and result.registry.number(21) == 2
    assert result.frame_indices == [0, 3, 6, 9]
    assert len(result.label_maps) == 10 and result.label_maps[0].shape == (120, 160)
    # the answer mapped back: order of mention, unknown mark reported, full-res masks of the last frame
    assert result.cited_ids == [5, 21]
    assert result.parsed.unknown == ["7"]
    assert np.array_equal(result.masks[21], maps[-1] == 21)
    assert sorted(result.marks) == [5, 21]
    # the marked frames differ from the (resized) input only around the masks
    assert not np.array_equal(result.marked_frames[0], result.frames[0][::2, ::2])


def test_real_computation_segmenter_and_pil_frames_and_templates_with_extra_vars():
    frames = []
    for t in range(5):
        f = np.zeros((64, 64, 3), np.uint8)
        f[10:30, 5 + 4 * t:25 + 4 * t] = 255
        frames.append(Image.fromarray(f))
    vlm = ScriptedVLM(lambda frames, prompt: "[1]" if "tower" in prompt else "none")
    vqa = GroundedVQA(ThresholdSegmenter(), vlm, prompt="som_grasp_first", system_prompt=None,
                      num_frames=None, max_side=None)
    result = vqa(frames, task="build a tower")
    assert result.system is None and vlm.calls[0].system is None
    assert len(result.marked_frames) == 5
    assert result.cited_ids == [1]
    assert result.masks[1].sum() == 400


def test_precomputed_label_maps_skip_the_segmenter_and_letters_work():
    frames, maps = clip(T=3)
    seg = FixedSegmenter(maps)
    vqa = GroundedVQA(seg, ScriptedVLM("[b] then [a]"), style="letter", prompt="som_interacted")
    result = vqa(np.stack(frames), label_maps=maps)
    assert seg.calls == 0
    assert "[a], [b]" in result.prompt
    assert result.cited_ids == [21, 5]


def test_an_answer_with_a_lone_surrogate_comes_back_encodable():
    """The VLM's text is returned after repair_text: a lone surrogate (here from a JSON
    escape) would crash whoever writes the answer as UTF-8 or JSON."""
    import json

    frames, maps = clip(T=3)
    answer = json.loads('"The block [1] moved \\ud800 and [2] stayed."')
    result = GroundedVQA(FixedSegmenter(maps), ScriptedVLM(answer))(frames, question="What moved?")
    assert result.answer == "The block [1] moved \ufffd and [2] stayed." == result.parsed.answer
    assert result.cited_ids == [result.registry.id_for_text("1"), result.registry.id_for_text("2")]
    json.dumps({"answer": result.answer}, ensure_ascii=False).encode("utf-8")


def test_pipeline_errors_are_clear():
    frames, maps = clip(T=3)
    vlm = ScriptedVLM("[1]")
    with pytest.raises(PromptError, match="unknown prompt template"):
        GroundedVQA(FixedSegmenter(maps), vlm, prompt="no_such_prompt")
    with pytest.raises(TypeError, match="generate"):
        GroundedVQA(FixedSegmenter(maps), object())
    with pytest.raises(TypeError, match="callable"):
        GroundedVQA("segmenter", vlm)
    vqa = GroundedVQA(FixedSegmenter(maps), vlm)
    with pytest.raises(ValueError, match="needs a question"):
        vqa(frames)
    with pytest.raises(ValueError, match="2 label maps for 3 frames"):
        vqa(frames, "q?", label_maps=maps[:2])
    with pytest.raises(ValueError, match="label map 1 has size"):
        vqa(frames, "q?", label_maps=[maps[0], maps[1][:50], maps[2]])
    with pytest.raises(TypeError, match="uint8"):
        vqa([f.astype(np.float32) for f in frames], "q?")
    with pytest.raises(FileNotFoundError, match="video.mp4"):
        vqa("video.mp4", "q?")
    with pytest.raises(TypeError, match="list of"):
        vqa(b"video.mp4", "q?")
    with pytest.raises(ValueError, match="takes no question"):
        GroundedVQA(FixedSegmenter(maps), vlm, prompt="som_interacted")(frames, "q?")
    with pytest.raises(PromptError, match="needs variable.*task"):
        GroundedVQA(FixedSegmenter(maps), vlm, prompt="som_grasp_first")(frames)
    with pytest.raises(TypeError, match="returned NoneType"):
        GroundedVQA(lambda fr: None, vlm)(frames, "q?")

    class SilentVLM:
        def generate(self, frames, prompt, system=None, **gen):
            return None

    with pytest.raises(TypeError, match="SilentVLM.generate must return"):
        GroundedVQA(FixedSegmenter(maps), SilentVLM())(frames, "q?")


def test_custom_renderer_is_used():
    frames, maps = clip(T=2)
    vqa = GroundedVQA(FixedSegmenter(maps), ScriptedVLM("x"), renderer=SetOfMarkRenderer(mode="mask"),
                      max_side=None)
    result = vqa(frames, "q?")
    bg = maps[0] == 0
    assert np.array_equal(result.marked_frames[0][bg], frames[0][bg])


def test_scripted_vlm_runs_out():
    frame = [np.zeros((8, 8, 3), np.uint8)]
    vlm = ScriptedVLM(["a"], cycle=False)
    vlm.generate(frame, "p")
    with pytest.raises(IndexError, match="after 1 calls"):
        vlm.generate(frame, "p")
