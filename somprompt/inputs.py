"""Validation of frames and label maps, with errors that say what was wrong and what to do.

Every public entry point of :mod:`somprompt` goes through these helpers, so a bad input
fails at the call that received it, never deep inside numpy or OpenCV. ``as_rgb_array``
and ``check_label_map`` are the ones all three packages share (``motionbits.frames``,
``motionbits.objects``).
"""

from __future__ import annotations

from typing import Union

import numpy as np
from PIL import Image

from motionbits.frames import as_rgb_array
from motionbits.objects import check_label_map

__all__ = ["ImageLike", "as_rgb_array", "like_input", "check_label_map"]

ImageLike = Union[np.ndarray, Image.Image]


def like_input(result: np.ndarray, original: ImageLike) -> ImageLike:
    """Return ``result`` ((H, W, 3) uint8) as the type of ``original`` (PIL in, PIL out)."""
    if isinstance(original, Image.Image):
        return Image.fromarray(result)  # (H, W, 3) uint8 -> mode "RGB"
    return result
