"""H.264 mp4 files that browsers play (PyAV, which ships its own FFmpeg with libx264).

OpenCV's ``mp4v`` writes MPEG-4 Part 2, which Chromium and Firefox do not play; this
writes H.264 (``avc1``), yuv420p, with the index at the front of the file
(``+faststart``) so a browser can start playing before the download ends.
"""

from __future__ import annotations

import numbers
import os
from fractions import Fraction
from pathlib import Path
from typing import Iterable

import numpy as np

__all__ = ["H264Writer", "write_h264", "MAX_FPS", "VIDEO_SUFFIXES"]

#: The largest frame rate an mp4 time base holds (a 32-bit numerator); above it PyAV
#: raises OverflowError.
MAX_FPS = 2**31 - 1
#: Containers that take H.264 and the ``+faststart`` option.
VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov")


def check_video_path(path: "str | os.PathLike", fps: float) -> Path:
    """``path`` as a Path, after checking it names an mp4 file and ``fps`` is usable.

    Raises:
        ValueError: ``fps`` is not a number in (0, MAX_FPS], or the suffix is not an mp4 one.
        IsADirectoryError: ``path`` is a folder.
    """
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not 0 < fps <= MAX_FPS:
        raise ValueError(f"fps must be a number > 0 and <= {MAX_FPS}, got {fps!r}")
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder; pass the video file to write, e.g. {path / 'video.mp4'}")
    if path.suffix.lower() not in VIDEO_SUFFIXES:
        raise ValueError(f"{path}: an H.264 video must end in {' or '.join(VIDEO_SUFFIXES)}, "
                         f"got {path.suffix or 'no suffix'!r}")
    return path


class H264Writer:
    """Append (H, W, 3) uint8 RGB frames to an H.264 mp4; use as a context manager.

    Odd widths or heights are padded by one black pixel (yuv420p needs even sizes).

    Args:
        path: output file, ``.mp4`` / ``.m4v`` / ``.mov`` (parent folders are created).
        fps: frames per second (> 0, at most :data:`MAX_FPS`).
        crf: x264 quality, 0 (lossless) .. 51; 20 looks clean on overlays.

    Example:
        >>> import tempfile, os
        >>> path = os.path.join(tempfile.mkdtemp(), "clip.mp4")
        >>> with H264Writer(path, fps=5) as w:
        ...     for t in range(3):
        ...         w.write(np.full((32, 48, 3), 40 * t, np.uint8))
        >>> import av; av.open(path).streams.video[0].codec_context.name
        'h264'
    """

    def __init__(self, path: "str | os.PathLike", fps: float = 10.0, crf: int = 20) -> None:
        self.path = check_video_path(path, fps)
        import av  # core dependency; imported here so `import motionbits` stays light

        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._av = av
        self._container = av.open(str(self.path), mode="w", options={"movflags": "+faststart"})
        self._fps = Fraction(fps).limit_denominator(1001)
        self._crf = int(crf)
        self._stream = None
        self._size: tuple[int, int] | None = None
        self.frames_written = 0

    def write(self, frame: np.ndarray) -> None:
        """Append one (H, W, 3) uint8 RGB frame; every frame must have the first one's size."""
        if not (isinstance(frame, np.ndarray) and frame.dtype == np.uint8 and frame.ndim == 3
                and frame.shape[2] == 3):
            raise ValueError(f"frames must be (H, W, 3) uint8 RGB arrays, got {getattr(frame, 'shape', type(frame))}")
        h, w = frame.shape[:2]
        if self._stream is None:
            self._size = (h, w)
            self._stream = self._container.add_stream("libx264", rate=self._fps)
            self._stream.width, self._stream.height = w + w % 2, h + h % 2
            self._stream.pix_fmt = "yuv420p"
            self._stream.options = {"crf": str(self._crf)}
            self._stream.codec_context.codec_tag = "avc1"
        elif (h, w) != self._size:
            raise ValueError(f"frame {self.frames_written} is {w}x{h}; the video is {self._size[1]}x{self._size[0]}")
        if h % 2 or w % 2:
            frame = np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)))
        video_frame = self._av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format="rgb24")
        for packet in self._stream.encode(video_frame):
            self._container.mux(packet)
        self.frames_written += 1

    def close(self) -> Path:
        """Flush the encoder and close the file; returns its path."""
        if self._container is not None:
            try:
                if self._stream is not None:
                    for packet in self._stream.encode():
                        self._container.mux(packet)
            finally:
                self._container.close()
                self._container = None
        return self.path

    def __enter__(self) -> "H264Writer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_h264(frames: Iterable[np.ndarray], path: "str | os.PathLike", fps: float = 10.0) -> Path:
    """Write (H, W, 3) uint8 RGB frames to an H.264 mp4; returns ``path``.

    Raises:
        ValueError: no frames, frames of different sizes or not RGB uint8, ``fps`` not in
            (0, MAX_FPS], or ``path`` without an mp4 suffix.
        IsADirectoryError: ``path`` is a folder.
    """
    with H264Writer(path, fps) as writer:
        for frame in frames:
            writer.write(frame)
    if writer.frames_written == 0:
        Path(path).unlink(missing_ok=True)
        raise ValueError("no frames to write")
    return Path(path)
