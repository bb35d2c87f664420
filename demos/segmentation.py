"""One segmentation run over a window of a video, shared by the agent tool and the web app."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from motionbits import MotionBitsConfig, MotionBitsSegmenter, iter_frames
from motionbits.frames import whole_number
from motionbits.segmenter import MIN_WORK_SIDE, min_short_side, work_size
from motionbits.video import IMAGE_SUFFIXES
from somprompt import MarkRegistry

__all__ = ["MAX_NODES", "MAX_VIDEO_SIDE", "MAX_WINDOW_FRAMES", "MAX_WINDOW_PIXELS", "Segmentation",
           "check_frame_shape", "check_segmentation", "check_window", "max_frames_for", "segment_window"]

#: Most frames one call processes (frames and label maps are kept in memory and returned) ...
MAX_WINDOW_FRAMES = 300
#: ... and most pixels over all of them: 300 frames of 480x640, 44 of 1920x1080 (about
#: 7 bytes a pixel are kept: RGB and an int32 label).
MAX_WINDOW_PIXELS = 300 * 480 * 640
#: Most graph nodes one call may ask for (a 200 x 200 grid, four times the default): time and
#: memory grow fast beyond (100,000 nodes: over 2 minutes and 2 GB for 3 frames of a 16x16
#: clip; 1,000,000: out of memory).
MAX_NODES = 40_000
#: Longest frame side accepted, px (the web app's limit too). The segmenter works at 640 px
#: whatever the input, but the frames are decoded, kept and returned at full size with a
#: label map each: a 3840x2160 video took 974 MB for 11 frames, a 7680x4320 one 1.2 GB for 2.
MAX_VIDEO_SIDE = 1920


def max_frames_for(height: int, width: int) -> int:
    """Most frames of ``height`` x ``width`` one window may hold (at least 2).

    Raises:
        TypeError / ValueError: a side that is not a whole number >= 1 (NaN gave 300).
    """
    for name, side in (("height", height), ("width", width)):
        if whole_number(name, side) < 1:
            raise ValueError(f"{name} must be >= 1 px, got {side!r}")
    height, width = int(height), int(width)
    return max(2, min(MAX_WINDOW_FRAMES, MAX_WINDOW_PIXELS // max(1, height * width)))

#: progress(done, total or None)
Progress = Callable[[int, "int | None"], None]


@dataclass
class Segmentation:
    """MotionBits of a window of a video.

    Attributes:
        video: the input path.
        frame_indices: index in the video of each processed frame.
        frames: processed frames, (H, W, 3) uint8 RGB.
        label_maps: one (H, W) int32 label map per processed frame (0 = background).
        moved: MotionBit id -> video frame indices in which it moved.
        twists: MotionBit id -> (omega rad/step, v_x, v_y px/step) at its latest motion.
        config: the segmenter's parameters.
        seconds: wall time of the segmentation.
    """

    video: str
    frame_indices: list[int]
    frames: list[np.ndarray]
    label_maps: list[np.ndarray]
    moved: dict[int, list[int]] = field(default_factory=dict)
    twists: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    config: MotionBitsConfig = field(default_factory=MotionBitsConfig)
    seconds: float = 0.0

    @cached_property
    def registry(self) -> MarkRegistry:
        """MotionBit id -> mark number (order of first appearance), as on the overlay
        (``somprompt.mark_video``) and in ``GroundedVQA``."""
        return MarkRegistry.from_label_maps(self.label_maps)

    @property
    def last_ids(self) -> list[int]:
        """Ids of the MotionBits in the last processed frame, ascending."""
        return [int(i) for i in np.unique(self.label_maps[-1]) if i > 0]


def check_segmentation(seg: object, name: str = "seg") -> "Segmentation":
    """``seg`` if it is a :class:`Segmentation` with at least one frame (else ``None.label_maps``
    failed deep inside); TypeError / ValueError naming ``name`` otherwise."""
    if not isinstance(seg, Segmentation):
        raise TypeError(f"{name} must be a Segmentation (from segment_window), got {type(seg).__name__}")
    if not seg.label_maps or not seg.frames:
        raise ValueError(f"{name} holds no segmented frame")
    return seg


def _int_arg(name: str, value: object, minimum: int, allow_none: bool = False) -> int | None:
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    return int(value)


def check_window(start: object = 0, frames: object = None, every: object = 1,
                 n_nodes: object = MotionBitsConfig.n_nodes) -> tuple[int, int | None, int, int]:
    """Validate the window arguments; returns them as ints (``frames`` may be None).

    Raises:
        ValueError: a non-integer or out-of-range value (one line naming it).
    """
    s = _int_arg("start", start, 0)
    f = _int_arg("frames", frames, 2, allow_none=True)
    e = _int_arg("every", every, 1)
    n = _int_arg("n_nodes", n_nodes, 16)
    if f is not None and f > MAX_WINDOW_FRAMES:
        raise ValueError(f"frames must be <= {MAX_WINDOW_FRAMES}, got {f}")
    if n > MAX_NODES:
        raise ValueError(f"n_nodes must be <= {MAX_NODES}, got {n}")
    return s, f, e, n


def check_frame_shape(height: int, width: int, config: MotionBitsConfig) -> None:
    """Refuse frames too large to hold or too thin for the segmenter, saying what size
    the video must have.

    The segmenter's own error (``crop it or raise max_side``) speaks to library users;
    here the user can only change the video, so the message gives its smallest size.

    Raises:
        ValueError: the longer side is over ``MAX_VIDEO_SIDE``, or the shorter one is
            below ``min_short_side`` for the longer one.
    """
    if max(height, width) > MAX_VIDEO_SIDE:
        raise ValueError(f"the video's frames are {width}x{height}, over the limit of {MAX_VIDEO_SIDE} px "
                         f"on the longer side (the segmenter works at {config.max_side} px anyway); "
                         f"downscale it first, e.g. ffmpeg -i IN -vf scale={MAX_VIDEO_SIDE}:-2 OUT "
                         f"(for a portrait video scale=-2:{MAX_VIDEO_SIDE})")
    if min(work_size(height, width, config.max_side)) >= MIN_WORK_SIDE:
        return
    long_side = max(height, width)
    need = min_short_side(long_side, config.max_side)
    raise ValueError(f"the video's frames are {width}x{height}, too thin to segment: with a longer "
                     f"side of {long_side} px the shorter side must be at least {need} px; "
                     "crop the video to a less elongated region")


def _check_video(video: object) -> Path:
    if not isinstance(video, (str, os.PathLike)) or not str(video).strip():
        raise ValueError(f"video must be the path of a video file or image folder, got {video!r}")
    path = Path(os.path.expanduser(os.fspath(video)))
    if not path.exists():
        raise FileNotFoundError(f"video not found: {path}")
    return path


def _declared_size(path: Path) -> tuple[int, int] | None:
    """(H, W) of a video file's frames as its header declares them, read without decoding
    a frame (a 7680x4320 frame alone takes hundreds of MB to decode); None for an image
    or a folder, or when unknown: the first decoded frame is checked then."""
    if path.is_dir() or path.suffix.lower() in IMAGE_SUFFIXES:
        return None
    cap = cv2.VideoCapture(str(path))
    try:
        h, w = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)), int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
    finally:
        cap.release()
    return (h, w) if h > 0 and w > 0 else None


def segment_window(video: "str | os.PathLike", *, start: int = 0, frames: int | None = None,
                   every: int = 1, n_nodes: int = MotionBitsConfig.n_nodes,
                   config: MotionBitsConfig | None = None,
                   progress: Progress | None = None) -> Segmentation:
    """Segment frames ``start, start + every, ...`` (at most ``frames`` of them) of a video.

    Args:
        video: a video file or a folder of images.
        start: index of the first frame used.
        frames: how many frames to use (>= 2; None: to the end). At most
            ``max_frames_for(H, W)`` frames (``MAX_WINDOW_FRAMES``, fewer for large frames).
        every: use every ``every``-th frame.
        n_nodes: graph nodes of the segmenter (``MotionBitsConfig.n_nodes``), at most
            ``MAX_NODES``.
        config: other segmenter parameters (``n_nodes`` overrides its field).
        progress: called as ``progress(done, total)`` after each frame (``total`` is None
            when ``frames`` is None).

    Raises:
        FileNotFoundError: no such file or folder.
        ValueError: a bad argument, an unreadable video, frames over ``MAX_VIDEO_SIDE``
            or too thin to segment (:func:`check_frame_shape`), fewer than two frames in
            the window, or more than ``max_frames_for(H, W)``.
    """
    start, frames, every, n_nodes = check_window(start, frames, every, n_nodes)
    if config is not None and not isinstance(config, MotionBitsConfig):  # else "'dict' ... no attribute 'with_'"
        raise TypeError(f"config must be a MotionBitsConfig or None, got {type(config).__name__}")
    if progress is not None and not callable(progress):  # else "not callable" after the first frame
        raise TypeError(f"progress must be callable as progress(done, total) or None, got {type(progress).__name__}")
    path = _check_video(video)
    cfg = (config or MotionBitsConfig()).with_(n_nodes=n_nodes)
    declared = _declared_size(path)
    if declared is not None:
        check_frame_shape(*declared, cfg)
    seg = MotionBitsSegmenter(cfg)
    out = Segmentation(str(path), [], [], [], config=cfg)
    t0 = time.perf_counter()
    cap = MAX_WINDOW_FRAMES
    window: list[tuple[int, np.ndarray]] = []  # read the whole window first: no segmenting in vain
    for i, frame in enumerate(iter_frames(path)):
        if i == 0:  # images (and a header that was wrong): refused at one frame's cost
            check_frame_shape(*frame.shape[:2], cfg)
        if i < start or (i - start) % every:
            continue
        if not window:
            cap = max_frames_for(*frame.shape[:2])
            if frames is not None and frames > cap:
                raise ValueError(f"frames={frames} is too many at {frame.shape[1]}x{frame.shape[0]}: "
                                 f"at most {cap} frames of this size per call")
        if len(window) == (frames or cap):
            if frames is None:
                raise ValueError(f"the window holds more than {cap} frames of {frame.shape[1]}x"
                                 f"{frame.shape[0]} (the most per call); choose fewer with frames= "
                                 "or a larger every=")
            break
        if window and frame.shape != window[0][1].shape:
            first, shape = window[0][0], window[0][1].shape
            raise ValueError(f"frame {i} is {frame.shape[1]}x{frame.shape[0]} but frame {first} is "
                             f"{shape[1]}x{shape[0]}: all frames of a video or image folder must have "
                             "the same size")
        window.append((i, frame))
    if len(window) < 2:
        where = f"from frame {start} with every={every}" if start or every > 1 else "in the video"
        raise ValueError(f"need at least 2 frames to see motion, found {len(window)} {where}")
    for i, frame in window:
        result = seg.update(frame)
        out.frame_indices.append(i)
        out.frames.append(frame)
        out.label_maps.append(result.labels)
        for mb in result.motionbits:
            if mb.moving:
                out.moved.setdefault(mb.id, []).append(i)
                out.twists[mb.id] = mb.twist
        if progress is not None:
            progress(len(out.frames), frames)
    out.seconds = time.perf_counter() - t0
    return out
