"""``motionbits batch``: segment many videos, resumable, on a process pool or Ray."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from motionbits.commands.segment import _check_options, add_video_options
from motionbits.errors import InputError
from motionbits.outputs import check_named

__all__ = ["register", "run"]

_EPILOG = """\
examples:
  motionbits batch clips/*.mp4 --out runs/clips
  motionbits batch /data/bridge --out runs/bridge --window 30      # every video below
  motionbits batch list.txt --out runs/x --engine ray --address auto

Exit status 0 when every video is done, 1 when some failed (see their "error"), 2 on
bad options. Run the same command again to resume after Ctrl-C, a crash or kill -9: videos recorded in
DIR/batch.jsonl are not redone, and unfinished outputs are removed.
"""


def register(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "batch", help="segment many videos (resumable; process pool or Ray)",
        description="Segment every input video as 'motionbits segment' does, into "
                    "DIR/<input stem>/, and append one JSON line per finished video to "
                    "DIR/batch.jsonl (input, output, status done|failed, frames, seconds, "
                    "error). A video that fails is recorded and the batch goes on.",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="video files, folders (a folder of frames is one video; another folder "
                        "means every video below it), globs, or .txt lists of these")
    p.add_argument("--out", required=True, metavar="DIR", help="batch folder")
    p.add_argument("--engine", choices=("local", "ray"), default="local",
                   help="local: a process pool on this machine (default); ray: Ray tasks "
                        "(pip install 'motionbits[ray]')")
    p.add_argument("--workers", type=int, metavar="N",
                   help="processes (local) or CPUs of the local Ray instance (default: all CPUs)")
    p.add_argument("--address", metavar="ADDR",
                   help="with --engine ray: join this cluster (e.g. auto, ray://head:10001) "
                        "instead of starting Ray here")
    p.add_argument("--retry-failed", action="store_true",
                   help="run videos recorded as failed again (default: keep their record)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    add_video_options(p)
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from motionbits.batch import expand_inputs, run_batch

    check_named(args.out, "--out", "folder")  # else the current folder
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise InputError(f"--out {args.out} is a file, not a folder")
    if args.address and args.engine != "ray":
        raise ValueError("--address needs --engine ray")
    if args.engine == "ray":  # the extra is checked before --out is made
        from motionbits.batch.ray_engine import import_ray

        import_ray()
    own = {"inputs", "out", "engine", "workers", "address", "retry_failed", "quiet", "func",
           "command", "debug"}
    options = {k: v for k, v in vars(args).items() if k not in own}
    # bad option values fail here, once, rather than in every video
    _check_options(args)
    items = expand_inputs(args.inputs)
    try:
        report = run_batch(items, args.out, options, engine=args.engine, workers=args.workers,
                           address=args.address, retry_failed=args.retry_failed,
                           quiet=args.quiet)
    except KeyboardInterrupt:
        print(f"interrupted; finished videos are recorded in {args.out}/batch.jsonl: run the "
              "same command again to resume", file=sys.stderr)
        return 130
    print(f"{len(items)} videos: {report.done} done, {report.failed} failed now, "
          f"{report.skipped} already recorded ({report.failed_total} failed in all); "
          f"{report.seconds:.1f} s; see {args.out}/batch.jsonl")
    return 1 if report.failed_total else 0
