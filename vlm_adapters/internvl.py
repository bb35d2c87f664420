"""InternVL (native transformers classes) and InternVideo2.5 (remote code, opt-in).

* `InternVLAdapter` loads transformers-format InternVL checkpoints with
  `InternVLForConditionalGeneration` + `InternVLProcessor` (e.g. ``OpenGVLab/InternVL3-8B-hf``:
  the ``-hf`` repositories). No remote code runs.
* `InternVideo25Adapter` loads ``OpenGVLab/InternVideo2_5_Chat_8B`` (the paper's
  InternVideo2.5-8B), which exists only as a remote-code checkpoint: transformers imports
  Python files shipped inside the checkpoint. That happens only with an explicit
  ``trust_remote_code=True``. Frames are preprocessed as in its model card (448 x 448,
  bicubic, ImageNet mean/std, one tile per frame, "Frame{i}: <image>" prefixes) and the
  model's own ``chat(tokenizer, pixel_values, question, generation_config,
  num_patches_list=...)`` method answers.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from motionbits.frames import whole_number

from .base import (
    DEFAULT_MAX_NEW_TOKENS,
    BaseVLM,
    Frame,
    check_generate_args,
    check_local_path,
    require,
    resolve_device,
    resolve_dtype,
    to_pil_frames,
)
from .hf import TransformersVLM

__all__ = ["InternVLAdapter", "InternVideo25Adapter"]

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)


class InternVLAdapter(TransformersVLM):
    """InternVL (2.5 / 3 / 3.5, transformers format) adapter.

    Video frames become one ``<video>`` input that the processor expands to
    "Frame1: <img>...</img>" blocks, one tile per frame. With ``frames_as="images"`` each
    frame is also one tile (``crop_to_patches=False``, as InternVL's video recipe does);
    pass ``processor_call_kwargs={"crop_to_patches": True}`` for InternVL's dynamic tiling
    of each image (up to 12 tiles + a thumbnail per frame).

    Example:
        >>> vlm = InternVLAdapter.from_pretrained("/models/InternVL3-8B-hf")  # doctest: +SKIP
        >>> vlm.generate(frames, "What rigid bodies have moved in the video?")  # doctest: +SKIP
    """

    model_class_name = "InternVLForConditionalGeneration"
    default_frames_as = "video"
    default_name = "internvl"
    stacks_video_frames = True  # InternVLVideoProcessor returns (B, T, 3, S, S)

    def default_call_kwargs(self) -> dict[str, Any]:
        return {"crop_to_patches": False} if self.frames_as == "images" else {}


class InternVideo25Adapter(BaseVLM):
    """InternVideo2.5-Chat (remote-code checkpoint) adapter.

    Args:
        model: the remote-code model (``AutoModel.from_pretrained(..., trust_remote_code=True)``);
            anything with InternVL's ``chat(tokenizer, pixel_values, question, generation_config,
            num_patches_list=..., history=None, return_history=False)`` method.
        tokenizer: its tokenizer.
        image_size: side of the square each frame is resized to (448 for InternVideo2.5).
        name: short name for tables.
    """

    default_name = "internvideo2.5"

    def __init__(self, model: Any, tokenizer: Any, *, image_size: int = 448, name: str | None = None) -> None:
        self.model = model
        self.tokenizer = tokenizer
        if whole_number("image_size", image_size) < 1:  # else 2.5 read as 2, 0 failed in PIL's resize
            raise ValueError(f"image_size must be >= 1 pixel, got {image_size!r}")
        self.image_size = int(image_size)
        self.name = name or self.default_name

    @classmethod
    def from_pretrained(
        cls,
        path_or_id: str,
        *,
        trust_remote_code: bool = False,
        device: Any = None,
        dtype: Any = None,
        name: str | None = None,
        model_kwargs: dict[str, Any] | None = None,
    ) -> InternVideo25Adapter:
        """Load ``OpenGVLab/InternVideo2_5_Chat_8B`` (or a local copy). Runs checkpoint code.

        Raises:
            ValueError: unless ``trust_remote_code=True`` is passed explicitly.
        """
        if not trust_remote_code:
            raise ValueError(
                "InternVideo2.5 is a remote-code checkpoint: loading it imports and runs Python files "
                "that ship inside the checkpoint folder. Read them, then pass trust_remote_code=True. "
                "For a checkpoint that needs no remote code use InternVLAdapter with an InternVL '-hf' "
                "checkpoint."
            )
        path = check_local_path(path_or_id, what=f"{cls.__name__} checkpoint")
        transformers = require("transformers", "vlm", cls.__name__)
        require("torch", "vlm", cls.__name__)
        device = resolve_device(device)
        dtype = resolve_dtype(dtype, device)
        model = transformers.AutoModel.from_pretrained(
            path, trust_remote_code=True, dtype=dtype, **(model_kwargs or {})
        )
        tokenizer = transformers.AutoTokenizer.from_pretrained(path, trust_remote_code=True, use_fast=False)
        model.to(device).eval()
        vision_cfg = getattr(getattr(model, "config", None), "vision_config", None)
        image_size = getattr(vision_cfg, "image_size", 448) or 448
        if isinstance(image_size, (list, tuple)):
            image_size = image_size[0]
        return cls(model, tokenizer, image_size=int(image_size), name=name)

    def pixel_values(self, frames: Sequence[Frame]) -> Any:
        """Frames as the model expects them: (T, 3, S, S) float tensor, S = `image_size`."""
        import torch
        from PIL import Image

        mean = np.asarray(IMAGENET_MEAN, np.float32)
        std = np.asarray(IMAGENET_STD, np.float32)
        tiles = []
        for img in to_pil_frames(frames):
            img = img.resize((self.image_size, self.image_size), Image.BICUBIC)
            arr = (np.asarray(img, np.float32) / 255.0 - mean) / std
            tiles.append(arr.transpose(2, 0, 1))
        x = torch.from_numpy(np.stack(tiles))
        param = next(iter(self.model.parameters()), None) if hasattr(self.model, "parameters") else None
        if param is not None:
            x = x.to(device=param.device, dtype=param.dtype)
        return x

    @staticmethod
    def build_question(num_frames: int, prompt: str) -> str:
        """The model card's video prompt: one "Frame{i}: <image>" line per frame, then the question."""
        return "".join(f"Frame{i + 1}: <image>\n" for i in range(num_frames)) + prompt

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
    ) -> str:
        """Answer `prompt` about `frames` through the checkpoint's own ``chat`` method."""
        check_generate_args(prompt, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature,
                            seed=seed)
        import torch

        if seed is not None:
            torch.manual_seed(seed)
        pixel_values = self.pixel_values(frames)
        n = int(pixel_values.shape[0])
        generation_config: dict[str, Any] = {"max_new_tokens": max_new_tokens, "do_sample": do_sample, "num_beams": 1}
        if do_sample:
            generation_config["temperature"] = temperature
        old_system = getattr(self.model, "system_message", None)
        if system is not None:
            self.model.system_message = system
        try:
            with torch.inference_mode():
                answer = self.model.chat(
                    self.tokenizer,
                    pixel_values,
                    self.build_question(n, prompt),
                    generation_config,
                    num_patches_list=[1] * n,
                    history=None,
                    return_history=False,
                )
        finally:
            if system is not None:
                self.model.system_message = old_system
        return str(answer).strip()
