"""Frames in one form, and which frames to show: the helpers every package shares.

``somprompt`` and ``vlm_adapters`` use these (never copies), so a frame is accepted or
refused, and a clip is sampled, the same way everywhere. Imports only numpy.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

__all__ = ["as_rgb_array", "sample_frame_indices"]


def as_rgb_array(frame: Any, *, name: str = "frame") -> np.ndarray:
    """One frame as a C-contiguous (H, W, 3) uint8 RGB array (no copy when it already is).

    Accepted: (H, W, 3) uint8 RGB; (H, W) or (H, W, 1) uint8 greyscale (replicated to
    three channels); (H, W, 4) uint8 RGBA (alpha dropped); a PIL image of any mode
    (converted to RGB). 16-bit input (uint16 arrays of either byte order, PIL modes
    "I;16", "I;16B" and "I" with values in 0..65535) is scaled to 8 bits by 255 / 65535,
    not clipped. Float images (arrays, PIL mode "F") are refused rather than guessed at
    ([0, 1] or [0, 255]?): the error says how to convert them.

    Args:
        frame: the frame.
        name: what to call it in error messages.

    Raises:
        TypeError: not an array or PIL image, or not uint8.
        ValueError: wrong number of dimensions or channels, or an empty image.

    Example:
        >>> as_rgb_array(np.zeros((2, 3), np.uint8)).shape
        (2, 3, 3)
    """
    if hasattr(frame, "convert") and hasattr(frame, "size") and not isinstance(frame, np.ndarray):
        # a PIL image, without importing PIL here; 16-bit modes keep their values, and
        # float ones ("F") are refused below like float arrays (convert("RGB") would clip
        # values in [0, 1] to a black frame)
        frame = np.asarray(frame if frame.mode.startswith(("I", "F")) else frame.convert("RGB"))
        if frame.dtype.kind == "i":  # mode "I" (int32)
            if frame.size and (frame.min() < 0 or frame.max() > 65535):
                raise ValueError(f"{name} is a 32-bit integer image with values outside 0..65535")
            frame = frame.astype(np.uint16)
    if isinstance(frame, np.ndarray) and frame.dtype.kind == "u" and frame.dtype.itemsize == 2:
        # uint16 in either byte order (PIL's "I;16B", big-endian FITS / TIFF data)
        frame = ((frame.astype(np.uint32) * 255 + 32767) // 65535).astype(np.uint8)
    if not isinstance(frame, np.ndarray):
        raise TypeError(
            f"{name} must be an (H, W, 3) uint8 RGB numpy array or a PIL image, got {type(frame).__name__}"
        )
    if frame.dtype != np.uint8:
        hint = _float_hint(frame) if np.issubdtype(frame.dtype, np.floating) else ""
        raise TypeError(f"{name} must be uint8 RGB, got dtype {frame.dtype}{hint}")
    if frame.ndim == 3 and frame.shape[2] == 1:
        frame = frame[..., 0]
    if frame.ndim == 2:
        frame = np.repeat(frame[..., None], 3, axis=2)
    elif frame.ndim == 3 and frame.shape[2] == 4:
        frame = frame[..., :3]
    if frame.ndim != 3 or frame.shape[2] != 3:
        first = (frame.ndim == 3 and frame.shape[0] in (1, 3, 4)
                 and min(frame.shape[1:]) > 4)  # a channels-first (torch) layout
        raise ValueError(
            f"{name} must have shape (H, W, 3) (RGB), (H, W) (greyscale) or (H, W, 4) (RGBA); "
            f"got {frame.shape}"
            + ("; it looks channels-first (C, H, W): pass frame.transpose(1, 2, 0)"
               if first else "")
        )
    if frame.shape[0] == 0 or frame.shape[1] == 0:
        raise ValueError(f"{name} is empty: shape {frame.shape}")
    return np.ascontiguousarray(frame)


def _float_hint(frame: np.ndarray) -> str:
    """How to convert a float frame to uint8, from its values: the [0, 1] recipe would turn
    a frame in [0, 255] white, and neither recipe is defined for NaN or infinity."""
    if frame.size and not np.isfinite(frame).all():
        return "; it also holds NaN or infinite values: replace them first (e.g. np.nan_to_num)"
    if frame.size and frame.max() > 1:
        return (f"; its values reach {frame.max():g}: if they are in [0, 255], convert with "
                "np.clip(img, 0, 255).astype(np.uint8)")
    return "; convert floats in [0, 1] with np.clip(img * 255, 0, 255).astype(np.uint8)"


def sample_frame_indices(num_total: int, num_frames: int | None) -> list[int]:
    """Indices of up to ``num_frames`` frames spread evenly over ``num_total``; the last
    frame is always kept (the paper scores it), and the first too when two or more are
    asked for.

    ``None`` or ``num_frames >= num_total`` keeps every frame. Both are whole numbers
    (ints, numpy's, or floats such as 8.0 from a UI slider); anything else raises TypeError.

    Example:
        >>> sample_frame_indices(10, 4), sample_frame_indices(10, 1)
        ([0, 3, 6, 9], [9])
    """
    num_total = whole_number("num_total", num_total)
    num_frames = None if num_frames is None else whole_number("num_frames", num_frames)
    if num_total < 1:
        raise ValueError(f"there are no frames to sample from (num_total = {num_total})")
    if num_frames is None or num_frames >= num_total:
        return list(range(num_total))
    if num_frames < 1:
        raise ValueError(f"num_frames must be >= 1 or None, got {num_frames}")
    if num_frames == 1:
        return [num_total - 1]
    return sorted({int(round(v)) for v in np.linspace(0, num_total - 1, num_frames)})


def whole_number(name: str, value: Any) -> int:
    """``value`` as an int if it is a whole number (8, np.int64(8), 8.0, 2**2000); else TypeError
    naming ``name`` (True would read as 1 frame, 2.5 and NaN failed inside range() or np.linspace)."""
    if (isinstance(value, bool) or not isinstance(value, numbers.Real)
            or not isinstance(value, numbers.Integral) and not float(value).is_integer()):
        raise TypeError(f"{name} must be a whole number, got {type(value).__name__} {value!r:.40}")
    return int(value)


def finite_number(name: str, value: Any) -> float:
    """``value`` as a float if it is a finite real number; else TypeError (not a number, or
    a bool) or ValueError (NaN, inf) naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {type(value).__name__} {value!r:.40}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return float(value)


def fraction(name: str, value: Any) -> float:
    """``value`` as a float if it is a real number in [0, 1] (not a bool); else ValueError
    naming ``name`` (NaN compares false with every threshold)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 <= value <= 1:
        raise ValueError(f"{name} must be a number in [0, 1], got {value!r:.40}")
    return float(value)
