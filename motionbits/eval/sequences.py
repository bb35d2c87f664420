"""Cut a DAVIS-style annotated sequence into MoRiBo-format scenes (short windows).

A DAVIS-style sequence is a folder with ``frames/`` holding the frames and ``gt/`` holding
one mask per frame with the same file stem, or a sequence folder of the DAVIS release
(``<root>/JPEGImages/480p/<seq>``, masks in ``<root>/Annotations/480p/<seq>``). Masks are
8-bit or palette PNGs where 0 is background and every other value one object (DAVIS 2016:
255 = the object; DAVIS 2017: palette indices 1..K). Each window of ``length`` frames
becomes a scene whose ``gt.png`` is the window's last mask, the objects relabelled 1..K in
increasing order of their value (``meta.json`` keeps the mapping).
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import cv2
import numpy as np

from motionbits.eval.labelmaps import read_label_map, write_label_map
from motionbits.video import frame_order, is_frame_file

__all__ = ["scenes_from_sequence"]


def _folders(src: Path) -> tuple[Path, Path]:
    """(frame folder, mask folder) of a sequence (module docstring)."""
    if (src / "frames").is_dir() and (src / "gt").is_dir():
        return src / "frames", src / "gt"
    parts = src.resolve().parts
    if "JPEGImages" in parts:
        i = len(parts) - 1 - parts[::-1].index("JPEGImages")
        masks = Path(*parts[:i], "Annotations", *parts[i + 1 :])
        if masks.is_dir():
            return src, masks
    raise FileNotFoundError(f"{src} is no sequence: it needs frames/ and gt/ folders (or is a "
                            "DAVIS JPEGImages/<res>/<seq> folder with matching Annotations/)")


def _check_sizes(files: list[Path]) -> None:
    """ValueError unless the frame files share one size (read from their headers)."""
    from PIL import Image

    size = None
    for f in dict.fromkeys(files):
        try:
            with Image.open(f) as img:
                wh = img.size
        except OSError as exc:
            raise ValueError(f"could not read frame {f}: {exc}") from exc
        if size is None:
            first, size = f, wh
        elif wh != size:
            raise ValueError(f"frame {f} is {wh[0]}x{wh[1]} but {first.name} is {size[0]}x{size[1]}; "
                             "the frames of a scene share one size")


def scenes_from_sequence(
    src: str | os.PathLike,
    out: str | os.PathLike,
    *,
    length: int = 16,
    stride: int = 8,
    max_side: int = 640,
    name: str | None = None,
) -> list[Path]:
    """Write the windows ``[s, s + length)``, s = 0, stride, ... of a sequence as scenes.

    Args:
        src: sequence folder with ``frames/`` and ``gt/``, or a DAVIS
            ``JPEGImages/<res>/<seq>`` folder; the last frame of every window needs a mask
            with its stem.
        out: output folder (a MoRiBo track); scenes go to ``out/<name>_<first frame>``.
        length: frames per scene (>= 2); only full windows are written.
        stride: step between window starts (>= 1).
        max_side: frames and masks larger than this on their longest side are resized
            (frames with area interpolation, masks nearest-neighbour); 0 keeps the size.
        name: scene name prefix, default the folder name of ``src``.

    Returns:
        The scene folders written, in order.

    Raises:
        FileNotFoundError: a folder or a mask is missing.
        ValueError: bad ``length``/``stride``/``max_side``, the sequence is shorter than
            ``length``, the frames differ in size, a mask's size differs from its frame's, or a
            scene folder already holds frames.
    """
    if length < 2 or stride < 1 or max_side < 0:
        raise ValueError(f"need length >= 2, stride >= 1, max_side >= 0; got {length}, "
                         f"{stride}, {max_side}")
    src, out = Path(src), Path(out)
    if not src.is_dir():
        raise FileNotFoundError(f"sequence folder not found: {src}")
    frame_dir, gt_dir = _folders(src)
    frames = sorted((p for p in frame_dir.iterdir() if is_frame_file(p)), key=frame_order)
    if len(frames) < length:
        raise ValueError(f"{frame_dir} holds {len(frames)} frames, fewer than --length {length}")
    name = name or src.resolve().name
    starts = range(0, len(frames) - length + 1, stride)
    _check_sizes([f for s in starts for f in frames[s : s + length]])  # before writing any scene
    scenes = []
    for start in starts:
        window = frames[start : start + length]
        scene = out / f"{name}_{start:05d}"
        if (scene / "frames").is_dir() and any((scene / "frames").iterdir()):
            raise ValueError(f"{scene}/frames already holds files; choose an empty --out")
        mask_file = gt_dir / f"{window[-1].stem}.png"
        mask = read_label_map(mask_file)
        (scene / "frames").mkdir(parents=True, exist_ok=True)
        ids = np.unique(mask)
        ids = ids[ids > 0]
        gt = np.searchsorted(ids, mask) + 1
        gt[mask == 0] = 0
        first = cv2.imread(str(window[0]), cv2.IMREAD_COLOR)
        if first is None:
            raise ValueError(f"could not read frame {window[0]}")
        h, w = first.shape[:2]
        if mask.shape != (h, w):
            raise ValueError(f"{mask_file} is {mask.shape[1]}x{mask.shape[0]}, its frame {w}x{h}")
        scale = max_side / max(h, w) if max_side and max(h, w) > max_side else 1.0
        size = (round(w * scale), round(h * scale))
        for i, f in enumerate(window):
            dst = scene / "frames" / f"{i:05d}{f.suffix.lower()}"
            if scale == 1.0:
                shutil.copyfile(f, dst)
                continue
            img = cv2.imread(str(f), cv2.IMREAD_COLOR)
            if img is None:
                raise ValueError(f"could not read frame {f}")
            cv2.imwrite(str(dst.with_suffix(".jpg")), cv2.resize(img, size, interpolation=cv2.INTER_AREA),
                        [cv2.IMWRITE_JPEG_QUALITY, 95])
        if scale != 1.0:
            gt = cv2.resize(gt.astype(np.uint16), size, interpolation=cv2.INTER_NEAREST)
        write_label_map(scene / "gt.png", gt)
        meta = {
            "source": str(src), "first_frame": start, "frames": [f.name for f in window],
            "gt_from": mask_file.name, "scale": scale, "size_hw": [size[1], size[0]],
            "labels": {str(k): int(v) for k, v in enumerate(ids, 1)},
        }
        (scene / "meta.json").write_text(json.dumps(meta, indent=1))
        scenes.append(scene)
    return scenes
