"""The MotionBits segmenter as a benchmark method (imported lazily: it may not be installed
in this checkout yet, and it should not slow down the other methods' start-up)."""

from __future__ import annotations

import numpy as np

__all__ = ["MotionBitsMethod"]


class MotionBitsMethod:
    """``motionbits.segment_video(frames, config)``; the last yielded result's ``labels``.

    Args:
        config: a ``motionbits.MotionBitsConfig`` (default: the paper's parameters), or a
            dict of its fields to change.
    """

    def __init__(self, config=None, **changes) -> None:
        self.config, self.changes = config, changes

    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        import motionbits

        segment_video = getattr(motionbits, "segment_video", None)
        if segment_video is None:
            raise ImportError("motionbits.segment_video is not available in this installation")
        config = self.config or motionbits.MotionBitsConfig()
        if isinstance(config, dict):
            config = motionbits.MotionBitsConfig(**config)
        if self.changes:
            config = config.with_(**self.changes)
        last = None
        for result in segment_video(frames, config):
            last = result
        if last is None:
            raise ValueError("segment_video yielded no result (a clip needs >= 2 frames)")
        return np.asarray(last.labels, dtype=np.int32)
