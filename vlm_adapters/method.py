"""The VLM + YOLOE baseline as a benchmark method: frames -> final-frame label map.

The benchmark runner takes callables ``frames -> (H, W) int32 label map`` for the final
frame. `make_vlm_yoloe_method` builds one from any `VLMAdapter`, a grounder and a prompt:
the VLM answers the prompt about (a subsample of) the clip, the grounder turns the answer
into masks on the final frame.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from motionbits.frames import whole_number

from .base import VLMAdapter, sample_frames, to_rgb_frames
from .grounding import TextGrounder
from .phrases import MOVED_OBJECTS_PROMPT

__all__ = ["VLMYOLOEMethod", "make_vlm_yoloe_method"]


class VLMYOLOEMethod:
    """Callable baseline: ``method(frames) -> (H, W) int32`` label map of the final frame.

    Args:
        vlm: any `VLMAdapter`.
        grounder: a `TextGrounder` (`YOLOEGrounder` for the paper's baseline).
        prompt: the question + output format (default: the paper's question with our format).
        system: optional system message.
        num_frames: frames sent to the VLM, evenly spaced, the final frame always included
            (None: all frames).
        generate_kwargs: passed to ``vlm.generate`` (default: greedy, seed 0).
        name: the method's name in result tables (default ``"<vlm name>+yoloe"``).

    After a call, `last_answer` and `last_phrases` hold the VLM's answer and the phrases used.
    """

    def __init__(
        self,
        vlm: VLMAdapter,
        grounder: TextGrounder,
        prompt: str = MOVED_OBJECTS_PROMPT,
        *,
        system: str | None = None,
        num_frames: int | None = 8,
        generate_kwargs: dict[str, Any] | None = None,
        name: str | None = None,
    ) -> None:
        if not callable(getattr(vlm, "generate", None)):  # else AttributeError on the first clip
            raise TypeError(f"vlm must have generate(frames, prompt, system=None, **gen), got {type(vlm).__name__}")
        if not (callable(getattr(grounder, "phrases", None)) and callable(getattr(grounder, "ground", None))):
            raise TypeError(f"grounder must be a TextGrounder (phrases(text), ground(text, image)), "
                            f"got {type(grounder).__name__}")
        if not isinstance(prompt, str) or not prompt.strip():  # else None was asked
            raise ValueError(f"prompt must be a non-empty str, got {prompt!r:.40}")
        if num_frames is not None and whole_number("num_frames", num_frames) < 1:  # else refused on the first clip
            raise ValueError(f"num_frames must be >= 1 or None, got {num_frames!r}")
        if generate_kwargs is not None and not isinstance(generate_kwargs, Mapping):
            raise TypeError(f"generate_kwargs must be a dict or None, got {type(generate_kwargs).__name__}")
        self.vlm = vlm
        self.grounder = grounder
        self.prompt = prompt
        self.system = system
        self.num_frames = num_frames
        self.generate_kwargs = {"do_sample": False, "seed": 0, **(generate_kwargs or {})}
        self.name = name or f"{getattr(vlm, 'name', type(vlm).__name__)}+yoloe"
        self.last_answer: str | None = None
        self.last_phrases: list[str] = []

    def __call__(self, frames: Sequence[Any] | np.ndarray) -> np.ndarray:
        """(T, H, W, 3) uint8 RGB frames (or a list of them) -> (H, W) int32 final-frame labels."""
        clip = to_rgb_frames(frames)
        answer = self.vlm.generate(sample_frames(clip, self.num_frames), self.prompt, self.system, **self.generate_kwargs)
        self.last_answer = answer
        self.last_phrases = self.grounder.phrases(answer)
        return self.grounder.ground(answer, clip[-1])

    def __repr__(self) -> str:
        return f"VLMYOLOEMethod(name={self.name!r}, num_frames={self.num_frames})"


def make_vlm_yoloe_method(
    vlm: VLMAdapter,
    grounder: TextGrounder,
    prompt: str = MOVED_OBJECTS_PROMPT,
    **kwargs: Any,
) -> VLMYOLOEMethod:
    """A benchmark method ``frames -> (H, W) int32`` from a VLM, a grounder and a prompt.

    Example:
        >>> vlm = Qwen2_5_VLAdapter.from_pretrained("/models/Qwen2.5-VL-32B-Instruct")  # doctest: +SKIP
        >>> grounder = YOLOEGrounder.from_pretrained("yoloe-11l-seg.pt", text_encoder="mobileclip_blt.ts")  # doctest: +SKIP
        >>> method = make_vlm_yoloe_method(vlm, grounder)  # doctest: +SKIP
        >>> labels = method(frames)  # (H, W) int32 for frames[-1]  # doctest: +SKIP
    """
    return VLMYOLOEMethod(vlm, grounder, prompt, **kwargs)
