"""One interface over video-language models, and the reverse path VLM text -> YOLOE -> masks.

Adapters (all with ``generate(frames, prompt, system=None, ...) -> str`` and
``generate_batch(videos, prompts, ...) -> list[str]``):

* `Qwen2_5_VLAdapter`   transformers ``Qwen2_5_VLForConditionalGeneration``
* `VideoLlama3Adapter`  transformers ``VideoLlama3ForConditionalGeneration``
* `InternVLAdapter`     transformers ``InternVLForConditionalGeneration``
* `InternVideo25Adapter` remote-code InternVideo2.5 (only with ``trust_remote_code=True``)
* `OpenAICompatibleVLM` any OpenAI-compatible chat-completions server (vLLM, SGLang, ...)
* `StubVLM`             scripted answers, for tests and demos

Reverse path: `phrases_from_answer`, `YOLOEGrounder` / `TextGrounder`, `masks_to_label_map`,
and `make_vlm_yoloe_method` (a benchmark method ``frames -> (H, W) int32``).
`vlm_yoloe_method` builds that method from string options (a VLM spec such as
``qwen2.5-vl:/models/...``, YOLOE files); it is the ``vlm-yoloe`` method of
``motionbits benchmark``, registered as an entry point in ``motionbits.methods``.

Names are imported lazily: ``import vlm_adapters`` does not import torch, transformers
or ultralytics.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS: dict[str, str] = {
    # base
    "VLMAdapter": "base",
    "BaseVLM": "base",
    "Frame": "base",
    "MissingDependencyError": "base",
    "to_rgb_frames": "base",
    "sample_frames": "base",
    # adapters
    "TransformersVLM": "hf",
    "Qwen2_5_VLAdapter": "qwen",
    "VideoLlama3Adapter": "videollama",
    "InternVLAdapter": "internvl",
    "InternVideo25Adapter": "internvl",
    "OpenAICompatibleVLM": "openai_compat",
    "StubVLM": "stub",
    # text -> phrases
    "PAPER_QUESTION": "phrases",
    "MOVED_OBJECTS_PROMPT": "phrases",
    "extract_noun_phrases": "phrases",
    "phrases_from_answer": "phrases",
    # phrases -> masks
    "Detections": "grounding",
    "PhraseDetector": "grounding",
    "YOLOEDetector": "grounding",
    "TextGrounder": "grounding",
    "YOLOEGrounder": "grounding",
    "masks_to_label_map": "grounding",
    # benchmark method
    "VLMYOLOEMethod": "method",
    "make_vlm_yoloe_method": "method",
    # the `vlm-yoloe` method of `motionbits benchmark` (entry point), built from string options
    "load_vlm": "plugin",
    "vlm_yoloe_method": "plugin",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'vlm_adapters' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # cache: later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs only (names are in __all__ via _EXPORTS)
    # ruff: noqa: F401
    from .base import BaseVLM, Frame, MissingDependencyError, VLMAdapter, sample_frames, to_rgb_frames
    from .grounding import (
        Detections,
        PhraseDetector,
        TextGrounder,
        YOLOEDetector,
        YOLOEGrounder,
        masks_to_label_map,
    )
    from .hf import TransformersVLM
    from .internvl import InternVideo25Adapter, InternVLAdapter
    from .method import VLMYOLOEMethod, make_vlm_yoloe_method
    from .openai_compat import OpenAICompatibleVLM
    from .plugin import load_vlm, vlm_yoloe_method
    from .phrases import (
        MOVED_OBJECTS_PROMPT,
        PAPER_QUESTION,
        extract_noun_phrases,
        phrases_from_answer,
    )
    from .qwen import Qwen2_5_VLAdapter
    from .stub import StubVLM
    from .videollama import VideoLlama3Adapter
