"""VideoLLaMA3 through transformers' native `VideoLlama3ForConditionalGeneration`.

transformers (5.x) ships VideoLLaMA3 natively (`transformers.models.video_llama_3`:
`VideoLlama3ForConditionalGeneration`, `VideoLlama3Processor`). The native classes load a
checkpoint in transformers format (``model_type: "video_llama_3"`` in config.json). The
original ``DAMO-NLP-SG/VideoLLaMA3-7B`` repository is a remote-code checkpoint
(``model_type: "videollama3_qwen2"``); convert it to the transformers layout first, or load
a transformers-format copy — this adapter does not run the remote code.
"""
from __future__ import annotations

from .hf import TransformersVLM

__all__ = ["VideoLlama3Adapter"]


class VideoLlama3Adapter(TransformersVLM):
    """VideoLLaMA3 adapter.

    VideoLLaMA3 writes a timestamp before every frame's tokens ("Time 1.5s:"); pass the
    frames' real ``fps`` so those timestamps are right (without it the processor assumes
    1 fps and warns).

    Example:
        >>> vlm = VideoLlama3Adapter.from_pretrained("/models/VideoLLaMA3-7B-hf", fps=1.0)  # doctest: +SKIP
        >>> vlm.generate(frames, "What rigid bodies have moved in the video?")  # doctest: +SKIP
    """

    model_class_name = "VideoLlama3ForConditionalGeneration"
    default_frames_as = "video"
    default_name = "videollama3"
