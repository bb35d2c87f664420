"""``motionbits segment``: label maps, an overlay video and a summary for one video."""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import re
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from motionbits import __version__
from motionbits.config import MotionBitsConfig
from motionbits.config_file import config_from_dict, load_config
from motionbits.errors import InputError
from motionbits.outputs import StagedFolder
from motionbits.segmenter import STAGES, MotionBitsSegmenter
from motionbits.video import count_frames, is_video_file, iter_frames
from motionbits.video_writer import MAX_FPS, MIN_FPS, H264Writer

#: What ``segment`` writes into ``--out`` (``--overwrite`` replaces only such a folder).
OUTPUTS = {"labels", "overlay.mp4", "summary.json"}


def register(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "segment", help="segment the moving rigid bodies of a video",
        description="Write DIR/labels/NNNNN.png (16-bit label maps, 0 = background), "
                    "DIR/overlay.mp4 (H.264, with somprompt's numbered marks) and DIR/summary.json "
                    "(the whole config, the backend and the version; `--config DIR/summary.json` "
                    "repeats the run). Without INPUT, a built-in synthetic clip is generated and "
                    "segmented (and scored against its exact ground truth).")
    p.add_argument("input", nargs="?", help="video file or folder of images (default: built-in demo clip)")
    p.add_argument("--out", default="motionbits_out", help="output folder (default: %(default)s)")
    add_video_options(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing --out folder of an earlier run (default: refuse)")
    p.set_defaults(func=run)
    return p


def add_video_options(p: argparse.ArgumentParser) -> None:
    """The options that say how one video is segmented (shared with ``motionbits batch``)."""
    p.add_argument("--config", metavar="FILE",
                   help="TOML or JSON file setting any MotionBitsConfig field (e.g. n_nodes = 2500), "
                        "or the summary.json of an earlier run to repeat it; --nodes, --max-side and "
                        "--backend, --window override it")
    p.add_argument("--nodes", type=int, help=f"grid nodes n (default: {MotionBitsConfig.n_nodes})")
    p.add_argument("--max-side", type=int,
                   help=f"working resolution, longest side in px (default: {MotionBitsConfig.max_side})")
    p.add_argument("--every", type=int, default=1, help="use every K-th frame (default: %(default)s)")
    p.add_argument("--start", type=int, default=0,
                   help="index of the first frame to use (default: %(default)s)")
    p.add_argument("--frames", type=int, metavar="N",
                   help="stop after N used frames (default: all; the paper's windows are 11-16)")
    p.add_argument("--fps", type=float, default=10.0, help="frame rate of overlay.mp4 (default: %(default)s)")
    p.add_argument("--backend",
                   help="numpy, torch (CUDA if present), torch:cpu or torch:cuda[:N] "
                        f"(default: {MotionBitsConfig.backend})")
    p.add_argument("--flow",
                   help="optical flow: dis-medium, dis-fast, dis-ultrafast, or raft:PATH "
                        f"(torchvision RAFT weights file) (default: {MotionBitsConfig.flow})")
    p.add_argument("--refine", choices=("none", "sam2"),
                   help="refine each frame's masks: sam2 = SAM2 prompted per MotionBit, from --sam2 "
                        f"(default: {MotionBitsConfig.refine})")
    p.add_argument("--sam2", metavar="PATH",
                   help="SAM2 checkpoint folder (transformers format) for --refine sam2")
    p.add_argument("--strict", action="store_true",
                   help="fail if a video decodes fewer frames than its header says "
                        "(default: a warning, and both counts in summary.json)")
    p.add_argument("--window", type=int, metavar="N",
                   help="temporal constraints over about the last N frames only (more than 3N/4, "
                        "at most N; default: the whole video, as in the paper)")


def _ground_truth_scores(pred: np.ndarray, gt: np.ndarray) -> dict:
    """IoU of each ground-truth body with the predicted label covering most of it."""
    scores = {}
    for g in np.unique(gt[gt > 0]):
        m = gt == g
        ids, cnt = np.unique(pred[m], return_counts=True)
        best = int(ids[np.argmax(cnt)])
        p = pred == best if best else np.zeros_like(m)
        scores[int(g)] = {"pred_id": best, "iou": float((m & p).sum() / (m | p).sum())}
    bg_pred = pred == 0
    precision = float((bg_pred & (gt == 0)).sum() / max(bg_pred.sum(), 1))
    return {"bodies": scores, "background_precision": precision}


def _check_options(args: argparse.Namespace) -> MotionBitsConfig:
    """Every option check that needs no work; returns the segmenter config."""
    if args.every < 1:
        raise InputError(f"--every must be >= 1, got {args.every}")
    if args.start < 0:
        raise InputError(f"--start must be >= 0, got {args.start}")
    if args.frames is not None and args.frames < 1:
        raise InputError(f"--frames must be >= 1, got {args.frames}")
    if not (math.isfinite(args.fps) and args.fps > 0):
        raise InputError(f"--fps must be a positive number, got {args.fps:g}")
    if args.fps > MAX_FPS:  # else an OverflowError traceback from PyAV
        raise InputError(f"--fps must be at most {MAX_FPS}, got {args.fps:g}")
    if args.fps < MIN_FPS:  # else rounded to 0: an overlay at 24 fps
        raise InputError(f"--fps must be at least {MIN_FPS}, got {args.fps:g}")
    flags = {k: v for k, v in (("n_nodes", args.nodes), ("max_side", args.max_side),
                                ("backend", args.backend), ("flow", args.flow),
                                ("refine", args.refine), ("sam2_path", args.sam2),
                                ("window", args.window)) if v is not None}
    try:
        config = load_config(args.config, **flags) if args.config is not None else config_from_dict(
            flags, source="options")
    except (TypeError, ValueError) as exc:
        raise config_option_error(exc, flags) from None
    if args.sam2 and config.refine != "sam2":
        raise InputError("--sam2 PATH is used only with --refine sam2")
    return config


#: Command-line options that set a config field.
CONFIG_OPTIONS = {"n_nodes": "--nodes", "max_side": "--max-side", "backend": "--backend",
                  "flow": "--flow", "refine": "--refine", "sam2_path": "--sam2", "window": "--window"}


def config_option_error(exc: Exception, flags: dict) -> InputError:
    """The config's error, led by the option that set the offending field (if one did)."""
    msg = str(exc)
    for field, value in flags.items():
        if field in CONFIG_OPTIONS and re.search(rf"\b{field}\b", msg):
            return InputError(f"{CONFIG_OPTIONS[field]} {value}: {msg}")
    return InputError(msg)


def _build_segmenter(config: MotionBitsConfig) -> MotionBitsSegmenter:
    try:
        return MotionBitsSegmenter(config)
    except RuntimeError as exc:  # e.g. --backend torch:cuda without a GPU
        raise InputError(f"--backend {config.backend}: {exc}") from None


def run(args: argparse.Namespace, progress=tqdm) -> int:
    """Segment ``args.input`` into ``args.out``; ``progress`` makes the per-frame bar
    (tqdm's signature; ``motionbits batch`` passes one that reports to its parent)."""
    config = _check_options(args)
    seg = _build_segmenter(config)  # a missing extra (torch) fails here
    gt = None
    if args.input is None:
        from motionbits.synth import demo_clip

        print("no INPUT given: segmenting the built-in demo clip (16 synthetic frames, 480x640)")
        clip = demo_clip()
        source, total, gt = clip.frames, len(clip.frames), clip.gt
    else:
        source, total = args.input, count_frames(args.input)
    frames = iter_frames(source)
    first = next(frames)  # a missing, empty or unreadable input fails here, before any output
    frames = itertools.chain([first], frames)
    # index of the last frame to use (the frame count of some videos is unknown: None)
    last = float("inf") if args.frames is None else args.start + args.every * (args.frames - 1)
    # a video's count is its header's, which can be short: the frames then tell (the
    # input running out ends the loop); a folder's or an array's is exact
    if total is not None and not is_video_file(args.input) and args.start >= total:
        raise InputError(f"--start {args.start} is past the last frame ({total} frames)")
    with StagedFolder(args.out, overwrite=args.overwrite, replaceable=OUTPUTS) as staged:
        summary = _segment(args, seg, frames, total, last, staged.path, gt, progress)
        staged.publish()
    out = Path(args.out)
    print(f"{summary['motionbits_in_last_frame']} MotionBits in the last frame; "
          f"{summary['frames']} frames in {summary['timings_ms']['total_s']:.1f} s "
          f"(median {summary['timings_ms']['per_frame_median']:.0f} ms/frame)")
    if gt is not None:
        scores = summary["demo_ground_truth"]
        ious = ", ".join(f"{g}: {s['iou']:.2f}" for g, s in scores["bodies"].items())
        print(f"demo ground truth: IoU per body {{{ious}}}, "
              f"background precision {scores['background_precision']:.3f}")
    print(f"wrote {out}/labels/*.png, {out}/overlay.mp4, {out}/summary.json")
    return 0


def _segment(args, seg, frames, total, last, out: Path, gt, progress=tqdm) -> dict:
    """Segment the chosen frames into ``out``; returns the summary (also written there)."""
    from somprompt import MarkRegistry, SetOfMarkRenderer  # the command draws marks; the library does not

    config = seg.config
    stages = STAGES if seg.refiner is None else (*STAGES, "refine")
    (out / "labels").mkdir()
    # somprompt's numbered marks and palette: one id, one number and one colour in the
    # overlay, the marks pictures and the demos
    renderer, registry = SetOfMarkRenderer(), MarkRegistry()
    writer = H264Writer(out / "overlay.mp4", args.fps)
    records: dict[int, dict] = {}
    stage_ms: dict[str, list[float]] = {s: [] for s in stages}
    frame_ms: list[float] = []
    frames_done = []
    result = None
    decoded = 0  # frames read from the input
    shown = last if total is None else min(last, max(total - 1, args.start))  # for the bar only
    bar = progress(total=None if shown == float("inf") else (shown - args.start) // args.every + 1,
                   unit="frame", disable=True if args.quiet else None, desc="segment")
    try:
        for i, frame in enumerate(frames):
            if i > last:
                break
            decoded = i + 1
            if i < args.start or (i - args.start) % args.every:
                continue
            t0 = time.perf_counter()
            result = seg.update(frame)
            frame_ms.append(1000 * (time.perf_counter() - t0))
            if result.frame_index > 0:
                for s in stages:
                    stage_ms[s].append(result.timings.get(s, 0.0))
            frames_done.append(i)
            label_file = out / "labels" / f"{i:05d}.png"
            if not cv2.imwrite(str(label_file), result.labels.astype(np.uint16)):
                raise OSError(f"could not write {label_file}")
            registry.update(result.labels, frame_index=i)
            writer.write(renderer.render(frame, result.labels, registry).image)
            bar.update(1)
            for mb in result.motionbits:
                rec = records.setdefault(mb.id, {"id": mb.id})
                rec.update(area=mb.area, bbox=list(mb.bbox), centroid=list(mb.centroid),
                           first_moved=mb.first_moved, last_moved=mb.last_moved,
                           last_seen=result.frame_index)
        else:  # the input ran out before --frames / --start asked it to
            if total is not None and decoded < total:
                msg = (f"{args.input}: the header says {total} frames but only {decoded} could "
                       "be decoded (truncated or corrupt file)")
                if args.strict:
                    raise InputError(msg)
                tqdm.write(f"motionbits segment: warning: {msg}; --strict makes this an error",
                           file=sys.stderr)
            if result is None:
                raise InputError(f"--start {args.start} is past the last frame of {args.input} "
                                 f"({decoded} frames decoded)")
    except BaseException:
        bar.leave = False  # no stale progress bar above the error message
        writer.discard()  # its error, not the overlay's, is the one shown
        raise
    finally:
        bar.close()
        writer.close()
    final_ids = set(result.ids)
    summary = {
        "input": args.input or "built-in demo clip",
        "frames": len(frames_done),
        "input_frames": {"expected": total, "decoded": decoded},
        "frame_indices": frames_done,
        "size": list(result.labels.shape),
        "version": __version__,
        "backend": seg.backend,
        "config": dataclasses.asdict(config),  # `motionbits segment --config summary.json` repeats the run
        "window": {"every": args.every, "start": args.start, "frames": args.frames},
        "marks": {str(i): registry.number(i) for i in registry.ids},  # MotionBit id -> overlay number
        "motionbits": [dict(r, in_last_frame=r["id"] in final_ids) for r in
                       sorted(records.values(), key=lambda r: r["id"])],
        "timings_ms": {
            "per_frame_median": float(np.median(frame_ms[1:])) if len(frame_ms) > 1 else 0.0,
            "stages_median": {s: float(np.median(v)) if v else 0.0 for s, v in stage_ms.items()},
            "total_s": float(sum(frame_ms) / 1000),
        },
        "motionbits_in_last_frame": len(final_ids),
    }
    if seg.refiner is not None:  # refined / rejected masks, with the reasons
        summary["refinement"] = dict(seg.refiner.totals, method=config.refine)
    if gt is not None:
        summary["demo_ground_truth"] = _ground_truth_scores(result.labels, gt)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary
