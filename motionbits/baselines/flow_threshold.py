"""Baseline (a): flow magnitude threshold + connected components.

Pixels of the last frame that moved at some time (``motion_evidence``), cleaned by a
morphological opening, split into 8-connected components; components smaller than
``min_area`` (a fraction of the image) are dropped. Touching bodies merge into one label.
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.baselines.motion_evidence import motion_evidence
from motionbits.flow import DISFlow, FlowBackend

__all__ = ["FlowThresholdCC", "clean_components"]


def clean_components(mask: np.ndarray, min_area: float = 0.001, open_px: int = 2) -> np.ndarray:
    """(H, W) bool -> (H, W) int32 connected components of the opened mask, small ones 0."""
    k = 2 * open_px + 1
    m = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_OPEN,
                         cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))) if open_px else mask.astype(np.uint8)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    keep = np.zeros(n, np.int32)
    big = [i for i in range(1, n) if stats[i, cv2.CC_STAT_AREA] >= min_area * mask.size]
    keep[big] = np.arange(1, len(big) + 1)
    return keep[lab]


class FlowThresholdCC:
    """Moving pixels (flow magnitude > ``threshold`` px/frame at any time) -> components.

    Args:
        threshold: px per frame.
        min_area: smallest component kept, as a fraction of the image.
        flow: flow backend (default OpenCV DIS, MEDIUM preset).
    """

    def __init__(self, threshold: float = 1.0, min_area: float = 0.001,
                 flow: FlowBackend | None = None) -> None:
        self.threshold, self.min_area = float(threshold), float(min_area)
        self.flow = flow or DISFlow("medium")

    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        moved, _ = motion_evidence(frames, self.flow, self.threshold)
        return clean_components(moved, self.min_area)
