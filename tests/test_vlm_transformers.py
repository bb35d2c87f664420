"""The transformers adapters on tiny random-weight checkpoints built here.

Each fixture builds a few-hundred-kilobyte model of the real architecture plus a byte-level
BPE tokenizer trained offline, writes model + processor with ``save_pretrained`` into a temp
folder, and the adapter loads that folder with ``from_pretrained`` exactly as it would load
a downloaded checkpoint. Answers are random text; the tests check the path: visual tokens in
the input, the right number of frames consumed by the vision tower, a string out.
"""
from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")
transformers = pytest.importorskip("transformers")
pytest.importorskip("tokenizers")

from vlm_adapters import InternVLAdapter, MissingDependencyError, Qwen2_5_VLAdapter, VideoLlama3Adapter  # noqa: E402

SPECIAL = [
    "<|endoftext|>", "<|im_start|>", "<|im_end|>", "<|vision_start|>", "<|vision_end|>",
    "<|image_pad|>", "<|video_pad|>", "<img>", "</img>", "<IMG_CONTEXT>", "<video>",
]
CORPUS = [
    "What rigid bodies or parts have moved in the video? Describe each in detail.",
    "- red block: a small cube that slid left\n- drawer: opened towards the camera",
    "Frame1: Time 0.0s: system user assistant",
]


def _tokenizer(**extra):
    from tokenizers import Tokenizer, decoders, models, pre_tokenizers, trainers
    from transformers import PreTrainedTokenizerFast

    tok = Tokenizer(models.BPE())
    tok.pre_tokenizer = pre_tokenizers.ByteLevel(add_prefix_space=False)
    tok.decoder = decoders.ByteLevel()
    trainer = trainers.BpeTrainer(
        vocab_size=400, special_tokens=SPECIAL, initial_alphabet=pre_tokenizers.ByteLevel.alphabet()
    )
    tok.train_from_iterator(CORPUS * 5, trainer)
    return PreTrainedTokenizerFast(tokenizer_object=tok, eos_token="<|im_end|>", pad_token="<|endoftext|>", **extra)


def _chat_template(image: str, video: str) -> str:
    """A ChatML template like the real checkpoints' (placeholders per model family)."""
    return (
        "{% for message in messages %}<|im_start|>{{ message['role'] }}\n"
        "{% if message['content'] is string %}{{ message['content'] }}{% else %}"
        "{% for c in message['content'] %}"
        "{% if c['type'] == 'image' %}" + image + "{% elif c['type'] == 'video' %}" + video +
        "{% elif c['type'] == 'text' %}{{ c['text'] }}{% endif %}{% endfor %}{% endif %}<|im_end|>\n"
        "{% endfor %}{% if add_generation_prompt %}<|im_start|>assistant\n{% endif %}"
    )


def _qwen2_text_config(tok) -> dict:
    return dict(
        model_type="qwen2", vocab_size=len(tok), hidden_size=32, intermediate_size=64, num_hidden_layers=2,
        num_attention_heads=4, num_key_value_heads=2, max_position_embeddings=2048,
        bos_token_id=tok.convert_tokens_to_ids("<|endoftext|>"), eos_token_id=tok.eos_token_id,
        pad_token_id=tok.pad_token_id,
    )


@pytest.fixture(scope="session")
def qwen_dir(tmp_path_factory):
    from transformers import (
        Qwen2_5_VLConfig, Qwen2_5_VLForConditionalGeneration, Qwen2_5_VLProcessor,
        Qwen2VLImageProcessor, Qwen2VLVideoProcessor,
    )

    tok = _tokenizer()
    pix = dict(min_pixels=28 * 28, max_pixels=56 * 56 * 4, patch_size=14, merge_size=2, temporal_patch_size=2)
    proc = Qwen2_5_VLProcessor(
        image_processor=Qwen2VLImageProcessor(**pix), video_processor=Qwen2VLVideoProcessor(**pix),
        tokenizer=tok, chat_template=_chat_template(
            "<|vision_start|><|image_pad|><|vision_end|>", "<|vision_start|><|video_pad|><|vision_end|>"),
    )
    text = _qwen2_text_config(tok)
    text.pop("model_type")
    text["rope_parameters"] = {"rope_type": "default", "rope_theta": 10000.0, "mrope_section": [1, 1, 2]}
    cfg = Qwen2_5_VLConfig(
        text_config=text,
        vision_config=dict(depth=2, hidden_size=32, intermediate_size=64, num_heads=4, out_hidden_size=32,
                           patch_size=14, spatial_merge_size=2, temporal_patch_size=2, window_size=56,
                           fullatt_block_indexes=[1]),
        image_token_id=tok.convert_tokens_to_ids("<|image_pad|>"),
        video_token_id=tok.convert_tokens_to_ids("<|video_pad|>"),
        vision_start_token_id=tok.convert_tokens_to_ids("<|vision_start|>"),
        vision_end_token_id=tok.convert_tokens_to_ids("<|vision_end|>"),
    )
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("tiny-qwen2.5-vl")
    Qwen2_5_VLForConditionalGeneration(cfg).save_pretrained(path)
    proc.save_pretrained(path)
    return path


@pytest.fixture(scope="session")
def videollama_dir(tmp_path_factory):
    from transformers import (
        VideoLlama3Config, VideoLlama3ForConditionalGeneration, VideoLlama3ImageProcessor,
        VideoLlama3Processor, VideoLlama3VideoProcessor,
    )

    tok = _tokenizer()
    proc = VideoLlama3Processor(
        image_processor=VideoLlama3ImageProcessor(min_pixels=28 * 28, max_pixels=56 * 56 * 4, patch_size=14, merge_size=1),
        video_processor=VideoLlama3VideoProcessor(min_pixels=28 * 28, max_pixels=56 * 56 * 4, patch_size=14, merge_size=2),
        tokenizer=tok, chat_template=_chat_template("<|image_pad|>", "<|video_pad|>"),
    )
    cfg = VideoLlama3Config(
        text_config=_qwen2_text_config(tok),
        vision_config=dict(hidden_size=32, intermediate_size=64, num_hidden_layers=2, num_attention_heads=4, patch_size=14),
        image_token_id=tok.convert_tokens_to_ids("<|image_pad|>"),
        video_token_id=tok.convert_tokens_to_ids("<|video_pad|>"),
    )
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("tiny-videollama3")
    VideoLlama3ForConditionalGeneration(cfg).save_pretrained(path)
    proc.save_pretrained(path)
    return path


@pytest.fixture(scope="session")
def internvl_dir(tmp_path_factory):
    from transformers import (
        GotOcr2ImageProcessor, InternVLConfig, InternVLForConditionalGeneration, InternVLProcessor,
        InternVLVideoProcessor,
    )

    tok = _tokenizer(extra_special_tokens={
        "start_image_token": "<img>", "end_image_token": "</img>",
        "context_image_token": "<IMG_CONTEXT>", "video_token": "<video>",
    })
    proc = InternVLProcessor(
        image_processor=GotOcr2ImageProcessor(size={"height": 28, "width": 28}, crop_to_patches=False),
        video_processor=InternVLVideoProcessor(size={"height": 28, "width": 28}),
        tokenizer=tok, image_seq_length=1, chat_template=_chat_template("<IMG_CONTEXT>\n", "<video>\n"),
    )
    cfg = InternVLConfig(
        text_config=_qwen2_text_config(tok),
        vision_config=dict(hidden_size=32, intermediate_size=64, num_hidden_layers=2, num_attention_heads=4,
                           image_size=[28, 28], patch_size=[14, 14]),
        image_token_id=tok.convert_tokens_to_ids("<IMG_CONTEXT>"), image_seq_length=1, downsample_ratio=0.5,
    )
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("tiny-internvl")
    InternVLForConditionalGeneration(cfg).save_pretrained(path)
    proc.save_pretrained(path)
    return path


def _marked_frames(n: int, h: int = 60, w: int = 80) -> list[np.ndarray]:
    """Frames with a numbered-mark look: a moving white square with a dark '1'-like bar."""
    frames = []
    for t in range(n):
        f = np.full((h, w, 3), 40, np.uint8)
        x = 5 + 6 * t
        f[20:40, x:x + 20] = 255
        f[25:35, x + 9:x + 11] = 0
        frames.append(f)
    return frames


class _Capture:
    """Forward hook that records the first positional/keyword tensor of each call."""

    def __init__(self, module):
        self.shapes: list[tuple[int, ...]] = []
        self.handle = module.register_forward_hook(self, with_kwargs=True)

    def __call__(self, module, args, kwargs, output):
        x = args[0] if args else next(v for v in kwargs.values() if torch.is_tensor(v))
        self.shapes.append(tuple(x.shape))

    def remove(self):
        self.handle.remove()


# ----------------------------------------------------------------------------- Qwen2.5-VL


@pytest.fixture(scope="session")
def qwen(qwen_dir):
    return Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir), device="cpu")


def test_qwen_video_path(qwen):
    frames = _marked_frames(4)
    inputs = qwen.prepare_inputs(frames, "What moved?")
    vp = qwen.processor.video_processor
    grid = inputs["video_grid_thw"]
    assert grid.shape == (1, 3)
    assert int(grid[0, 0]) * vp.temporal_patch_size == len(frames)  # every frame consumed
    n_video_tokens = int((inputs["input_ids"] == qwen.model.config.video_token_id).sum())
    assert n_video_tokens == int(grid.prod()) // vp.merge_size**2 > 0
    cap = _Capture(qwen.model.model.visual)
    try:
        answer = qwen.generate(frames, "What moved?", max_new_tokens=6)
    finally:
        cap.remove()
    assert isinstance(answer, str)
    assert cap.shapes and cap.shapes[0][0] == int(grid.prod())  # patches of all 4 frames reached the tower
    assert qwen.generate(frames, "What moved?", max_new_tokens=6) == answer  # greedy is deterministic


def test_qwen_images_path_and_system(qwen_dir):
    vlm = Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir), device="cpu", dtype="float32", frames_as="images")
    frames = _marked_frames(3)
    inputs = vlm.prepare_inputs(frames, "Which mark moved?", system="You are precise.")
    assert inputs["image_grid_thw"].shape[0] == 3  # one image per frame
    text = vlm.processor.batch_decode(inputs["input_ids"])[0]
    assert "You are precise." in text and "Which mark moved?" in text
    n_img = int((inputs["input_ids"] == vlm.model.config.image_token_id).sum())
    assert n_img == int(inputs["image_grid_thw"].prod(-1).sum()) // 4
    out = vlm.generate([f for f in frames], "Which mark moved?", system="You are precise.", max_new_tokens=4,
                       do_sample=True, temperature=0.7, seed=3)
    assert isinstance(out, str)


def test_qwen_fps_is_forwarded(qwen_dir):
    vlm = Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir), device="cpu", fps=4.0)
    inputs = vlm.prepare_inputs(_marked_frames(4), "What moved?")
    # second_per_grid_ts = temporal_patch_size / fps
    assert float(inputs["second_per_grid_ts"][0]) == pytest.approx(2 / 4.0)


# ----------------------------------------------------------------------------- VideoLLaMA3


def test_videollama3_video_path(videollama_dir):
    vlm = VideoLlama3Adapter.from_pretrained(str(videollama_dir), device="cpu", fps=2.0)
    frames = _marked_frames(4)
    inputs = vlm.prepare_inputs(frames, "What moved?")
    assert int(inputs["video_grid_thw"][0, 0]) == len(frames)  # temporal patch 1: one grid slice per frame
    n_tokens = int((inputs["input_ids"] == vlm.model.config.video_token_id).sum())
    assert n_tokens == int(inputs["video_compression_mask"].sum()) > 0
    text = vlm.processor.batch_decode(inputs["input_ids"])[0]
    assert "Time 1.5s:" in text  # per-frame timestamps from fps=2: frames 0..3 -> 0.0 .. 1.5 s
    cap = _Capture(vlm.model.model.vision_model)
    try:
        answer = vlm.generate(frames, "What moved?", max_new_tokens=5)
    finally:
        cap.remove()
    assert isinstance(answer, str) and cap.shapes


# ----------------------------------------------------------------------------- InternVL


@pytest.mark.parametrize("frames_as", ["video", "images"])
def test_internvl_paths(internvl_dir, frames_as):
    vlm = InternVLAdapter.from_pretrained(str(internvl_dir), device="cpu", frames_as=frames_as)
    frames = _marked_frames(3)
    inputs = vlm.prepare_inputs(frames, "What moved?")
    assert inputs["pixel_values"].shape[0] == len(frames)  # one 28x28 tile per frame
    n_ctx = int((inputs["input_ids"] == vlm.model.config.image_token_id).sum())
    assert n_ctx == len(frames) * vlm.processor.image_seq_length
    cap = _Capture(vlm.model.model.vision_tower)
    try:
        answer = vlm.generate(frames, "What moved?", max_new_tokens=4)
    finally:
        cap.remove()
    assert isinstance(answer, str)
    assert cap.shapes[0][0] == len(frames)


# ----------------------------------------------------------------------------- batches of unequal videos


@pytest.mark.parametrize("family", ["qwen", "videollama", "internvl"])
def test_generate_batch_on_unequal_videos(family, request):
    """A 4-frame and a 2-frame video (and a second 4-frame one) in one call: one answer per
    video, in order, each equal to what `generate` answers for that video alone."""
    adapter_cls = {"qwen": Qwen2_5_VLAdapter, "videollama": VideoLlama3Adapter, "internvl": InternVLAdapter}[family]
    path = request.getfixturevalue(f"{family}_dir")
    vlm = adapter_cls.from_pretrained(str(path), device="cpu", fps=2.0)
    videos = [_marked_frames(4), _marked_frames(2), _marked_frames(4)[::-1]]
    prompts = ["What moved?", "Anything else?", "What moved?"]
    answers = vlm.generate_batch(videos, prompts, max_new_tokens=5)
    alone = [vlm.generate(v, p, max_new_tokens=5) for v, p in zip(videos, prompts)]
    assert answers == alone


def test_internvl_batches_by_frame_count(internvl_dir):
    vlm = InternVLAdapter.from_pretrained(str(internvl_dir), device="cpu")
    cap = _Capture(vlm.model.model.vision_tower)
    try:
        vlm.generate_batch([_marked_frames(4), _marked_frames(2), _marked_frames(4)], "What moved?", max_new_tokens=1)
    finally:
        cap.remove()
    assert [s[0] for s in cap.shapes] == [8, 2]  # one forward for the two 4-frame videos, one for the 2-frame one


# ----------------------------------------------------------------------------- errors


def test_missing_checkpoint_folder_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        Qwen2_5_VLAdapter.from_pretrained(str(tmp_path / "no-such-model"))


def test_transformers_without_the_class_names_the_extra(qwen_dir, monkeypatch):
    monkeypatch.setattr(Qwen2_5_VLAdapter, "model_class_name", "NoSuchVLForConditionalGeneration")
    with pytest.raises(MissingDependencyError, match=r"does not have.*motionbits\[vlm\]"):
        Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir))


@pytest.fixture
def qwen_class_unimportable(monkeypatch):
    """transformers' lazy import of the Qwen2.5-VL modeling module fails, as it does when
    torchvision's compiled ops do not load against the installed torch."""
    import sys

    lazy = sys.modules["transformers"]  # loading a model can swap this object: take the current one
    monkeypatch.delattr(lazy, "Qwen2_5_VLForConditionalGeneration", raising=False)
    monkeypatch.setitem(sys.modules, "transformers.models.qwen2_5_vl.modeling_qwen2_5_vl", None)
    with pytest.raises(ModuleNotFoundError, match="Could not import module"):  # transformers' own error
        getattr(lazy, "Qwen2_5_VLForConditionalGeneration")


def test_class_import_failure_names_the_cause(qwen_dir, qwen_class_unimportable):
    with pytest.raises(MissingDependencyError) as err:
        Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir))
    msg = str(err.value)
    assert "could not import transformers.Qwen2_5_VLForConditionalGeneration" in msg
    assert "modeling_qwen2_5_vl" in msg  # the underlying cause, not transformers' generic message
    assert 'pip install "motionbits[vlm]"' in msg


def test_missing_path_is_checked_before_the_import(tmp_path, qwen_class_unimportable):
    with pytest.raises(FileNotFoundError, match="no-such-model"):
        Qwen2_5_VLAdapter.from_pretrained(str(tmp_path / "no-such-model"))


def test_processor_without_chat_template_is_rejected(qwen):
    class NoTemplate:
        chat_template = None

    with pytest.raises(ValueError, match="chat template"):
        Qwen2_5_VLAdapter(qwen.model, NoTemplate())


# ----------------------------------------------------------------------------- InternVideo2.5 (remote code)


def test_internvideo25_calls_the_checkpoint_chat_contract():
    """The remote-code model is not available offline; check what the adapter hands to its
    ``chat`` method (InternVL's signature, as in the InternVideo2.5 model card)."""
    from vlm_adapters import InternVideo25Adapter

    class FakeRemoteModel(torch.nn.Module):
        system_message = "default system"

        def __init__(self):
            super().__init__()
            self.w = torch.nn.Parameter(torch.zeros(1, dtype=torch.float32))
            self.calls = []

        def chat(self, tokenizer, pixel_values, question, generation_config, num_patches_list=None,
                 history=None, return_history=False):
            self.calls.append((tokenizer, pixel_values, question, dict(generation_config), num_patches_list,
                               self.system_message))
            return f"  {question.count('<image>')} frames  "

    model = FakeRemoteModel()
    vlm = InternVideo25Adapter(model, tokenizer="tok", image_size=56)
    frames = _marked_frames(3)
    assert vlm.generate(frames, "What moved?", system="sys", max_new_tokens=9) == "3 frames"
    tok, pv, question, gen, patches, system = model.calls[0]
    assert tok == "tok" and pv.shape == (3, 3, 56, 56) and pv.dtype == torch.float32
    assert question == "Frame1: <image>\nFrame2: <image>\nFrame3: <image>\nWhat moved?"
    assert gen["max_new_tokens"] == 9 and gen["do_sample"] is False and patches == [1, 1, 1]
    assert system == "sys" and model.system_message == "default system"  # restored after the call
    # ImageNet normalisation of the background value 40/255 in the red channel
    assert float(pv[0, 0, 0, 0]) == pytest.approx((40 / 255 - 0.485) / 0.229, abs=1e-3)


def test_dtype_reaches_model_and_pixels(qwen_dir):
    """bfloat16 (the CUDA default) end to end, here on CPU: pixels follow the model dtype."""
    vlm = Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir), device="cpu", dtype="bfloat16")
    assert vlm.model.dtype == torch.bfloat16
    inputs = vlm.prepare_inputs(_marked_frames(2), "What moved?")
    assert inputs["pixel_values_videos"].dtype == torch.bfloat16
    assert inputs["input_ids"].dtype == torch.long
    assert isinstance(vlm.generate(_marked_frames(2), "What moved?", max_new_tokens=3), str)


def test_only_pixels_take_the_model_dtype(qwen_dir):
    """Qwen's `second_per_grid_ts` feeds temporal position ids: in bfloat16, 2/3 s would be 0.668."""
    vlm = Qwen2_5_VLAdapter.from_pretrained(str(qwen_dir), device="cpu", dtype="bfloat16", fps=3.0)
    inputs = vlm.prepare_inputs(_marked_frames(4), "What moved?")
    assert inputs["pixel_values_videos"].dtype == torch.bfloat16
    assert inputs["second_per_grid_ts"].dtype == torch.float32
    assert float(inputs["second_per_grid_ts"][0]) == pytest.approx(2 / 3, abs=1e-6)
