"""Stand-ins for tests and demos: a scripted VLM and a segmenter that returns fixed maps.

Neither runs a model. ``ScriptedVLM`` follows the ``generate(frames, prompt, system=None,
**gen) -> str`` interface of ``vlm_adapters``; ``FixedSegmenter`` the ``frames -> label
maps`` interface of :class:`somprompt.Segmenter`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence, Union

import numpy as np

__all__ = ["ScriptedVLM", "VLMCall", "FixedSegmenter"]

Script = Union[str, Sequence[str], Callable[..., str]]


@dataclass
class VLMCall:
    """One recorded ``generate`` call."""

    frames: list
    prompt: str
    system: str | None
    gen: dict[str, Any]


class ScriptedVLM:
    """A fake VLM that answers from a script and records every call.

    Args:
        script: one answer for every call; or a list of answers, one per call (raises
            once exhausted); or ``f(frames, prompt, system) -> str``.

    Example:
        >>> vlm = ScriptedVLM(["[1] moved.", "[2] too."])
        >>> vlm.generate([], "What moved?"), vlm.generate([], "And?"), len(vlm.calls)
        ('[1] moved.', '[2] too.', 2)
    """

    def __init__(self, script: Script) -> None:
        if not (isinstance(script, str) or callable(script) or isinstance(script, Sequence)):
            raise TypeError("script must be a str, a list of str, or a callable")
        self.script = script
        self.calls: list[VLMCall] = []

    def generate(self, frames, prompt: str, system: str | None = None, **gen: Any) -> str:
        self.calls.append(VLMCall(list(frames), prompt, system, dict(gen)))
        if isinstance(self.script, str):
            return self.script
        if callable(self.script):
            return self.script(list(frames), prompt, system)
        k = len(self.calls) - 1
        if k >= len(self.script):
            raise RuntimeError(f"ScriptedVLM has {len(self.script)} scripted answers; call {k + 1} has none")
        return self.script[k]


@dataclass
class FixedSegmenter:
    """Returns the given label maps (one per frame) whatever the frames; records calls.

    Args:
        label_maps: T (H, W) integer label maps.
    """

    label_maps: Sequence[np.ndarray]
    calls: int = field(default=0, init=False)

    def __call__(self, frames: list[np.ndarray]) -> list[np.ndarray]:
        self.calls += 1
        if len(frames) != len(self.label_maps):
            raise ValueError(f"FixedSegmenter holds {len(self.label_maps)} label maps, got {len(frames)} frames")
        return [np.asarray(m) for m in self.label_maps]
