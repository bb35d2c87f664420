"""The MotionBits segmenter as a benchmark method (imported lazily: it may not be installed
in this checkout yet, and it should not slow down the other methods' start-up)."""

from __future__ import annotations

import numpy as np

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
        raise ValueError(f"motionbits.{name}={text!r}: expected {'an integer' if kind == 'int' else 'a number'}") from None


class MotionBitsMethod:
    """``motionbits.segment_video(frames, config)``; the last yielded result's ``labels``.

    Args:
        config: a ``motionbits.MotionBitsConfig`` (default: the paper's parameters), or a
            dict of its fields to change.
        **changes: config fields to change; strings (from ``--option motionbits.KEY=VALUE``)
            are converted to the field's type ("true"/"false" for booleans).

    Raises:
        ValueError / TypeError: an unknown field, or a value of the wrong type or range
            (checked here, before any clip is segmented).
    """

    def __init__(self, config=None, **changes) -> None:
        from dataclasses import fields

        import motionbits

        kinds = {f.name: f.type if isinstance(f.type, str) else f.type.__name__
                 for f in fields(motionbits.MotionBitsConfig)}
        for name, value in changes.items():
            if name not in kinds:
                raise ValueError(f"unknown MotionBitsConfig field {name!r}; known: "
                                 + ", ".join(kinds))
            if isinstance(value, str):
                changes[name] = _from_text(name, kinds[name], value)
        self.config, self.changes = config, changes
        self._config()  # fail now on a bad value, not in the middle of a benchmark

    def _config(self):
        import motionbits

        config = self.config or motionbits.MotionBitsConfig()
        if isinstance(config, dict):
            config = motionbits.MotionBitsConfig(**config)
        return config.with_(**self.changes) if self.changes else config

    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        import motionbits

        segment_video = getattr(motionbits, "segment_video", None)
        if segment_video is None:
            raise ImportError("motionbits.segment_video is not available in this installation")
        last = None
        for result in segment_video(frames, self._config()):
            last = result
        if last is None:
            raise ValueError("segment_video yielded no result (a clip needs >= 2 frames)")
        return np.asarray(last.labels, dtype=np.int32)
