"""``motionbits segment``: label maps, an overlay video and a summary for one video."""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from motionbits import __version__
from motionbits.config import MotionBitsConfig
from motionbits.config_file import config_from_dict, load_config
from motionbits.segmenter import STAGES, MotionBitsSegmenter
from motionbits.video import count_frames, iter_frames
from motionbits.video_writer import H264Writer


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "segment", help="segment the moving rigid bodies of a video",
        description="Write DIR/labels/NNNNN.png (16-bit label maps, 0 = background), "
                    "DIR/overlay.mp4 (H.264, with somprompt's numbered marks) and DIR/summary.json "
                    "(the whole config, the backend and the version; `--config DIR/summary.json` "
                    "repeats the run). Without INPUT, a built-in synthetic clip is generated and "
                    "segmented (and scored against its exact ground truth).")
    p.add_argument("input", nargs="?", help="video file or folder of images (default: built-in demo clip)")
    p.add_argument("--out", default="motionbits_out", help="output folder (default: %(default)s)")
    p.add_argument("--config", metavar="FILE",
                   help="TOML or JSON file setting any MotionBitsConfig field (e.g. n_nodes = 2500), "
                        "or the summary.json of an earlier run to repeat it; --nodes, --max-side and "
                        "--backend override it")
    p.add_argument("--nodes", type=int, help=f"grid nodes n (default: {MotionBitsConfig.n_nodes})")
    p.add_argument("--max-side", type=int,
                   help=f"working resolution, longest side in px (default: {MotionBitsConfig.max_side})")
    p.add_argument("--every", type=int, default=1, help="use every K-th frame (default: %(default)s)")
    p.add_argument("--start", type=int, default=0,
                   help="index of the first frame to use (default: %(default)s)")
    p.add_argument("--frames", type=int, metavar="N",
                   help="stop after N used frames (default: all; the paper's windows are 11-16)")
    p.add_argument("--fps", type=float, default=10.0, help="frame rate of overlay.mp4 (default: %(default)s)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--backend",
                   help="numpy, torch (CUDA if present), torch:cpu or torch:cuda[:N] "
                        f"(default: {MotionBitsConfig.backend})")
    p.set_defaults(func=run)


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


def run(args: argparse.Namespace) -> int:
    if args.every < 1:
        raise ValueError(f"--every must be >= 1, got {args.every}")
    if args.start < 0:
        raise ValueError(f"--start must be >= 0, got {args.start}")
    if args.frames is not None and args.frames < 1:
        raise ValueError(f"--frames must be >= 1, got {args.frames}")
    flags = {k: v for k, v in (("n_nodes", args.nodes), ("max_side", args.max_side),
                                ("backend", args.backend)) if v is not None}
    config = load_config(args.config, **flags) if args.config else config_from_dict(flags, source="options")
    gt = None
    if args.input is None:
        from motionbits.synth import demo_clip

        print("no INPUT given: segmenting the built-in demo clip (16 synthetic frames, 480x640)")
        clip = demo_clip()
        source, total, gt = clip.frames, len(clip.frames), clip.gt
    else:
        source, total = args.input, count_frames(args.input)
    out = Path(args.out)
    (out / "labels").mkdir(parents=True, exist_ok=True)

    from somprompt import MarkRegistry, SetOfMarkRenderer  # the command draws marks; the library does not

    seg = MotionBitsSegmenter(config)
    # somprompt's numbered marks and palette: one id, one number and one colour in the
    # overlay, the marks pictures and the demos
    renderer, registry = SetOfMarkRenderer(), MarkRegistry()
    writer = H264Writer(out / "overlay.mp4", args.fps)
    records: dict[int, dict] = {}
    stage_ms: dict[str, list[float]] = {s: [] for s in STAGES}
    frame_ms: list[float] = []
    frames_done = []
    result = None
    # index of the last frame to use (the frame count of some videos is unknown: None)
    last = float("inf") if args.frames is None else args.start + args.every * (args.frames - 1)
    if total is not None:
        if args.start >= total:
            raise ValueError(f"--start {args.start} is past the last frame ({total} frames)")
        last = min(last, total - 1)
    bar = tqdm(total=None if last == float("inf") else (last - args.start) // args.every + 1,
               unit="frame", disable=args.quiet, desc="segment")
    try:
        for i, frame in enumerate(iter_frames(source)):
            if i > last:
                break
            if i < args.start or (i - args.start) % args.every:
                continue
            bar.update(1)
            t0 = time.perf_counter()
            result = seg.update(frame)
            frame_ms.append(1000 * (time.perf_counter() - t0))
            if result.frame_index > 0:
                for s in STAGES:
                    stage_ms[s].append(result.timings.get(s, 0.0))
            frames_done.append(i)
            cv2.imwrite(str(out / "labels" / f"{i:05d}.png"), result.labels.astype(np.uint16))
            registry.update(result.labels, frame_index=i)
            writer.write(renderer.render(frame, result.labels, registry).image)
            for mb in result.motionbits:
                rec = records.setdefault(mb.id, {"id": mb.id})
                rec.update(area=mb.area, bbox=list(mb.bbox), centroid=list(mb.centroid),
                           first_moved=mb.first_moved, last_moved=mb.last_moved,
                           last_seen=result.frame_index)
    finally:
        bar.close()
        writer.close()
    if result is None:
        raise ValueError("the input holds no frames")
    final_ids = set(result.ids)
    summary = {
        "input": args.input or "built-in demo clip",
        "frames": len(frames_done),
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
    }
    if gt is not None:
        summary["demo_ground_truth"] = _ground_truth_scores(result.labels, gt)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(f"{len(final_ids)} MotionBits in the last frame; {len(frames_done)} frames in "
          f"{summary['timings_ms']['total_s']:.1f} s "
          f"(median {summary['timings_ms']['per_frame_median']:.0f} ms/frame)")
    if gt is not None:
        scores = summary["demo_ground_truth"]
        ious = ", ".join(f"{g}: {s['iou']:.2f}" for g, s in scores["bodies"].items())
        print(f"demo ground truth: IoU per body {{{ious}}}, "
              f"background precision {scores['background_precision']:.3f}")
    print(f"wrote {out}/labels/*.png, {out}/overlay.mp4, {out}/summary.json")
    return 0
