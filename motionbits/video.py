"""Reading frames from videos, image folders and arrays, with clear errors on bad input."""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path
from typing import Iterable, Iterator, Union

import cv2
import numpy as np
from PIL import Image

from motionbits.frames import as_rgb_array

__all__ = ["FrameSource", "as_rgb_frame", "iter_frames", "count_frames", "read_image",
           "is_frame_file", "is_video_file", "frame_order", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
#: Files read with PIL, page by page, when given as the input (not as frames of a folder);
#: OpenCV decodes only the first frame of an animated GIF.
MULTI_FRAME_IMAGE_SUFFIXES = (".gif",)

FrameSource = Union[str, os.PathLike, np.ndarray, Iterable[np.ndarray]]


def as_rgb_frame(frame: np.ndarray, *, name: str = "frame") -> np.ndarray:
    """Validate one frame and return it as a contiguous (H, W, 3) uint8 RGB array.

    Accepted as everywhere in the toolkit (:func:`motionbits.frames.as_rgb_array`):
    (H, W, 3) uint8 RGB, (H, W) or (H, W, 1) uint8 greyscale, (H, W, 4) uint8 RGBA, PIL
    images; the segmenter also needs at least 8x8 pixels. Anything else raises
    ``ValueError`` / ``TypeError`` saying what was wrong.
    """
    frame = as_rgb_array(frame, name=name)
    if frame.shape[0] < 8 or frame.shape[1] < 8:
        raise ValueError(f"{name} is too small to segment: {frame.shape[1]}x{frame.shape[0]} pixels")
    return frame


def _iter_video_file(path: Path) -> Iterator[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise ValueError(f"could not open {path} as a video (unsupported codec or corrupt file)")
    try:
        n = 0
        while True:
            ok, bgr = cap.read()
            if not ok:
                break
            n += 1
            yield cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
        if n == 0:
            raise ValueError(f"{path} contains no decodable frames (empty or corrupt video)")
    finally:
        cap.release()


def is_frame_file(path: Path) -> bool:
    """Whether an entry of a folder of frames is read as a frame: a regular file with an
    image suffix whose name does not start with '.' (hidden files such as the
    ``._00001.png`` AppleDouble files macOS leaves on shared drives are not images)."""
    return (path.suffix.lower() in IMAGE_SUFFIXES and not path.name.startswith(".")
            and path.is_file())


def is_video_file(path: "str | os.PathLike | None") -> bool:
    """Whether ``path`` is a file read by the video decoder (not an image file); its frame
    count is its header's, a guess."""
    return (path is not None and Path(path).is_file()
            and Path(path).suffix.lower() not in IMAGE_SUFFIXES + MULTI_FRAME_IMAGE_SUFFIXES)


def frame_order(path: Path) -> tuple:
    """Sort key of frame files: by name, numbers by value, so ``2.png`` comes before
    ``10.png`` (FFmpeg's ``%d.png``); zero-padded names keep their order."""
    parts = re.split(r"(\d+)", path.name)
    return tuple((0, int(t), t) if t.isdecimal() else (1, t) for t in parts if t)  # not "²"


def check_no_broken_links(folder: Path) -> None:
    """Raise ValueError if ``folder`` holds a link named like a frame whose target is
    missing: skipping it would shift every later frame's index silently."""
    broken = sorted((p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES
                     and not p.name.startswith(".") and p.is_symlink() and not p.exists()),
                    key=frame_order)
    if broken:
        raise ValueError(f"frame {broken[0].name} in {folder} is a broken link (to "
                         f"{os.readlink(broken[0])}); restore or remove it")


def _image_files(folder: Path) -> list[Path]:
    check_no_broken_links(folder)
    files = sorted((p for p in folder.iterdir() if is_frame_file(p)), key=frame_order)
    if not files:
        raise ValueError(f"folder {folder} contains no images ({', '.join(IMAGE_SUFFIXES)})")
    return files


def _to_uint8(arr: np.ndarray, name: str) -> np.ndarray:
    """An image array of a file as uint8: 16-bit (and 16-bit values held in int32) are
    scaled by 255 / 65535, floats in [0, 1] by 255; NaN or values out of range raise."""
    if arr.dtype == np.uint8:
        return arr
    if arr.dtype == bool:
        return arr.astype(np.uint8) * 255
    if np.issubdtype(arr.dtype, np.floating):
        if not np.isfinite(arr).all():
            raise ValueError(f"{name} holds NaN or infinite values")
        if arr.size and (arr.min() < 0 or arr.max() > 1):
            raise ValueError(f"{name} is a float image with values outside [0, 1] "
                             f"({arr.min():g}..{arr.max():g})")
        return np.round(arr * 255).astype(np.uint8)
    if np.issubdtype(arr.dtype, np.integer) and (arr.size == 0 or (arr.min() >= 0 and arr.max() <= 65535)):
        return ((arr.astype(np.uint32) * 255 + 32767) // 65535).astype(np.uint8)
    raise ValueError(f"{name} has unsupported pixel type {arr.dtype} (values "
                     f"{arr.min()}..{arr.max()}); use 8- or 16-bit images")


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read an image file as (H, W, 3) uint8 RGB.

    8-bit images of any mode are converted to RGB; 16-bit images (PNG, TIFF) are scaled to
    8 bits (not clipped), float images in [0, 1] likewise; alpha is dropped.

    Raises:
        ValueError: the file is not a readable image, holds NaN, or an unsupported pixel type.
    """
    path = Path(path)
    try:
        with Image.open(path) as im:
            return _pil_to_rgb(im, f"image {path}")
    except ValueError:
        raise
    except Exception as exc:  # PIL raises several types for corrupt files
        raise ValueError(f"could not read image {path}: {exc}") from exc


def _pil_to_rgb(im: Image.Image, name: str) -> np.ndarray:
    """The current page of an open PIL image as (H, W, 3) uint8 RGB (see read_image)."""
    if im.mode in ("1", "L", "P", "RGB", "RGBA", "LA", "PA", "CMYK", "YCbCr", "LAB", "HSV"):
        return np.asarray(im.convert("RGB"))
    arr = _to_uint8(np.asarray(im), name)  # "I;16*", "I", "F": one channel of more than 8 bits
    return np.repeat(arr[..., None], 3, axis=2) if arr.ndim == 2 else arr[..., :3]


def _image_pages(path: Path) -> int:
    """How many frames an image file holds (a multi-page TIFF, an animated GIF / WebP /
    PNG: more than one); 1 when it cannot be told."""
    try:
        with warnings.catch_warnings(), Image.open(path) as im:
            warnings.simplefilter("ignore", UserWarning)  # PIL's "Corrupt EXIF data" of a cut TIFF
            return max(1, int(getattr(im, "n_frames", 1)))
    except Exception:  # unreadable: read_image says why
        return 1


def _iter_image_pages(path: Path) -> Iterator[np.ndarray]:
    """Every page of a multi-page image file as (H, W, 3) uint8 RGB, in order."""
    try:
        im = Image.open(path)
    except Exception as exc:
        raise ValueError(f"could not read image {path}: {exc}") from exc
    with im:
        for k in range(_image_pages(path)):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # the error below says it all
                    im.seek(k)
                page = _pil_to_rgb(im, f"frame {k} of image {path}")
            except ValueError:
                raise
            except Exception as exc:  # a truncated page
                raise ValueError(f"could not read frame {k} of image {path}: {exc}") from exc
            yield page


def iter_frames(source: FrameSource) -> Iterator[np.ndarray]:
    """Yield (H, W, 3) uint8 RGB frames from a video file, an image folder or arrays.

    Args:
        source: path to a video file (anything OpenCV/FFmpeg decodes), to an image file
            (a multi-page TIFF or an animated GIF / WebP / PNG gives one frame per page)
            or to a folder of images (sorted by name, numbers by value: ``2.png`` before
            ``10.png``; hidden files, named ``.*``, are skipped); a (T, H, W, 3) / (T, H, W) uint8 array; or an iterable
            of (H, W, 3) frames.

    Raises:
        FileNotFoundError: the path does not exist.
        ValueError: the path is empty, the video or folder holds no readable frame, or a
            frame is malformed.
        TypeError: the source or a frame has the wrong type.
    """
    if isinstance(source, (bytes, bytearray)):  # else read as an iterable of ints
        raise TypeError(f"a path must be a str or pathlib.Path, got {type(source).__name__} "
                        f"{bytes(source)[:80]!r}; decode it with os.fsdecode(path)")
    if isinstance(source, (str, os.PathLike)):
        if not os.fspath(source).strip():  # Path("") is ".": the current folder
            raise ValueError(f"the input path is empty ({os.fspath(source)!r}); pass a video "
                             "file or a folder of images")
        path = Path(source)
        if not path.exists():
            raise FileNotFoundError(f"input not found: {path}")
        if path.is_dir():
            for i, f in enumerate(_image_files(path)):
                yield as_rgb_frame(read_image(f), name=f"frame {i} ({f.name})")
            return
        if path.suffix.lower() in IMAGE_SUFFIXES + MULTI_FRAME_IMAGE_SUFFIXES:
            if _image_pages(path) == 1:
                yield as_rgb_frame(read_image(path), name=str(path))
                return
            # a multi-page TIFF, an animated GIF / WebP / PNG: every page is a frame
            for i, frame in enumerate(_iter_image_pages(path)):
                yield as_rgb_frame(frame, name=f"frame {i} of {path.name}")
            return
        for i, frame in enumerate(_iter_video_file(path)):
            yield as_rgb_frame(frame, name=f"frame {i} of {path.name}")
        return
    if isinstance(source, np.ndarray):
        if source.ndim not in (3, 4):
            raise ValueError(
                f"an array of frames must have shape (T, H, W, 3) or (T, H, W); got {source.shape}"
            )
        if source.shape[0] == 0:
            raise ValueError("the array of frames is empty (T = 0)")
        if source.ndim == 3 and source.shape[2] in (3, 4) and min(source.shape[:2]) >= 8:
            # read as T greyscale frames 3 or 4 px wide (was: "frame 0 is too small ...")
            raise ValueError(
                f"an array of frames of shape {source.shape} reads as {source.shape[0]} "
                f"greyscale frames {source.shape[2]} px wide; if it is one RGB frame, pass "
                "[frame] or frame[None]")
        for i in range(source.shape[0]):
            yield as_rgb_frame(source[i], name=f"frame {i}")
        return
    if isinstance(source, Iterable):
        n = 0
        for i, frame in enumerate(source):
            n += 1
            yield as_rgb_frame(frame, name=f"frame {i}")
        if n == 0:
            raise ValueError("the frame iterable is empty")
        return
    raise TypeError(
        f"unsupported frame source of type {type(source).__name__}: pass a path, an array or "
        "an iterable of frames"
    )


def count_frames(source: FrameSource) -> int | None:
    """Number of frames in ``source`` if known cheaply, else ``None`` (for progress bars)."""
    if isinstance(source, np.ndarray):
        return int(source.shape[0]) if source.ndim in (3, 4) else None
    if isinstance(source, (list, tuple)):
        return len(source)
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if path.is_dir():
            return sum(1 for p in path.iterdir() if is_frame_file(p))
        if is_video_file(path):
            cap = cv2.VideoCapture(str(path))
            n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else 0
            cap.release()
            return n if n > 0 else None  # some readers answer -1 or INT64_MIN: unknown
        if path.is_file():  # an image file: its pages
            return _image_pages(path)
    return None
