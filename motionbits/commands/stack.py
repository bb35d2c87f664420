"""``motionbits stack``: the tower-stacking experiment of the paper's Table 3, in MuJoCo."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from motionbits.errors import InputError
from motionbits.outputs import check_named, check_output_file, write_text_atomic

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "stack",
        help="tower stacking from segmentation masks in simulation (paper Table 3, [sim] extra)",
        description=(
            "Five glued composite objects on a table; a gripper pushes each once while the camera "
            "records; each method segments the clip; a greedy controller grasps the largest mask "
            "at its centroid and principal axes and stacks it on a tower. Every method runs on "
            "the same seeded trials. Needs: pip install motionbits[sim]."
        ),
    )
    p.add_argument("--trials", type=int, default=10, metavar="N", help="trials per method (10)")
    p.add_argument("--methods", default="motionbits,per-colour,gt", metavar="M1,M2,...",
                   help="comma-separated method names: 'gt' (ground-truth masks) or any "
                        "benchmark method (motionbits, per-colour, flow-cc, affine-ransac, ...)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (0)")
    p.add_argument("--video", default=None, metavar="DIR",
                   help="write DIR/<method>_trial<i>.mp4 of every trial (slower)")
    p.add_argument("--json", default=None, metavar="FILE", help="write the summary as JSON")
    p.add_argument("--quiet", action="store_true", help="no per-trial lines")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from motionbits.stacking.run import format_table, run_stacking, summarise

    # a method named twice runs once (as in benchmark), not twice into one row
    methods = list(dict.fromkeys(m.strip() for m in args.methods.split(",") if m.strip()))
    if not methods:
        raise ValueError("--methods is empty")
    if args.trials < 1:
        raise ValueError(f"--trials must be >= 1, got {args.trials}")
    if args.seed < 0:  # numpy's seed sequence refuses it ("expected non-negative integer")
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    # the outputs are checked before the trials (minutes of simulation), not after
    if args.json is not None:
        check_output_file(args.json, "--json")
    if args.video is not None:
        check_named(args.video, "--video", "folder")  # else the current folder
        if Path(args.video).exists() and not Path(args.video).is_dir():
            raise InputError(f"--video {args.video} is a file, not a folder")
    t0 = time.perf_counter()
    try:
        results = run_stacking(methods, args.trials, args.seed, video_dir=args.video,
                               progress=None if args.quiet else print)
    except KeyError as exc:  # unknown method: the message lists the known ones
        raise ValueError(exc.args[0]) from None
    summary = summarise(results)
    summary["seed"] = args.seed
    summary["wall_seconds"] = round(time.perf_counter() - t0, 1)
    print(format_table(summary))
    print(f"{args.trials} trials x {len(methods)} methods in {summary['wall_seconds']:.0f} s")
    if args.json is not None:
        write_text_atomic(args.json, json.dumps(summary, indent=1))
    return 0
