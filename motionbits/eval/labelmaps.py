"""Label maps: validation, compact relabelling, and 16-bit PNG reading and writing.

A label map is an (H, W) integer array: 0 = background (static or not an object),
k > 0 = one object. Labels need not be 1..K; any non-negative integers work.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from motionbits.objects import check_label_map  # the one label-map check of the toolkit

__all__ = ["check_label_map", "compact_labels", "read_label_map", "write_label_map"]

_LUT_MAX = 1 << 20  # labels up to this value are compacted with a lookup table, not a sort


def compact_labels(flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Relabel non-negative integer labels to 0..K keeping 0 as background.

    Args:
        flat: (N,) int64 labels.

    Returns:
        ``(index, ids)``: (N,) int64 with 0 for background and 1..K for objects, and the
        (K,) int64 original object ids in increasing order (``ids[index - 1]`` recovers them).
    """
    if flat.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    top = int(flat.max())
    if top < _LUT_MAX:
        present = np.bincount(flat, minlength=top + 1) > 0
        present[0] = False
        ids = np.flatnonzero(present).astype(np.int64)
        lut = np.zeros(top + 1, np.int64)
        lut[ids] = np.arange(1, ids.size + 1)
        return lut[flat], ids
    uniq, inv = np.unique(flat, return_inverse=True)
    if uniq[0] == 0:
        return inv.astype(np.int64), uniq[1:].astype(np.int64)
    return inv.astype(np.int64) + 1, uniq.astype(np.int64)


def read_label_map(path: str | os.PathLike) -> np.ndarray:
    """Read a label map PNG (16-bit grayscale, 8-bit grayscale or palette-indexed).

    Returns:
        (H, W) int32 labels; for palette images, the palette indices.

    Raises:
        FileNotFoundError: the file does not exist.
        ValueError: the file is not a single-channel or indexed image.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"label map not found: {path}")
    try:
        with Image.open(path) as im:
            mode = im.mode
            if mode in ("RGB", "RGBA", "LA", "CMYK", "YCbCr", "HSV", "LAB"):
                raise ValueError(
                    f"{path} is a {mode} image; a label map must be a single-channel (16-bit "
                    "or 8-bit) or palette-indexed PNG whose values are object ids"
                )
            arr = np.asarray(im)
    except ValueError:
        raise
    except Exception as exc:  # PIL raises several types for corrupt files
        raise ValueError(f"could not read label map {path}: {exc}") from exc
    if arr.ndim != 2:
        raise ValueError(f"{path}: expected a single-channel label map, got shape {arr.shape}")
    if arr.dtype == bool:
        arr = arr.astype(np.uint8)
    return arr.astype(np.int32)


def write_label_map(path: str | os.PathLike, labels: np.ndarray) -> None:
    """Write an (H, W) label map with labels in 0..65535 as a 16-bit grayscale PNG.

    Raises:
        IsADirectoryError: ``path`` is a folder.
        ValueError: ``path`` does not end in ``.png`` (a JPEG or BMP would keep 8 bits, lossily),
            or labels beyond 65535.
    """
    labels = check_label_map(np.asarray(labels), name=f"label map for {path}")
    if labels.size and labels.max() > 65535:
        raise ValueError(f"labels up to {labels.max()} do not fit a 16-bit PNG (max 65535)")
    path = Path(path)
    if path.is_dir():  # else OpenCV's "could not find a writer for the specified extension"
        raise IsADirectoryError(f"{path} is a folder; pass the PNG file to write, e.g. {path / 'gt.png'}")
    if path.suffix.lower() != ".png":  # OpenCV wrote .jpg / .bmp as 8 bits: ids above 255 lost
        raise ValueError(f"{path}: a label map is written as a 16-bit PNG and must end in .png, "
                         f"got {path.suffix or 'no suffix'!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), labels.astype(np.uint16)):
        raise ValueError(f"could not write {path} (is the suffix .png?)")
