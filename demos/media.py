"""Files the demos hand out: label maps as a zip, the generated example clip (H.264)."""

from __future__ import annotations

import io
import os
import zipfile
from pathlib import Path
from typing import Sequence

import numpy as np
from PIL import Image

from motionbits.frames import whole_number
from motionbits.objects import check_label_map
from motionbits.video_writer import write_h264
from somprompt.registry import whole_ids

__all__ = ["write_labels_zip", "write_demo_clip"]


def write_labels_zip(label_maps: Sequence[np.ndarray], frame_indices: Sequence[int],
                     path: "str | os.PathLike") -> Path:
    """Zip of 16-bit PNG label maps ``NNNNN.png`` (video frame index; 0 = background).

    Raises:
        TypeError, ValueError: a map that is not an (H, W) integer label map with ids in
            0..65535 (a 16-bit PNG holds no more), a frame index that is not a whole number
            >= 0, two maps with the same index, or not one index per map.
    """
    label_maps, frame_indices = list(label_maps), whole_ids(frame_indices, "frame_indices", "frame indices")
    if len(label_maps) != len(frame_indices):  # else zip() dropped the maps without an index
        raise ValueError(f"got {len(label_maps)} label maps but {len(frame_indices)} frame indices; "
                         "pass one index per map")
    if any(i < 0 for i in frame_indices) or len(set(frame_indices)) != len(frame_indices):
        raise ValueError(f"frame_indices must be distinct whole numbers >= 0, got {frame_indices[:20]}")
    maps = []
    for i, labels in zip(frame_indices, label_maps):
        lm = check_label_map(np.asarray(labels), name=f"label map of frame {i}")
        if lm.size and lm.max() > 65535:  # else wrapped around in uint16: other ids
            raise ValueError(f"label map of frame {i} holds ids up to {lm.max()}; a 16-bit PNG holds at most 65535")
        maps.append(lm)
    path = Path(path)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for i, lm in zip(frame_indices, maps):
            buf = io.BytesIO()
            Image.fromarray(lm.astype(np.uint16)).save(buf, format="PNG")
            zf.writestr(f"{i:05d}.png", buf.getvalue())
    return path


def write_demo_clip(path: "str | os.PathLike", n_frames: int = 16,
                    size: tuple[int, int] = (240, 320), fps: float = 10.0) -> Path:
    """The built-in generated clip (``motionbits.synth.demo_clip``) as an H.264 mp4.

    ``n_frames`` >= 1 and ``size`` (H, W) are whole numbers (each side >= 1 px).
    """
    from motionbits.synth import demo_clip

    whole_number("n_frames", n_frames)  # else "'float' object cannot be interpreted as an integer"
    if (isinstance(size, (str, bytes)) or not isinstance(size, Sequence) or len(size) != 2
            or any(whole_number("size", v) < 1 for v in size)):  # else OpenCV's "inv_scale_x > 0"
        raise ValueError(f"size must be (height, width), two whole numbers >= 1, got {size!r:.40}")

    return write_h264(list(demo_clip(n_frames=n_frames, size=size).frames), path, fps)
