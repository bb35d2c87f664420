"""`StubVLM`: a scripted stand-in for a real VLM, for tests and demos without weights.

It does not look at the frames. It returns scripted answers, so pipelines around a VLM
(set-of-mark prompting, the YOLOE reverse path, the benchmark) can run end to end
anywhere. Every call is recorded in `calls` for inspection.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Union

from .base import DEFAULT_MAX_NEW_TOKENS, BaseVLM, Frame, to_rgb_frames

__all__ = ["StubVLM", "StubCall"]

Script = Union[str, Sequence[str], Callable[[list, str], str]]


@dataclass(frozen=True)
class StubCall:
    """One recorded call: how many frames, their (H, W) size, the prompt and system text."""

    num_frames: int
    frame_size: tuple[int, int]
    prompt: str
    system: str | None


class StubVLM(BaseVLM):
    """A fake VLM that answers from a script, not from the frames.

    Args:
        responses: one answer for every call; or a list of answers returned in turn
            (cycling when `cycle=True`, else an error when they run out); or a callable
            ``(frames, prompt) -> str`` where frames are (H, W, 3) uint8 arrays.
        cycle: whether a list of answers starts over when used up.
        name: short name for tables.

    Example:
        >>> vlm = StubVLM("- red block: the cube the gripper pushed")
        >>> vlm.generate([frame0, frame1], "What moved?")  # doctest: +SKIP
        '- red block: the cube the gripper pushed'
    """

    def __init__(self, responses: Script = "", *, cycle: bool = True, name: str = "stub") -> None:
        self._fn: Callable[[list, str], str] | None = None
        self._answers: list[str] = []
        if callable(responses):
            self._fn = responses
        elif isinstance(responses, str):
            self._answers = [responses]
        else:
            self._answers = [str(r) for r in responses]
            if not self._answers:
                raise ValueError("StubVLM needs at least one scripted response")
        self.cycle = cycle
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
        arrays = to_rgb_frames(frames)
        i = len(self.calls)
        self.calls.append(StubCall(len(arrays), arrays[-1].shape[:2], prompt, system))
        if self._fn is not None:
            return str(self._fn(arrays, prompt))
        if i >= len(self._answers) and not self.cycle:
            raise IndexError(f"StubVLM ran out of scripted responses after {len(self._answers)} calls")
        return self._answers[i % len(self._answers)]
