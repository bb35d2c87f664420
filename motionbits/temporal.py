"""The segmenter's temporal state: over the whole video (the paper) or a sliding window.

The temporal constraints of the paper (Sec. 5.1) read two things from every earlier frame:
the label history -- the meet of all earlier label partitions, one integer map carried by
the flow (see :mod:`motionbits.identity`) -- and the largest earlier weight of every graph
edge. Both are folds (meet, max) that cannot be undone when a frame leaves a window, so
a window of N frames keeps P staggered copies of the state, each restarted every N frames
and N / P frames after the previous one; the constraints read the copy restarted longest
ago, which covers the last m folded frames, N - ceil(N / P) < m <= N (so m > 3N/4 with
the default P = 4). Without a window there is
one copy, never restarted: the paper's whole-video constraints, at constant memory.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from motionbits.flow import nearest_maps, sample_maps, warp_nearest
from motionbits.identity import refine_history

__all__ = ["TemporalState", "WINDOW_PARTS"]

#: Staggered copies kept for a sliding window: the window covers more than 3/4 of N frames.
WINDOW_PARTS = 4


class TemporalState:
    """Label history and past edge maxima, over the whole video or the last ``window`` frames.

    Args:
        pixel_shape: (h, w) working resolution of the label maps.
        edge_shape: (n, k) graph edges (nodes x neighbours).
        window: N >= 2 label maps, or ``None`` for the whole video.
        parts: staggered copies for a window (1 < parts <= window); ignored without one.

    Attributes:
        histories: (P, h, w) int32 meet of the label partitions each copy covers.
        past_max: (P, n, k) largest edge weight each copy covers.
        covered: (P,) label maps folded into each copy since its last restart.
    """

    def __init__(self, pixel_shape: tuple[int, int], edge_shape: tuple[int, int],
                 window: int | None = None, parts: int = WINDOW_PARTS):
        if window is not None and window < 2:
            raise ValueError(f"window must be >= 2 frames or None, got {window}")
        p = 1 if window is None else max(2, min(parts, window))
        self.window = window
        self.histories = np.zeros((p,) + tuple(pixel_shape), np.int32)
        self.past_max = np.zeros((p,) + tuple(edge_shape))
        self.covered = np.zeros(p, np.int64)
        # copy i restarts when the number of folded maps is offset[i] modulo the window
        self.offsets = (np.arange(p) * (window or 1)) // p
        self.folded = 0

    @property
    def oldest(self) -> int:
        """Index of the copy the constraints read (the one covering the most frames)."""
        return int(np.argmax(self.covered))

    def carry(self, maps: list[np.ndarray], flow_back: np.ndarray,
              flow_maps: tuple[np.ndarray, np.ndarray] | None = None
              ) -> tuple[list[np.ndarray], np.ndarray]:
        """Carry every history copy, and ``maps`` along with them, to the current frame.

        Args:
            maps: (h, w) int32 maps of the previous frame to carry too (the label map...),
                with the same pixel maps.
            flow_back: (h, w, 2) flow from the current frame to the previous one.
            flow_maps: ``motionbits.flow.sample_maps(flow_back)`` if already computed.

        Returns:
            (carried maps, history): ``maps`` carried, and the carried history the
            constraints read, (h, w) int32. The copies are kept carried for :meth:`fold`.
        """
        # the nearest-pixel maps are converted once (cv2.remap converts float maps on
        # every call, the same way) and each map is remapped alone: stacking the maps into
        # channels and splitting them again costs more than the remaps
        nearest = nearest_maps(*(sample_maps(flow_back) if flow_maps is None else flow_maps))
        carried = [warp_nearest(h, flow_back, maps=nearest) for h in self.histories]
        self.histories = carried[0][None] if len(carried) == 1 else np.stack(carried)
        return ([warp_nearest(m, flow_back, maps=nearest) for m in maps],
                self.histories[self.oldest])

    def project(self, project: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Move the past edge maxima onto the current graph.

        Args:
            project: maps (P, n, k) weights of the previous graph to (P, n, k) of this one.

        Returns:
            (n, k) largest earlier weight of each edge, as the constraints read it.
        """
        self.past_max = project(self.past_max)
        return self.past_max[self.oldest]

    def fold(self, raw: np.ndarray, labels: np.ndarray, margin: int) -> None:
        """Add this frame: its edge weights ``raw`` (n, k) and its label map (h, w).

        ``margin`` is passed to :func:`motionbits.identity.refine_history`. Copies due a
        restart start again from this frame alone.
        """
        self.past_max = np.maximum(self.past_max, raw)
        refined = [refine_history(h, labels, margin=margin) for h in self.histories]
        self.histories = refined[0][None] if len(refined) == 1 else np.stack(refined)
        self.folded += 1
        self.covered += 1
        if self.window is None:
            return
        for i in np.flatnonzero((self.folded - self.offsets) % self.window == 0):
            self.past_max[i] = raw
            self.histories[i] = refine_history(np.zeros_like(labels), labels, margin=margin)
            self.covered[i] = 1
