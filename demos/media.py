"""Files the demos hand out: label maps as a zip, the generated example clip (H.264)."""

from __future__ import annotations

import io
import os
import zipfile
from pathlib import Path
from typing import Sequence

import numpy as np
from PIL import Image

from motionbits.video_writer import write_h264

__all__ = ["write_labels_zip", "write_demo_clip"]


def write_labels_zip(label_maps: Sequence[np.ndarray], frame_indices: Sequence[int],
                     path: "str | os.PathLike") -> Path:
    """Zip of 16-bit PNG label maps ``NNNNN.png`` (video frame index; 0 = background)."""
    path = Path(path)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for i, labels in zip(frame_indices, label_maps):
            buf = io.BytesIO()
            Image.fromarray(np.asarray(labels).astype(np.uint16)).save(buf, format="PNG")
            zf.writestr(f"{int(i):05d}.png", buf.getvalue())
    return path


def write_demo_clip(path: "str | os.PathLike", n_frames: int = 16,
                    size: tuple[int, int] = (240, 320), fps: float = 10.0) -> Path:
    """The built-in generated clip (``motionbits.synth.demo_clip``) as an H.264 mp4."""
    from motionbits.synth import demo_clip

    return write_h264(list(demo_clip(n_frames=n_frames, size=size).frames), path, fps)
