"""``motionbits benchmark``: run methods over a MoRiBo dataset and print the Table 2 layout."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "benchmark",
        help="run segmentation methods on MoRiBo-format data and score them",
        description=(
            "Run each method on every scene (frames -> last-frame label map), score it with the "
            "MoRiBo protocol (see 'motionbits eval') and print Overlap / Boundary P R F1 (mIoU) "
            "per track and averaged over tracks, with seconds per frame."
        ),
    )
    p.add_argument("--data", required=True, metavar="DIR",
                   help="MoRiBo scene, track (folder of scenes) or folder of tracks")
    p.add_argument("--methods", nargs="+", default=["flow-cc", "affine-ransac", "motionbits"],
                   metavar="NAME", help="registered methods (default: flow-cc affine-ransac "
                                        "motionbits; --list shows all)")
    p.add_argument("--list", action="store_true", help="list the registered methods and exit")
    p.add_argument("--json", metavar="FILE", help="write all scores and timings here")
    p.add_argument("--save-pred", metavar="DIR", help="write predictions as DIR/<method>/<track>/<scene>.png")
    p.add_argument("--max-scenes", type=int, metavar="N", help="only the first N scenes per track")
    p.add_argument("--pooled", action="store_true", help="also print the pooled (UOIS) table")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from motionbits.baselines import available_methods, make_method
    from motionbits.eval.benchmark import run_benchmark
    from motionbits.eval.table import format_table, json_ready

    if args.list:
        for name, desc in available_methods().items():
            print(f"{name:<16} {desc}")
        return 0
    known = available_methods()
    unknown = [m for m in args.methods if m not in known]
    if unknown:
        raise ValueError(f"unknown method(s) {', '.join(unknown)}; available: {', '.join(known)}")
    methods = {name: make_method(name) for name in dict.fromkeys(args.methods)}
    results, spf = run_benchmark(args.data, methods, save_pred=args.save_pred,
                                 max_scenes=args.max_scenes, progress=not args.quiet)
    print(format_table(results, block="macro", seconds_per_frame=spf), end="")
    if args.pooled:
        print()
        print(format_table(results, block="pooled", seconds_per_frame=spf), end="")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        payload = {"methods": results, "seconds_per_frame": spf}
        Path(args.json).write_text(json.dumps(json_ready(payload), indent=1, allow_nan=False))
    return 0
