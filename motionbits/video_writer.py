"""H.264 mp4 files that browsers play (PyAV, which ships its own FFmpeg with libx264).

OpenCV's ``mp4v`` writes MPEG-4 Part 2, which Chromium and Firefox do not play; this
writes H.264 (``avc1``), yuv420p, with the index at the front of the file
(``+faststart``) so a browser can start playing before the download ends.
"""

from __future__ import annotations

import math
import numbers
import os
import uuid
from fractions import Fraction
from pathlib import Path
from collections.abc import Iterable

import numpy as np

from motionbits.frames import whole_number

__all__ = ["H264Writer", "write_h264", "MAX_FPS", "MIN_FPS", "MAX_SIDE", "VIDEO_SUFFIXES"]

#: The largest frame rate an mp4 time base holds (a 32-bit numerator); above it PyAV
#: raises OverflowError.
MAX_FPS = 2**31 - 1
#: The smallest frame rate (one frame per 1000 s): the rate is written as a fraction of
#: denominator at most 1001, so 1e-6 became 0 (and the file played at 24 fps).
MIN_FPS = 0.001
#: The largest width or height libx264 encodes (after padding to even sizes).
MAX_SIDE = 16384
#: Containers that take H.264 and the ``+faststart`` option.
VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov")


def check_video_path(path: "str | os.PathLike", fps: float) -> Path:
    """``path`` as a Path, after checking it names an mp4 file and ``fps`` is usable.

    Raises:
        ValueError: ``fps`` is not a number in [MIN_FPS, MAX_FPS], or the suffix is not an mp4 one.
        TypeError: ``path`` is not a file path.
        IsADirectoryError: ``path`` is a folder.
    """
    if (isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not math.isfinite(fps)
            or not MIN_FPS <= fps <= MAX_FPS):
        raise ValueError(f"fps must be a number >= {MIN_FPS} and <= {MAX_FPS}, got {fps!r}")
    if not isinstance(path, (str, os.PathLike)):  # else "expected str, bytes or os.PathLike"
        raise TypeError(f"path must be a file path, got {type(path).__name__} {path!r:.40}")
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
    The video is written to a temporary sibling file and renamed to ``path`` when closed
    without an error; on an error (leaving the ``with`` block by an exception, or
    :meth:`discard`) it is removed and an earlier file at ``path`` is left as it was.

    Args:
        path: output file, ``.mp4`` / ``.m4v`` / ``.mov`` (parent folders are created).
        fps: frames per second (:data:`MIN_FPS` .. :data:`MAX_FPS`).
        crf: x264 quality, a whole number 0 (lossless) .. 51; 20 looks clean on overlays.

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
        if whole_number("crf", crf) < 0 or crf > 51:  # else PyAV's OverflowError / x264 clamping
            raise ValueError(f"crf must be in [0, 51], got {crf}")
        import av  # core dependency; imported here so `import motionbits` stays light

        self._dest = self.path.absolute()  # the same file if the current folder changes
        parent = self._dest.parent
        # the file's mode as any new file's (mkstemp's would be 0600)
        self._tmp = parent / f".{self.path.stem}.partial-{uuid.uuid4().hex[:8]}{self.path.suffix}"
        self._av = av
        try:
            parent.mkdir(parents=True, exist_ok=True)
            self._container = av.open(str(self._tmp), mode="w", options={"movflags": "+faststart"})
        except OSError as exc:  # a parent that is a file: "[Errno 17] File exists"
            _remove(self._tmp)
            above = next((p for p in (parent, *parent.parents) if p.exists()), parent)
            why = f"{above} is a file, not a folder" if not above.is_dir() else exc.strerror or exc
            raise OSError(f"cannot write {self.path}: {why}") from exc
        self._fps = Fraction(float(fps)).limit_denominator(1001)  # np.float32: not a Rational
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
        if max(h + h % 2, w + w % 2) > MAX_SIDE:  # else libx264's "Generic error in an external library"
            raise ValueError(f"frames must be at most {MAX_SIDE} pixels a side for H.264, got {w}x{h}")
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
        """Flush the encoder, close the file and rename it to ``path``; returns ``path``."""
        if self._container is not None:
            try:
                if self._stream is not None:
                    for packet in self._stream.encode():
                        self._container.mux(packet)
                self._container.close()
                self._container = None
                if self._tmp.exists():  # PyAV creates no file for a video of no streams
                    os.replace(self._tmp, self._dest)
            except BaseException:
                self.discard()
                raise
        return self.path

    def discard(self) -> None:
        """Close without writing ``path`` (an earlier file there is left as it was)."""
        if self._container is not None:
            try:
                self._container.close()
            except Exception:  # noqa: BLE001 - the file is removed anyway
                pass
            self._container = None
        _remove(self._tmp)

    def __enter__(self) -> "H264Writer":
        return self

    def __exit__(self, kind, exc, tb) -> None:
        if kind is None:
            self.close()
        else:
            self.discard()


def _remove(path: Path) -> None:
    try:
        path.unlink(missing_ok=True)
    except OSError:  # its folder is gone or is a file: nothing to remove
        pass


def write_h264(frames: Iterable[np.ndarray], path: "str | os.PathLike", fps: float = 10.0) -> Path:
    """Write (H, W, 3) uint8 RGB frames to an H.264 mp4; returns ``path``.

    Nothing is written on an error: an earlier file at ``path`` is left as it was.

    Raises:
        ValueError: no frames, frames of different sizes or not RGB uint8, ``fps`` not in
            [MIN_FPS, MAX_FPS], or ``path`` without an mp4 suffix.
        TypeError: ``frames`` is not an iterable of frames.
        IsADirectoryError: ``path`` is a folder.
    """
    if isinstance(frames, (str, bytes)) or not isinstance(frames, Iterable):  # None: "not iterable"
        raise TypeError(f"frames must be an iterable of (H, W, 3) uint8 frames, got {type(frames).__name__}")
    with H264Writer(path, fps) as writer:
        for frame in frames:
            writer.write(frame)
        if writer.frames_written == 0:  # raised inside: the file is discarded, an old one kept
            raise ValueError("no frames to write")
    return Path(path)
