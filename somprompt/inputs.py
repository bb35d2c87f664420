"""Validation of frames and label maps, with errors that say what was wrong and what to do.

Every public entry point of :mod:`somprompt` goes through these helpers, so a bad input
fails at the call that received it, never deep inside numpy or OpenCV.
"""

from __future__ import annotations

from typing import Union

import numpy as np
from PIL import Image

__all__ = ["ImageLike", "as_rgb_array", "like_input", "check_label_map"]

ImageLike = Union[np.ndarray, Image.Image]


def as_rgb_array(scene: ImageLike, *, name: str = "scene") -> np.ndarray:
    """Return ``scene`` as a C-contiguous (H, W, 3) uint8 RGB array (a copy is not made
    for numpy input that already qualifies).

    Args:
        scene: (H, W, 3) uint8 RGB numpy array, or a PIL image of any mode (converted
            to RGB; 16-bit and 32-bit integer modes scaled from 0..65535, not clipped).
        name: what to call the argument in error messages.

    Raises:
        TypeError: not an array / PIL image, or not uint8.
        ValueError: wrong number of dimensions or channels, or an empty image.
    """
    if isinstance(scene, Image.Image):
        if scene.mode.startswith("I"):  # "I;16*" / "I": 16-bit values; convert() would clip
            grey = np.asarray(scene).astype(np.int64)
            if grey.size and (grey.min() < 0 or grey.max() > 65535):
                raise ValueError(f"{name} is a mode {scene.mode} image with values outside 0..65535")
            grey = ((grey * 255 + 32767) // 65535).astype(np.uint8)
            return np.repeat(grey[..., None], 3, axis=2)
        return np.asarray(scene.convert("RGB")).copy()
    if not isinstance(scene, np.ndarray):
        raise TypeError(
            f"{name} must be a numpy (H, W, 3) uint8 RGB array or a PIL image, "
            f"got {type(scene).__name__}"
        )
    if scene.dtype != np.uint8:
        hint = (
            "; convert floats in [0, 1] with np.clip(img * 255, 0, 255).astype(np.uint8)"
            if np.issubdtype(scene.dtype, np.floating) else ""
        )
        raise TypeError(f"{name} must be uint8 RGB, got dtype {scene.dtype}{hint}")
    if scene.ndim != 3 or scene.shape[2] != 3:
        hint = (
            "; for grayscale use np.repeat(img[..., None], 3, axis=2)" if scene.ndim == 2
            else "; for RGBA drop alpha with img[..., :3]" if scene.ndim == 3 and scene.shape[2] == 4
            else ""
        )
        raise ValueError(f"{name} must have shape (H, W, 3) (RGB), got {scene.shape}{hint}")
    if scene.shape[0] == 0 or scene.shape[1] == 0:
        raise ValueError(f"{name} is empty: shape {scene.shape}")
    return np.ascontiguousarray(scene)


def like_input(result: np.ndarray, original: ImageLike) -> ImageLike:
    """Return ``result`` ((H, W, 3) uint8) as the type of ``original`` (PIL in, PIL out)."""
    if isinstance(original, Image.Image):
        return Image.fromarray(result)  # (H, W, 3) uint8 -> mode "RGB"
    return result


def check_label_map(
    labels: np.ndarray,
    shape: tuple[int, int] | None = None,
    *,
    name: str = "labels",
) -> np.ndarray:
    """Validate an (H, W) label map and return it as an int64 array.

    A label map holds 0 for background and k > 0 for object k. Boolean maps are
    accepted as a single object with id 1.

    Args:
        labels: (H, W) array of non-negative integers (any integer dtype) or bool.
        shape: (H, W) that the map must have (the frame it belongs to), or None.
        name: what to call the argument in error messages.

    Returns:
        (H, W) int64 array (the input itself when it already is one).

    Raises:
        TypeError: not a numpy array, or not an integer/bool dtype.
        ValueError: not 2-D, negative ids, or a size that differs from ``shape``.
    """
    if not isinstance(labels, np.ndarray):
        raise TypeError(
            f"{name} must be an (H, W) numpy integer array (0 = background, k > 0 = object k), "
            f"got {type(labels).__name__}"
        )
    if labels.dtype == np.bool_:
        labels = labels.astype(np.int64)
    elif not np.issubdtype(labels.dtype, np.integer):
        raise TypeError(
            f"{name} must have an integer dtype (0 = background, k > 0 = object k), got "
            f"{labels.dtype}; if it holds whole numbers, use labels.astype(np.int32)"
        )
    if labels.ndim == 3 and labels.shape[2] == 1:
        labels = labels[..., 0]
    if labels.ndim != 2:
        raise ValueError(f"{name} must be an (H, W) label map, got shape {labels.shape}")
    if labels.size and labels.min() < 0:
        raise ValueError(f"{name} holds negative ids (min {labels.min()}); ids must be >= 0")
    if shape is not None and tuple(labels.shape) != tuple(shape[:2]):
        raise ValueError(
            f"{name} has size {labels.shape[1]}x{labels.shape[0]} (W x H) but the frame is "
            f"{shape[1]}x{shape[0]}; resize the label map with nearest-neighbour "
            "interpolation (cv2.INTER_NEAREST) to the frame size"
        )
    if labels.dtype != np.int64:
        labels = labels.astype(np.int64)
    return labels
