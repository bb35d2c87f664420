"""``motionbits bench``: per-stage timing of the segmenter on the built-in clip."""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from motionbits.config import MotionBitsConfig
from motionbits.segmenter import STAGES, MotionBitsSegmenter


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="time each stage of the segmenter on a synthetic clip",
                       description="Median milliseconds per stage over a generated clip "
                                   "(the first frame, which only primes the stream, is excluded).")
    p.add_argument("--frames", type=int, default=16, help="clip length (default: %(default)s)")
    p.add_argument("--size", default="480x640", help="HxW of the clip (default: %(default)s)")
    p.add_argument("--nodes", type=int, default=MotionBitsConfig.n_nodes, help="grid nodes n (default: %(default)s)")
    p.add_argument("--backend", default=MotionBitsConfig.backend,
                   help="numpy, torch (CUDA if present), torch:cpu or torch:cuda[:N] (default: %(default)s)")
    p.set_defaults(func=run)


def parse_size(text: str) -> tuple[int, int]:
    try:
        h, w = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ValueError(f"--size must look like 480x640, got {text!r}") from None
    return h, w


def time_clip(frames: np.ndarray, config: MotionBitsConfig) -> tuple[dict[str, float], list[float]]:
    """Per-stage median ms and the per-frame wall times (ms) of one pass over ``frames``."""
    seg = MotionBitsSegmenter(config)
    stages: dict[str, list[float]] = {s: [] for s in STAGES}
    walls = []
    for i, frame in enumerate(frames):
        t0 = time.perf_counter()
        res = seg.update(frame)
        if i > 0:
            walls.append(1000 * (time.perf_counter() - t0))
            for s in STAGES:
                stages[s].append(res.timings.get(s, 0.0))
    return {s: float(np.median(v)) for s, v in stages.items()}, walls


def run(args: argparse.Namespace) -> int:
    from motionbits.synth import demo_clip

    size = parse_size(args.size)
    config = MotionBitsConfig(n_nodes=args.nodes, max_side=max(size), backend=args.backend)
    clip = demo_clip(n_frames=args.frames, size=size)
    print(f"MotionBits bench: {args.frames} frames {size[0]}x{size[1]}, n = {config.grid_side ** 2} "
          f"nodes, flow {config.flow}, backend {config.backend}; {platform.processor() or platform.machine()}, "
          f"{__import__('os').cpu_count()} CPUs")
    medians, walls = time_clip(clip.frames, config)
    print(f"{'stage':<14}{'median ms':>12}")
    for s in STAGES:
        print(f"{s:<14}{medians[s]:>12.1f}")
    total = float(np.median(walls))
    print(f"{'per frame':<14}{total:>12.1f}   ({1000 / total:.2f} frames/s; max {max(walls):.0f} ms)")
    return 0
