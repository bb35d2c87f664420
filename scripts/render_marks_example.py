#!/usr/bin/env python3
"""Render Set-of-Mark marks on the last frame of a video, from saved label maps.

Usage:
    python scripts/render_marks_example.py VIDEO LABEL_DIR OUT.png [--mode mask+contour+number]
        [--style number|letter] [--max-side 960] [--gif OUT.gif]

VIDEO is any file OpenCV reads (or a folder of images); LABEL_DIR holds one 16-bit PNG
label map per frame, named NNNNN.png by frame index, as `motionbits segment` writes to
DIR/labels/ (0 = background, k > 0 = object k). The last label map is drawn on the frame
with the same index; numbers and colours are assigned over all label maps, in order, so
they match a video rendered from the same folder. Also writes OUT.json (mark metadata)
and, with --gif, the whole marked video.

Example (once the segmenter has run):
    motionbits segment ../shared/data/real/02_cups.mp4 --out runs/cups --start 60 --every 4 --frames 16
    python scripts/render_marks_example.py ../shared/data/real/02_cups.mp4 runs/cups/labels \
        docs/img/somprompt_cups.png
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

import somprompt
from motionbits.video import iter_frames  # a script may use both packages; somprompt may not


def read_label_maps(folder: Path) -> dict[int, np.ndarray]:
    """Frame index -> (H, W) label map, from NNNNN.png files."""
    files = sorted(p for p in folder.glob("*.png") if p.stem.isdigit())
    if not files:
        sys.exit(f"error: no label maps named NNNNN.png in {folder}")
    maps = {}
    for p in files:
        lm = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
        if lm is None:
            sys.exit(f"error: could not read {p}")
        if lm.ndim != 2:
            sys.exit(f"error: {p} has {lm.shape[2]} channels; expected a single-channel (16-bit) label map")
        maps[int(p.stem)] = lm
    return maps


def read_frames(video: Path, wanted: set[int]) -> dict[int, np.ndarray]:
    """Frame index -> (H, W, 3) RGB frame, for the indices in ``wanted``."""
    out, last = {}, max(wanted)
    for i, frame in enumerate(iter_frames(video)):
        if i in wanted:
            out[i] = frame
        if i >= last:
            break
    return out


def fit(frame: np.ndarray, labels: np.ndarray, max_side: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Frame and label map at one size: the label map's aspect, longest side ``max_side``
    (label maps are often at the segmenter's working resolution), never beyond the frame's
    resolution. ``max_side=None``: the label map's size."""
    h, w = labels.shape
    s = min(max_side / max(h, w), frame.shape[0] / h) if max_side else 1.0
    size = (max(1, round(w * s)), max(1, round(h * s)))
    if size != (w, h):
        labels = cv2.resize(labels, size, interpolation=cv2.INTER_NEAREST)  # uint8/uint16 PNG data
    if frame.shape[:2] != labels.shape:
        frame = cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
    return frame, labels


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("video", type=Path)
    ap.add_argument("labels", type=Path, help="folder of NNNNN.png label maps")
    ap.add_argument("out", type=Path, help="output PNG")
    ap.add_argument("--mode", default="mask+contour+number")
    ap.add_argument("--style", default="number", choices=["number", "letter"])
    ap.add_argument("--max-side", type=int, default=960, help="longest side of the output (0: label-map size)")
    ap.add_argument("--gif", type=Path, default=None, help="also write the marked video as a GIF")
    args = ap.parse_args(argv)

    maps = read_label_maps(args.labels)
    registry = somprompt.MarkRegistry(args.style)
    for t in sorted(maps):
        registry.update(maps[t], frame_index=t)
    wanted = set(maps) if args.gif else {max(maps)}
    frames = read_frames(args.video, wanted)
    last = max(maps)
    if last not in frames:
        sys.exit(f"error: {args.video} has no frame {last} (the last label map is {last:05d}.png)")

    renderer = somprompt.SetOfMarkRenderer(mode=args.mode)
    frame, labels = fit(frames[last], maps[last], args.max_side or None)
    rendered = renderer.render(frame, labels, registry)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out), cv2.cvtColor(rendered.image, cv2.COLOR_RGB2BGR))
    marks = somprompt.describe_marks(rendered.regions, registry, rendered.placements, renderer.palette, last)
    json_path = somprompt.save_marks_json(args.out.with_suffix(".json"), marks, style=registry.style,
                                          image_size=(labels.shape[1], labels.shape[0]))
    print(f"wrote {args.out} ({len(marks)} marks on frame {last}) and {json_path}")

    if args.gif:
        idx = [t for t in sorted(maps) if t in frames]
        pairs = [fit(frames[t], maps[t], args.max_side or None) for t in idx]
        video = somprompt.mark_video([p[0] for p in pairs], [p[1] for p in pairs], renderer,
                                     registry=registry, frame_indices=idx)
        video.to_gif(args.gif)
        print(f"wrote {args.gif} ({len(idx)} frames)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
