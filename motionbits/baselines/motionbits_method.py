"""The MotionBits segmenter as a benchmark method (its module is imported when the method
is first made, so it does not slow down the other methods' start-up)."""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from motionbits.config import MotionBitsConfig
from motionbits.segmenter import segment_video

__all__ = ["MotionBitsMethod"]

_TRUE, _FALSE = {"true", "1", "yes", "on"}, {"false", "0", "no", "off"}


def _from_text(name: str, kind: str, text: str):
    """A config field's value from its ``--option`` text (annotation ``kind``)."""
    if kind == "bool":
        if text.strip().lower() in _TRUE | _FALSE:
            return text.strip().lower() in _TRUE
        raise ValueError(f"motionbits.{name}={text!r}: expected true or false")
    try:
        return {"int": int, "float": float}.get(kind, str)(text)
    except ValueError:
        what = "an integer" if kind == "int" else "a number"
        raise ValueError(f"motionbits.{name}={text!r}: expected {what}") from None


class MotionBitsMethod:
    """``frames -> (H, W) int32`` labels of the last frame, by :func:`motionbits.segment_video`.

    Args:
        config: a :class:`MotionBitsConfig` (default: the paper's parameters), or a dict
            of its fields.
        **changes: fields to change on top of ``config`` (e.g. ``exact=True``); strings
            (from ``--option motionbits.KEY=VALUE``) are converted to the field's type
            ("true"/"false" for booleans).

    Raises:
        ValueError / TypeError: an unknown field, or a value of the wrong type or range
            (checked here, before any clip is segmented).
    """

    def __init__(self, config: MotionBitsConfig | dict | None = None, **changes) -> None:
        kinds = {f.name: f.type if isinstance(f.type, str) else f.type.__name__
                 for f in fields(MotionBitsConfig)}
        for name, value in changes.items():
            if name not in kinds:
                raise ValueError(f"unknown MotionBitsConfig field {name!r}; known: "
                                 + ", ".join(kinds))
            if isinstance(value, str):
                changes[name] = _from_text(name, kinds[name], value)
        if isinstance(config, dict):
            config = MotionBitsConfig(**config)
        config = config or MotionBitsConfig()
        self.config = config.with_(**changes) if changes else config

    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        labels = None
        for result in segment_video(frames, self.config):
            labels = result.labels
        if labels is None:
            raise ValueError("no frames given")
        return labels.astype(np.int32)
