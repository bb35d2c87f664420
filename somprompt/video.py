"""Marks on videos: stable numbers and colours across frames, and the outputs
(frames, mp4, GIF, frames sized for a VLM)."""

from __future__ import annotations

import numbers
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np
from PIL import Image

from motionbits.frames import sample_frame_indices, whole_number

from .anchors import LabelPlacement
from .inputs import ImageLike, as_rgb_array, check_label_map, like_input
from .metadata import MarkInfo, describe_marks, marks_to_json
from .registry import MarkRegistry, MarkStyle, check_registry, whole_ids
from .render import SetOfMarkRenderer

__all__ = [
    "sample_frame_indices",
    "resize_max_side",
    "frames_for_vlm",
    "sample_for_vlm",
    "MarkedVideo",
    "mark_video",
    "write_mp4",
    "write_gif",
]


def _target_size(h: int, w: int, max_side: int | None) -> tuple[int, int]:
    if max_side is not None:
        max_side = whole_number("max_side", max_side)
    if max_side is None or max(h, w) <= max_side:
        return w, h
    if max_side < 1:
        raise ValueError(f"max_side must be >= 1, got {max_side}")
    s = max_side / max(h, w)
    return max(1, round(w * s)), max(1, round(h * s))


def resize_max_side(image: ImageLike, max_side: int | None) -> ImageLike:
    """Shrink an image so its longer side is at most ``max_side`` (never enlarges).

    Args:
        image: (H, W, 3) uint8 RGB array or PIL image (same type returned), or an
            (H, W) integer label map (resized with nearest neighbour, dtype kept).
        max_side: pixels, or None to keep the size.
    """
    if isinstance(image, np.ndarray) and image.ndim == 2:
        lm = check_label_map(image, name="label map")
        w, h = _target_size(*lm.shape, max_side)
        if (h, w) == lm.shape:
            return image
        # nearest neighbour by index (any integer dtype; cv2 cannot resize int64)
        ys = np.minimum(((np.arange(h) + 0.5) * lm.shape[0] / h).astype(int), lm.shape[0] - 1)
        xs = np.minimum(((np.arange(w) + 0.5) * lm.shape[1] / w).astype(int), lm.shape[1] - 1)
        return image[ys[:, None], xs[None, :]]
    img = as_rgb_array(image, name="frame")
    w, h = _target_size(*img.shape[:2], max_side)
    if (h, w) != img.shape[:2]:
        img = cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)
    return like_input(img, image)


def frames_for_vlm(
    frames: Sequence[ImageLike], max_side: int | None = 768, num_frames: int | None = 8
) -> list[ImageLike]:
    """Sample ``num_frames`` frames uniformly and shrink them to ``max_side``.

    Use it on frames already marked; to keep the numbers legible at the VLM's size,
    prefer :func:`sample_for_vlm` before rendering (what :class:`GroundedVQA` does).
    """
    frames = _as_list(frames, "frames", "frames")
    return [resize_max_side(frames[i], max_side) for i in sample_frame_indices(len(frames), num_frames)]


def sample_for_vlm(
    frames: Sequence[ImageLike],
    label_maps: Sequence[np.ndarray],
    max_side: int | None = 768,
    num_frames: int | None = 8,
) -> tuple[list[np.ndarray], list[np.ndarray], list[int]]:
    """Sample frames and their label maps uniformly and shrink both to ``max_side``
    (frames with area interpolation, label maps with nearest neighbour), so marks can
    be drawn at the size the VLM will see.

    Returns:
        ``(frames, label_maps, indices)``: (h, w, 3) uint8 arrays, (h, w) label maps,
        and the indices of the chosen frames in the input.
    """
    frames, label_maps = _as_list(frames, "frames", "frames"), _as_list(label_maps, "label_maps", "(H, W) label maps")
    _check_lengths(frames, label_maps)
    idx = sample_frame_indices(len(frames), num_frames)
    out_f, out_l = [], []
    for i in idx:
        f = as_rgb_array(frames[i], name=f"frame {i}")
        lm = check_label_map(label_maps[i], f.shape[:2], name=f"label map {i}")
        out_f.append(resize_max_side(f, max_side))
        out_l.append(resize_max_side(lm, max_side))
    return out_f, out_l, idx


def _as_list(values: object, name: str, what: str) -> list:
    """``values`` as a list; TypeError naming ``name`` for None, a str or a single array
    (else "'NoneType' object is not iterable")."""
    if values is None or isinstance(values, (str, bytes, Image.Image)) or not hasattr(values, "__iter__"):
        raise TypeError(f"{name} must be a list of {what}, got {type(values).__name__}")
    return list(values)


def _check_lengths(frames: Sequence, label_maps: Sequence) -> None:
    if len(frames) == 0:
        raise ValueError("no frames given")
    if len(frames) != len(label_maps):
        raise ValueError(
            f"got {len(frames)} frames but {len(label_maps)} label maps; pass one (H, W) "
            "label map per frame"
        )


def _check_frame_indices(indices: Sequence[int], n: int) -> list[int]:
    """``indices`` as ints >= 0, one per frame ([0, 0.5] was kept as given in
    ``MarkedVideo.frame_indices`` but recorded as frame 0 by the registry)."""
    out = whole_ids(indices, "frame_indices", "frame numbers")
    if any(i < 0 for i in out):
        raise ValueError(f"frame_indices must be >= 0, got {min(out)}")
    if len(out) != n:
        raise ValueError(f"got {len(out)} frame indices for {n} frames")
    return out


@dataclass
class MarkedVideo:
    """Frames with marks, and what the marks mean.

    Attributes:
        frames: marked frames, same type as the input frames.
        registry: id -> mark number (stable over the video).
        marks: id -> :class:`MarkInfo` (geometry from the last frame each id was in).
        placements: per frame, id -> label placement.
        frame_indices: index of each frame in the original video.
    """

    frames: list[ImageLike]
    registry: MarkRegistry
    marks: dict[int, MarkInfo]
    placements: list[dict[int, LabelPlacement]] = field(default_factory=list)
    frame_indices: list[int] = field(default_factory=list)

    def to_json(self, **kwargs) -> str:
        """Mark metadata as JSON (see :func:`somprompt.marks_to_json`)."""
        first = as_rgb_array(self.frames[0]) if self.frames else None
        size = None if first is None else (first.shape[1], first.shape[0])
        return marks_to_json(self.marks, style=self.registry.style, image_size=size, **kwargs)

    def to_mp4(self, path: "str | os.PathLike", fps: float = 10.0) -> Path:
        return write_mp4(self.frames, path, fps)

    def to_gif(self, path: "str | os.PathLike", fps: float = 10.0) -> Path:
        return write_gif(self.frames, path, fps)

    def for_vlm(self, max_side: int | None = 768, num_frames: int | None = 8) -> list[ImageLike]:
        return frames_for_vlm(self.frames, max_side, num_frames)


def mark_video(
    frames: Sequence[ImageLike],
    label_maps: Sequence[np.ndarray],
    renderer: SetOfMarkRenderer | None = None,
    registry: MarkRegistry | None = None,
    style: MarkStyle = "number",
    frame_indices: Sequence[int] | None = None,
) -> MarkedVideo:
    """Draw marks on every frame of a video so that each object id keeps its number and
    colour throughout, and each label follows its mask (staying put while its point is
    still well inside the mask, to avoid jitter).

    Args:
        frames: T frames, (H, W, 3) uint8 RGB arrays or PIL images.
        label_maps: T (H, W) integer label maps, one per frame, same sizes.
        renderer: how to draw (default ``SetOfMarkRenderer()``).
        registry: reuse one to keep numbers from an earlier call (e.g. one filled from
            the full-length video before sampling); ``None`` creates one.
        style: ``"number"`` or ``"letter"`` for a new registry.
        frame_indices: each frame's index in the original video (default 0..T-1), as
            recorded in ``frames_seen``.

    Returns:
        :class:`MarkedVideo`.
    """
    frames, label_maps = _as_list(frames, "frames", "frames"), _as_list(label_maps, "label_maps", "(H, W) label maps")
    _check_lengths(frames, label_maps)
    if frame_indices is None:
        frame_indices = list(range(len(frames)))
    else:
        frame_indices = _check_frame_indices(frame_indices, len(frames))
    if renderer is not None and not isinstance(renderer, SetOfMarkRenderer):  # else "no attribute 'render'"
        raise TypeError(f"renderer must be a somprompt.SetOfMarkRenderer or None, got {type(renderer).__name__}")
    if registry is not None:
        check_registry(registry)  # else "'int' object has no attribute 'update'"
    renderer = renderer if renderer is not None else SetOfMarkRenderer()
    registry = registry if registry is not None else MarkRegistry(style)
    checked = []
    for t, (f, lm) in enumerate(zip(frames, label_maps)):
        img = as_rgb_array(f, name=f"frame {t}")
        lm = check_label_map(lm, img.shape[:2], name=f"label map {t}")
        registry.update(lm, frame_index=frame_indices[t])  # numbers in order of first appearance
        checked.append(lm)
    out_frames, all_placements = [], []
    marks: dict[int, MarkInfo] = {}
    prefer: dict[int, tuple[int, int]] = {}
    for t, (f, lm) in enumerate(zip(frames, checked)):
        rendered = renderer.render(f, lm, registry, prefer=prefer)
        out_frames.append(rendered.image)
        all_placements.append(rendered.placements)
        prefer.update({i: p.point for i, p in rendered.placements.items() if not p.leader})
        marks.update(describe_marks(rendered.regions, registry, rendered.placements,
                                    renderer.palette, frame_indices[t]))
    marks = dict(sorted(marks.items(), key=lambda kv: kv[1].number))
    return MarkedVideo(out_frames, registry, marks, all_placements, list(frame_indices))


def _as_arrays(frames: Sequence[ImageLike]) -> list[np.ndarray]:
    arrs = [as_rgb_array(f, name=f"frame {i}") for i, f in enumerate(frames)]
    if not arrs:
        raise ValueError("no frames to write")
    shape = arrs[0].shape
    for i, a in enumerate(arrs):
        if a.shape != shape:
            raise ValueError(f"frame {i} has shape {a.shape}, frame 0 has {shape}; all must match")
    return arrs


def write_mp4(frames: Sequence[ImageLike], path: "str | os.PathLike", fps: float = 10.0) -> Path:
    """Write RGB frames to an H.264 mp4 that browsers play (see :func:`motionbits.video_writer.write_h264`).

    Raises:
        ValueError: no frames, frames of different sizes, ``fps`` <= 0, or ``path`` without
            an mp4 suffix.
        IsADirectoryError: ``path`` is a folder.
    """
    from motionbits.video_writer import write_h264

    return write_h264(_as_arrays(frames), path, fps)


def write_gif(frames: Sequence[ImageLike], path: "str | os.PathLike", fps: float = 10.0) -> Path:
    """Write RGB frames to a looping GIF (Pillow).

    Raises:
        ValueError: no frames, frames of different sizes, ``fps`` not a number in
            [100 / 65535, 100] (a GIF frame lasts 1/100 s to 655.35 s), or ``path`` does not
            end in ``.gif``.
        IsADirectoryError: ``path`` is a folder.
    """
    arrs = _as_arrays(frames)
    # a GIF's frame delay is 1 to 65535 centiseconds (was: OverflowError from Pillow below,
    # 0 ms delays above, which viewers play at their own speed)
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not 100 / 65535 <= fps <= 100:
        raise ValueError(f"fps must be a number >= {100 / 65535:.5f} and <= 100 (a GIF frame lasts 1/100 s "
                         f"to 655.35 s), got {fps!r}")
    path = Path(path)
    if path.is_dir():  # else PIL's "unknown file extension: "
        raise IsADirectoryError(f"{path} is a folder; pass the GIF file to write, e.g. {path / 'marks.gif'}")
    if path.suffix.lower() != ".gif":
        raise ValueError(f"{path}: a GIF must end in .gif, got {path.suffix or 'no suffix'!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    images = [Image.fromarray(a) for a in arrs]
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(round(1000 / fps)),
                   loop=0, optimize=False)
    return path
