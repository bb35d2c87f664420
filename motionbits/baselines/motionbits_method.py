"""The MotionBits segmenter as a benchmark method (its module is imported when the method
is first made, so it does not slow down the other methods' start-up)."""

from __future__ import annotations

import numpy as np

from motionbits.config import MotionBitsConfig
from motionbits.segmenter import segment_video

__all__ = ["MotionBitsMethod"]


class MotionBitsMethod:
    """``frames -> (H, W) int32`` labels of the last frame, by :func:`motionbits.segment_video`.

    Args:
        config: a :class:`MotionBitsConfig` (default: the paper's parameters), or a dict
            of its fields.
        **changes: fields to change on top of ``config`` (e.g. ``exact=True``).
    """

    def __init__(self, config: MotionBitsConfig | dict | None = None, **changes) -> None:
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
