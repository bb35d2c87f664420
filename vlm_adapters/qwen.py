"""Qwen2.5-VL through transformers' native `Qwen2_5_VLForConditionalGeneration`.

Checkpoints: ``Qwen/Qwen2.5-VL-{3B,7B,32B,72B}-Instruct`` (the paper used 32B), or any folder
written by ``save_pretrained``. Frames go in as one video by default (Qwen's video path:
2-frame temporal patches, M-RoPE time ids); ``frames_as="images"`` sends them as images.
"""
from __future__ import annotations

from .hf import TransformersVLM

__all__ = ["Qwen2_5_VLAdapter"]


class Qwen2_5_VLAdapter(TransformersVLM):
    """Qwen2.5-VL adapter.

    Example:
        >>> vlm = Qwen2_5_VLAdapter.from_pretrained("/models/Qwen2.5-VL-7B-Instruct", fps=2.0)  # doctest: +SKIP
        >>> vlm.generate(frames, "What rigid bodies have moved in the video?")  # doctest: +SKIP

    Pixel budget: pass ``processor_kwargs={"min_pixels": ..., "max_pixels": ...}`` to
    `from_pretrained` (e.g. ``max_pixels=360 * 420`` for video), as in Qwen's model card.
    """

    model_class_name = "Qwen2_5_VLForConditionalGeneration"
    default_frames_as = "video"
    default_name = "qwen2.5-vl"
