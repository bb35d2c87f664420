"""A stand-in segmenter for tests and demos: it returns fixed label maps.

``FixedSegmenter`` follows the ``frames -> label maps`` interface of
:class:`somprompt.Segmenter`. For a scripted VLM use ``StubVLM`` of ``vlm_adapters``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

__all__ = ["FixedSegmenter"]


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
