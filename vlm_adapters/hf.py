"""Shared machinery for adapters over transformers' native vision-language classes.

A transformers VLM checkpoint is a model class + a processor (image processor, video
processor, tokenizer, chat template). All of them take the same path here:

    messages  --processor.apply_chat_template-->  text with <image>/<video> placeholders
    text + frames  --processor(...)-->  input_ids (placeholders expanded to visual tokens),
                                        pixel values, grids
    inputs  --model.generate-->  new token ids  --processor.batch_decode-->  answer

Subclasses only name the model class (`model_class_name`). torch and transformers are
imported when a model is loaded, never at import time.
"""
from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any, ClassVar

from .base import (
    DEFAULT_MAX_NEW_TOKENS,
    BaseVLM,
    Frame,
    MissingDependencyError,
    _broadcast_prompts,
    check_generate_args,
    check_local_path,
    require,
    require_attr,
    resolve_device,
    resolve_dtype,
    to_pil_frames,
)

__all__ = ["TransformersVLM"]

_FRAMES_AS = ("video", "images")


class TransformersVLM(BaseVLM):
    """A transformers vision-language model behind the `VLMAdapter` interface.

    Args:
        model: a loaded ``*ForConditionalGeneration`` model (already on its device).
        processor: its processor (``AutoProcessor.from_pretrained`` of the same checkpoint);
            it must carry a chat template.
        frames_as: ``"video"`` passes the frames as one video input (the model's video
            path: temporal patches, frame timestamps); ``"images"`` passes them as a list of
            images in one user turn (what set-of-mark prompting with a few key frames uses).
        fps: frame rate of the frames as given, forwarded as video metadata (Qwen2.5-VL uses
            it for temporal position ids, VideoLLaMA3 for its per-frame timestamps).
            ``None`` leaves the processor's default.
        name: a short name for logs and benchmark tables.
        processor_call_kwargs: extra keyword arguments for every ``processor(...)`` call
            (e.g. ``{"crop_to_patches": True}`` for InternVL tiling).

    Use `from_pretrained` to load a checkpoint folder, as with transformers.
    """

    #: name of the transformers class that loads the checkpoint
    model_class_name: ClassVar[str] = ""
    #: default value of `frames_as` for this family
    default_frames_as: ClassVar[str] = "video"
    #: default `name`
    default_name: ClassVar[str] = "transformers-vlm"
    #: the processor stacks each video's frames into one (B, T, C, H, W) tensor, so one forward
    #: batch (``frames_as="video"``) can only hold videos with the same number of frames
    stacks_video_frames: ClassVar[bool] = False

    def __init__(
        self,
        model: Any,
        processor: Any,
        *,
        frames_as: str | None = None,
        fps: float | None = None,
        name: str | None = None,
        processor_call_kwargs: dict[str, Any] | None = None,
    ) -> None:
        frames_as = frames_as or self.default_frames_as
        if frames_as not in _FRAMES_AS:
            raise ValueError(f"frames_as must be one of {_FRAMES_AS}, got {frames_as!r}")
        if fps is not None and (isinstance(fps, bool) or not isinstance(fps, numbers.Real)
                                or not (math.isfinite(fps) and fps > 0)):  # else sent as video metadata
            raise ValueError(f"fps must be None or a finite number > 0, got {fps!r:.40}")
        if getattr(processor, "chat_template", None) is None:
            raise ValueError(
                "the processor has no chat template; load the processor of an instruction-tuned "
                "checkpoint (its chat_template.jinja / chat_template.json) or set processor.chat_template"
            )
        self.model = model
        self.processor = processor
        self.frames_as = frames_as
        self.fps = fps
        self.name = name or self.default_name
        self.processor_call_kwargs = dict(processor_call_kwargs or {})

    # ------------------------------------------------------------------ loading
    @classmethod
    def from_pretrained(
        cls,
        path_or_id: str,
        *,
        device: Any = None,
        dtype: Any = None,
        frames_as: str | None = None,
        fps: float | None = None,
        name: str | None = None,
        processor_call_kwargs: dict[str, Any] | None = None,
        attn_implementation: str | None = None,
        trust_remote_code: bool = False,
        model_kwargs: dict[str, Any] | None = None,
        processor_kwargs: dict[str, Any] | None = None,
    ) -> TransformersVLM:
        """Load model and processor from a checkpoint folder (or a hub id in the local cache).

        Args:
            path_or_id: a folder written by ``save_pretrained`` / downloaded from the hub.
            device: ``"cpu"``, ``"cuda"``, ``"cuda:1"``, a ``torch.device``; default: CUDA
                when available, else CPU.
            dtype: ``torch.dtype`` or its name; default: bfloat16 on CUDA, float32 on CPU.
            frames_as, fps, name, processor_call_kwargs: see the class docstring.
            attn_implementation: e.g. ``"sdpa"``, ``"flash_attention_2"``, ``"eager"``.
            trust_remote_code: forwarded to transformers; the native classes do not need it.
            model_kwargs / processor_kwargs: extra arguments for the two ``from_pretrained`` calls
                (e.g. ``processor_kwargs={"max_pixels": 640 * 28 * 28}``).
        """
        path = check_local_path(path_or_id, what=f"{cls.__name__} checkpoint")
        transformers = require("transformers", "vlm", cls.__name__)
        require("torch", "vlm", cls.__name__)
        model_cls = require_attr(transformers, cls.model_class_name, "vlm", cls.__name__)
        device = resolve_device(device)
        dtype = resolve_dtype(dtype, device)
        mkw = dict(model_kwargs or {})
        if attn_implementation is not None:
            mkw["attn_implementation"] = attn_implementation
        if trust_remote_code:
            mkw["trust_remote_code"] = True
        pkw = dict(processor_kwargs or {})
        if trust_remote_code:
            pkw["trust_remote_code"] = True
        try:
            model = model_cls.from_pretrained(path, dtype=dtype, **mkw)
            processor = transformers.AutoProcessor.from_pretrained(path, **pkw)
        except ImportError as exc:  # e.g. a processor whose torchvision fails to load
            raise MissingDependencyError(
                f"{cls.__name__} could not load '{path_or_id}' (a module it needs failed to import): "
                f"{type(exc).__name__}: {exc}. Repair the install: pip install \"motionbits[vlm]\""
            ) from exc
        except OSError as exc:
            raise OSError(
                f"could not load a {cls.model_class_name} checkpoint from '{path_or_id}': {exc}\n"
                f"Pass a local folder holding config.json, the weights and the processor files "
                f"(no model hub is needed when the folder is complete)."
            ) from exc
        model.to(device)
        model.eval()
        return cls(
            model, processor, frames_as=frames_as, fps=fps, name=name, processor_call_kwargs=processor_call_kwargs
        )

    # ------------------------------------------------------------------ inputs
    @property
    def device(self) -> Any:
        """The model's `torch.device`."""
        return next(self.model.parameters()).device

    def build_messages(self, num_frames: int, prompt: str, system: str | None = None) -> list[dict[str, Any]]:
        """Chat messages in transformers' multimodal format for one video and one prompt."""
        if self.frames_as == "video":
            visual = [{"type": "video"}]
        else:
            visual = [{"type": "image"} for _ in range(num_frames)]
        messages: list[dict[str, Any]] = []
        if system:
            messages.append({"role": "system", "content": [{"type": "text", "text": system}]})
        messages.append({"role": "user", "content": [*visual, {"type": "text", "text": prompt}]})
        return messages

    def default_call_kwargs(self) -> dict[str, Any]:
        """Processor-call defaults of this model family (overridden by `processor_call_kwargs`)."""
        return {}

    def _video_metadata(self, num_frames: int) -> dict[str, Any]:
        return {"total_num_frames": num_frames, "fps": float(self.fps), "frames_indices": list(range(num_frames))}

    def prepare_inputs(
        self,
        videos: Sequence[Sequence[Frame]] | Sequence[Frame],
        prompts: Sequence[str] | str,
        system: str | None = None,
    ) -> Any:
        """Processor outputs for one video (or a batch of videos), on the model's device.

        Args:
            videos: one video (list of (H, W, 3) uint8 RGB frames / PIL images), or a list of them
                when `prompts` is a list.
            prompts: the question, or one per video.
            system: optional system message.

        Returns:
            the processor's `BatchFeature`: ``input_ids`` (B, L) with the visual placeholders
            expanded to visual tokens, ``attention_mask``, pixel values and grid sizes.
        """
        if isinstance(prompts, str):
            videos = [videos]  # type: ignore[list-item]
        prompts = _broadcast_prompts(prompts, videos)
        clips = [to_pil_frames(v) for v in videos]
        texts = [
            self.processor.apply_chat_template(
                self.build_messages(len(c), p, system), tokenize=False, add_generation_prompt=True
            )
            for c, p in zip(clips, prompts)
        ]
        kwargs: dict[str, Any] = {"text": texts, "return_tensors": "pt", "padding": True}
        if len(texts) > 1:
            kwargs["padding_side"] = "left"  # decoder-only generation needs left padding
        if self.frames_as == "video":
            kwargs["videos"] = clips
            if self.fps is not None:
                kwargs["video_metadata"] = [self._video_metadata(len(c)) for c in clips]
        else:
            kwargs["images"] = [img for c in clips for img in c]
        kwargs.update(self.default_call_kwargs())
        kwargs.update(self.processor_call_kwargs)
        inputs = self.processor(**kwargs).to(self.device)
        # only pixel values take the model's dtype (e.g. bfloat16 on CUDA): other float outputs,
        # such as Qwen's `second_per_grid_ts` (temporal positions), keep their precision
        dtype = getattr(self.model, "dtype", None)
        if dtype is not None:
            for key in [k for k in inputs if k.startswith("pixel_values")]:
                if inputs[key].is_floating_point():
                    inputs[key] = inputs[key].to(dtype)
        return inputs

    # ------------------------------------------------------------------ generation
    def _generate(
        self,
        inputs: Any,
        *,
        max_new_tokens: int,
        do_sample: bool,
        temperature: float,
        seed: int | None,
        generate_kwargs: dict[str, Any],
    ) -> list[str]:
        import torch

        if seed is not None:
            torch.manual_seed(seed)
            if torch.cuda.is_available():
                torch.cuda.manual_seed_all(seed)
        gen: dict[str, Any] = {"max_new_tokens": max_new_tokens, "do_sample": do_sample}
        if do_sample:
            gen["temperature"] = temperature
        else:  # greedy: neutralise sampling defaults a checkpoint's generation_config may carry
            gen.update(temperature=None, top_p=None, top_k=None)
        tok = getattr(self.processor, "tokenizer", None)
        if tok is not None and tok.pad_token_id is not None:
            gen["pad_token_id"] = tok.pad_token_id
        gen.update(generate_kwargs)
        with torch.inference_mode():
            out = self.model.generate(**inputs, **gen)
        new_tokens = out[:, inputs["input_ids"].shape[1] :]
        texts = self.processor.batch_decode(new_tokens, skip_special_tokens=True)
        return [t.strip() for t in texts]

    def generate(
        self,
        frames: Sequence[Frame],
        prompt: str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
        **generate_kwargs: Any,
    ) -> str:
        """Answer `prompt` about `frames` (list of (H, W, 3) uint8 RGB arrays or PIL images).

        ``do_sample=False`` is greedy decoding (deterministic); extra keyword arguments go to
        ``model.generate``.
        """
        check_generate_args(prompt, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature,
                            seed=seed)
        inputs = self.prepare_inputs(frames, prompt, system)
        return self._generate(
            inputs,
            max_new_tokens=max_new_tokens,
            do_sample=do_sample,
            temperature=temperature,
            seed=seed,
            generate_kwargs=generate_kwargs,
        )[0]

    def generate_batch(
        self,
        videos: Sequence[Sequence[Frame]],
        prompts: Sequence[str] | str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
        **generate_kwargs: Any,
    ) -> list[str]:
        """One answer per video, in one padded forward batch (left padding).

        Where the family's processor cannot batch videos of different lengths
        (`stacks_video_frames`), videos are batched by frame count: one forward batch per
        distinct length; answers come back in the order of `videos`.
        """
        prompts = _broadcast_prompts(prompts, videos)
        for p in prompts:
            check_generate_args(p, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature,
                                seed=seed)
        clips = [to_pil_frames(v) for v in videos]
        if self.frames_as == "video" and self.stacks_video_frames:
            groups: dict[int, list[int]] = {}
            for i, clip in enumerate(clips):
                groups.setdefault(len(clip), []).append(i)
            batches = list(groups.values())
        else:
            batches = [list(range(len(clips)))]
        answers: list[str] = [""] * len(clips)
        for idx in batches:
            inputs = self.prepare_inputs([clips[i] for i in idx], [prompts[i] for i in idx], system)
            out = self._generate(
                inputs,
                max_new_tokens=max_new_tokens,
                do_sample=do_sample,
                temperature=temperature,
                seed=seed,
                generate_kwargs=generate_kwargs,
            )
            for i, answer in zip(idx, out):
                answers[i] = answer
        return answers

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(name={self.name!r}, model={type(self.model).__name__}, "
            f"frames_as={self.frames_as!r}, fps={self.fps})"
        )
