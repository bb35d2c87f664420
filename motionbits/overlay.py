"""Coloured label overlays for looking at results (the set-of-mark renderer is ``somprompt``)."""

from __future__ import annotations

import colorsys

import cv2
import numpy as np

__all__ = ["label_color", "overlay_labels"]


def label_color(label: int) -> tuple[int, int, int]:
    """A distinct, stable RGB colour for a label id (golden-ratio hue steps)."""
    h = (label * 0.618033988749895) % 1.0
    r, g, b = colorsys.hsv_to_rgb(h, 0.85, 1.0)
    return int(255 * r), int(255 * g), int(255 * b)


def overlay_labels(frame: np.ndarray, labels: np.ndarray, alpha: float = 0.5) -> np.ndarray:
    """Blend coloured masks and white contours of ``labels`` over ``frame``.

    Args:
        frame: (H, W, 3) uint8 RGB.
        labels: (H, W) int label map (0 = background, left untouched).
        alpha: opacity of the mask colours.

    Returns:
        (H, W, 3) uint8 RGB.
    """
    if labels.shape != frame.shape[:2]:
        raise ValueError(f"labels {labels.shape} and frame {frame.shape[:2]} differ in size")
    out = frame.copy()
    ids = np.unique(labels[labels > 0])
    if len(ids) == 0:
        return out
    lut = np.zeros((int(ids.max()) + 1, 3), np.float32)
    for i in ids:
        lut[i] = label_color(int(i))
    m = labels > 0
    out[m] = (out[m] * (1 - alpha) + lut[labels[m]] * alpha).astype(np.uint8)
    for i in ids:
        contours, _ = cv2.findContours((labels == i).astype(np.uint8), cv2.RETR_EXTERNAL,
                                       cv2.CHAIN_APPROX_NONE)
        cv2.drawContours(out, contours, -1, (255, 255, 255), 1)
    return out
