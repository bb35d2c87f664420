"""``motionbits bench``: speed of the segmenter, fast path against the exact one.

One run prints, on the same built-in clip: per-stage medians of the fast path and its
frames per second; the exact path (``MotionBitsConfig(exact=True)``: float64, every node
fitted, MCL iterated until idempotent) on the same frames with the time ratio and the
agreement of the two (adjusted Rand index of the grid-level labels and of the pixel
labels); and how the time per frame grows with the number of nodes and the input size.
With ``--data`` it also compares both paths on every scene of a MoRiBo-format dataset.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionbits.config import MotionBitsConfig
from motionbits.errors import InputError
from motionbits.segmenter import STAGES, MotionBitsResult, MotionBitsSegmenter

__all__ = ["register", "run", "ClipTiming", "time_clip", "parse_size"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench", help="SPEED of the segmenter: ms per stage and frame on a generated clip (accuracy: see benchmark)",
        description="Median milliseconds per stage and per frame on a generated clip (the "
                    "first frame, which only primes the stream, is excluded); the exact path "
                    "on the same frames with the agreement of the two; scaling with the "
                    "number of nodes and the input size. Timings are wall-clock on this "
                    "machine: close other work first.")
    p.add_argument("--frames", type=int, default=16, help="clip length (default: %(default)s)")
    p.add_argument("--size", default="640x480", metavar="WxH",
                   help="width x height of the clip, as in 'synth' (default: %(default)s)")
    p.add_argument("--nodes", type=int, default=MotionBitsConfig.n_nodes,
                   help="grid nodes n (default: %(default)s)")
    p.add_argument("--backend", default=MotionBitsConfig.backend,
                   help="numpy, torch (CUDA if present), torch:cpu or torch:cuda[:N] "
                        "(default: %(default)s)")
    p.add_argument("--no-exact", action="store_true", help="skip the exact-path comparison")
    p.add_argument("--no-scaling", action="store_true", help="skip the scaling tables")
    p.add_argument("--scaling-frames", type=int, default=8,
                   help="clip length of each scaling run (default: %(default)s)")
    p.add_argument("--data", metavar="DIR",
                   help="also compare fast and exact on every scene of this MoRiBo dataset")
    p.add_argument("--max-scenes", type=int, metavar="N", help="with --data: first N scenes per track")
    p.set_defaults(func=run)


def parse_size(text: str) -> tuple[int, int]:
    """``"WxH"`` (width first, as ``synth --size``) -> ``(H, W)``; each side at least 32."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError(f"--size must be WIDTHxHEIGHT like 640x480, got {text!r}") from None
    if h < 32 or w < 32:
        raise InputError(f"--size {text} is too small (at least 32x32)")
    return h, w


@dataclass
class ClipTiming:
    """One pass of the segmenter over a clip.

    Attributes:
        stages: median ms of each stage (``STAGES``) over the frames after the first.
        walls: wall ms of each ``update`` after the first.
        results: every frame's result.
    """

    stages: dict[str, float]
    walls: list[float]
    results: list[MotionBitsResult]

    @property
    def per_frame(self) -> float:
        return float(np.median(self.walls))


def time_clip(frames, config: MotionBitsConfig) -> ClipTiming:
    """Run a fresh segmenter over ``frames`` and time it."""
    seg = MotionBitsSegmenter(config)
    stages: dict[str, list[float]] = {s: [] for s in STAGES}
    walls, results = [], []
    for i, frame in enumerate(frames):
        t0 = time.perf_counter()
        res = seg.update(frame)
        if i > 0:
            walls.append(1000 * (time.perf_counter() - t0))
            for s in STAGES:
                stages[s].append(res.timings.get(s, 0.0))
        results.append(res)
    return ClipTiming({s: float(np.median(v)) for s, v in stages.items()}, walls, results)


def _agreement(a: list[MotionBitsResult], b: list[MotionBitsResult]) -> tuple[float, float, float]:
    """(final-frame grid ARI, lowest grid ARI over frames, final-frame pixel ARI)."""
    from motionbits.eval import adjusted_rand_index as ari

    grid = [ari(x.node_labels, y.node_labels) for x, y in zip(a[1:], b[1:])]
    return grid[-1], min(grid), ari(a[-1].labels, b[-1].labels)


def _print_stages(t: ClipTiming) -> None:
    print(f"{'stage':<14}{'median ms':>12}")
    for s in STAGES:
        print(f"{s:<14}{t.stages[s]:>12.1f}")
    print(f"{'per frame':<14}{t.per_frame:>12.1f}   ({1000 / t.per_frame:.2f} frames/s; "
          f"max {max(t.walls):.0f} ms)")
    if t.stages["flow"] > 0:
        print(f"{'per frame / flow':<17}{t.per_frame / t.stages['flow']:>9.2f}x")


def _scaling(rows: list[tuple[str, MotionBitsConfig, tuple[int, int]]], frames: int,
             unit: str, counts: list[int]) -> None:
    from motionbits.synth import demo_clip

    print(f"{'':<16}{'ms/frame':>10}{'frames/s':>10}{'x time':>8}{'x ' + unit:>10}"
          f"{'us per ' + unit[:-1]:>14}")
    base = None
    for (name, config, size), count in zip(rows, counts):
        t = time_clip(demo_clip(n_frames=frames, size=size).frames, config)
        if base is None:
            base = (t.per_frame, count)
        print(f"{name:<16}{t.per_frame:>10.1f}{1000 / t.per_frame:>10.2f}"
              f"{t.per_frame / base[0]:>8.2f}{count / base[1]:>10.2f}"
              f"{1000 * t.per_frame / count:>14.3f}")


def _compare_on_data(data: str, max_scenes: int | None, config: MotionBitsConfig) -> None:
    from motionbits.eval import adjusted_rand_index as ari
    from motionbits.eval import evaluate_frame, summarize
    from motionbits.eval.dataset import discover_scenes, load_scene

    scenes = discover_scenes(data, max_scenes)
    print(f"\nfast vs exact on {len(scenes)} scenes of {data} (final frame)")
    print(f"{'scene':<28}{'grid ARI':>10}{'pixel ARI':>10}{'fast ms':>9}{'exact ms':>9}")
    aris, scores = [], {"fast": [], "exact": []}
    ms = {"fast": [], "exact": []}
    for scene in scenes:
        frames, gt, ignore = load_scene(scene)
        runs = {"fast": time_clip(frames, config),
                "exact": time_clip(frames, config.with_(exact=True))}
        for k, t in runs.items():
            scores[k].append(evaluate_frame(t.results[-1].labels, gt, ignore))
            ms[k].append(t.per_frame)
        g = ari(runs["fast"].results[-1].node_labels, runs["exact"].results[-1].node_labels)
        p = ari(runs["fast"].results[-1].labels, runs["exact"].results[-1].labels)
        aris.append(g)
        print(f"{scene.key:<28}{g:>10.4f}{p:>10.4f}{ms['fast'][-1]:>9.0f}{ms['exact'][-1]:>9.0f}")
    aris = np.array(aris)
    miou = {k: 100 * summarize(v)["macro"]["mIoU"] for k, v in scores.items()}
    print(f"grid ARI: mean {aris.mean():.4f}, min {aris.min():.4f}, "
          f">= 0.99 on {(aris >= 0.99).sum()}/{len(aris)} scenes")
    print(f"macro mIoU vs ground truth: fast {miou['fast']:.1f}, exact {miou['exact']:.1f} "
          f"(difference {miou['fast'] - miou['exact']:+.1f} points); median ms/frame fast "
          f"{np.median(ms['fast']):.0f}, exact {np.median(ms['exact']):.0f}")


def run(args: argparse.Namespace) -> int:
    from motionbits.synth import demo_clip

    size = parse_size(args.size)
    if args.frames < 2:
        raise InputError("--frames must be >= 2 (the first frame only primes the stream)")
    if args.scaling_frames < 2:
        raise InputError("--scaling-frames must be >= 2 (the first frame only primes the stream)")
    if args.max_scenes is not None and args.max_scenes < 1:
        raise InputError(f"--max-scenes must be >= 1, got {args.max_scenes}")
    if args.data and not Path(args.data).exists():
        raise InputError(f"--data {args.data} not found")
    try:
        config = MotionBitsConfig(n_nodes=args.nodes, max_side=max(size), backend=args.backend)
        MotionBitsSegmenter(config)  # a missing extra (torch) or GPU fails here, before timing
    except (TypeError, ValueError, RuntimeError) as exc:
        from motionbits.commands.segment import config_option_error

        raise config_option_error(exc, {"n_nodes": args.nodes, "backend": args.backend}) from None
    clip = demo_clip(n_frames=args.frames, size=size)
    print(f"MotionBits bench: {args.frames} frames {size[0]}x{size[1]}, n = "
          f"{config.grid_side ** 2} nodes, flow {config.flow}, backend {config.backend}; "
          f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs")
    print("\nfast path (default)")
    fast = time_clip(clip.frames, config)
    _print_stages(fast)

    if not args.no_exact:
        print("\nexact path (exact=True: float64, every node fitted, MCL until idempotent)")
        exact = time_clip(clip.frames, config.with_(exact=True))
        _print_stages(exact)
        g_last, g_min, p_last = _agreement(fast.results, exact.results)
        print(f"exact / fast time: {exact.per_frame / fast.per_frame:.2f}x; agreement "
              f"(adjusted Rand index): grid final frame {g_last:.4f}, grid lowest frame "
              f"{g_min:.4f}, pixels final frame {p_last:.4f}")

    if not args.no_scaling:
        h, w = size
        print(f"\nscaling with the number of nodes ({h}x{w}, {args.scaling_frames} frames)")
        ns = [2_500, 10_000, 40_000]
        _scaling([(f"n = {n:,}", config.with_(n_nodes=n), size)
                  for n in ns], args.scaling_frames, "nodes", ns)
        sizes = [(240, 320), (480, 640), (720, 1280)]
        print(f"\nscaling with the input size (n = {config.grid_side ** 2:,}, processed at "
              f"full resolution, {args.scaling_frames} frames)")
        _scaling([(f"{sh}x{sw}", config.with_(max_side=max(sh, sw)),
                   (sh, sw)) for sh, sw in sizes], args.scaling_frames, "pixels",
                 [sh * sw for sh, sw in sizes])

    if args.data:
        _compare_on_data(args.data, args.max_scenes, MotionBitsConfig(backend=args.backend))
    return 0
