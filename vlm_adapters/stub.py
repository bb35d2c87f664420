"""`StubVLM`: the scripted stand-in for a real VLM, for tests and demos without weights
(the one scripted VLM of the toolkit; ``somprompt``'s tests use it too).

It does not look at the frames. It returns scripted answers, so pipelines around a VLM
(set-of-mark prompting, the YOLOE reverse path, the benchmark) can run end to end
anywhere. Every call is recorded in `calls` for inspection.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Union

import numpy as np

from .base import DEFAULT_MAX_NEW_TOKENS, BaseVLM, Frame, check_generate_args, to_rgb_frames

__all__ = ["StubVLM", "StubCall"]

Script = Union[str, Sequence[str], Callable[[list, str], str]]


@dataclass(frozen=True)
class StubCall:
    """One recorded call: how many frames, their (H, W) size, the prompt and system text,
    the frames themselves ((H, W, 3) uint8) and the generation options."""

    num_frames: int
    frame_size: tuple[int, int]
    prompt: str
    system: str | None
    frames: list[np.ndarray] = field(default_factory=list, compare=False, repr=False)
    gen: dict[str, Any] = field(default_factory=dict, compare=False)


class StubVLM(BaseVLM):
    """A fake VLM that answers from a script, not from the frames.

    Args:
        responses: one answer for every call; or a list of answers returned in turn
            (cycling when `cycle=True`, else an error when they run out); or a callable
            ``(frames, prompt) -> str`` where frames are (H, W, 3) uint8 arrays.
        cycle: whether a list of answers starts over when used up (True or False).
        name: short name for tables.

    Example:
        >>> import numpy as np
        >>> vlm = StubVLM("- red block: the cube the gripper pushed")
        >>> vlm.generate([np.zeros((4, 6, 3), np.uint8)] * 2, "What moved?")
        '- red block: the cube the gripper pushed'
        >>> vlm.calls[0].num_frames, vlm.calls[0].frame_size
        (2, (4, 6))
    """

    def __init__(self, responses: Script = "", *, cycle: bool = True, name: str = "stub") -> None:
        self._fn: Callable[[list, str], str] | None = None
        self._answers: list[str] = []
        if callable(responses):
            self._fn = responses
        elif isinstance(responses, str):
            self._answers = [responses]
        elif not isinstance(responses, Sequence):  # e.g. None: "'NoneType' object is not iterable"
            raise TypeError("StubVLM responses must be a str, a list of str or a callable "
                            f"(frames, prompt) -> str, got {type(responses).__name__}")
        else:
            self._answers = list(responses)
            if not self._answers:
                raise ValueError("StubVLM needs at least one scripted response")
            bad = [r for r in self._answers if not isinstance(r, str)]
            if bad:
                raise TypeError(f"StubVLM responses must be strings, got {type(bad[0]).__name__} {bad[0]!r:.40}")
        if not isinstance(cycle, (bool, np.bool_)):  # else "no" (or any non-empty str) read as True
            raise TypeError(f"cycle must be True or False, got {type(cycle).__name__} {cycle!r:.40}")
        self.cycle = bool(cycle)
        self.name = name
        self.calls: list[StubCall] = []

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
        # the checks of the real adapters, so that a pipeline tested with the stub sends them nothing
        # they refuse (a None prompt or max_new_tokens=0 was recorded and answered)
        check_generate_args(prompt, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature,
                            seed=seed)
        arrays = to_rgb_frames(frames)
        i = len(self.calls)
        gen = {"max_new_tokens": max_new_tokens, "do_sample": do_sample, "temperature": temperature, "seed": seed}
        self.calls.append(StubCall(len(arrays), arrays[-1].shape[:2], prompt, system, arrays, gen))
        if self._fn is not None:
            answer = self._fn(arrays, prompt)
            if not isinstance(answer, str):  # str(None) would be the answer "None"
                raise TypeError(f"the StubVLM script returned {type(answer).__name__}, not str")
            return answer
        if i >= len(self._answers) and not self.cycle:
            raise IndexError(f"StubVLM ran out of scripted responses after {len(self._answers)} calls")
        return self._answers[i % len(self._answers)]
