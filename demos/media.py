"""Files the demos hand out: browser-playable H.264 video, label maps as a zip, example clips."""

from __future__ import annotations

import io
import os
import zipfile
from fractions import Fraction
from pathlib import Path
from typing import Sequence

import numpy as np
from PIL import Image

__all__ = ["write_h264", "write_labels_zip", "write_demo_clip"]


def write_h264(frames: Sequence[np.ndarray], path: "str | os.PathLike", fps: float = 10.0) -> Path:
    """Write (H, W, 3) uint8 RGB frames as an H.264 (yuv420p) mp4 that browsers play (PyAV).

    Odd sizes are cropped by one pixel (yuv420p needs even sides).
    """
    import av

    if not frames:
        raise ValueError("no frames to write")
    if not fps > 0:
        raise ValueError(f"fps must be > 0, got {fps}")
    h, w = (s - s % 2 for s in frames[0].shape[:2])
    path = Path(path)
    with av.open(str(path), mode="w") as container:
        stream = container.add_stream("libx264", rate=Fraction(fps).limit_denominator(1000))
        stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
        stream.options = {"crf": "23", "preset": "veryfast", "movflags": "+faststart"}
        for f in frames:
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(f[:h, :w]), format="rgb24")
            container.mux(stream.encode(frame))
        container.mux(stream.encode())
    return path


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
