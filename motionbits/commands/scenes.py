"""``motionbits scenes``: cut an annotated sequence into MoRiBo-format scenes."""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "scenes",
        help="cut an annotated sequence (DAVIS style) into MoRiBo-format scenes",
        description=(
            "Cut a DAVIS-style sequence (SRC/frames/ and SRC/gt/ with one mask per frame, 0 = "
            "background; or a DAVIS JPEGImages/480p/<seq> folder, masks from the matching "
            "Annotations/480p/<seq>) into windows of --length frames every "
            "--stride frames. Each window becomes a scene OUT/<name>_<first frame>/ with frames/, "
            "gt.png (the window's last mask, objects relabelled 1..K) and meta.json, so that "
            "'motionbits benchmark --data OUT' scores it."
        ),
    )
    p.add_argument("format", choices=("davis",), help="layout of SRC (davis)")
    p.add_argument("src", metavar="SRC", help="sequence folder")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (a track of scenes)")
    p.add_argument("--length", type=int, default=16, metavar="T", help="frames per scene (16)")
    p.add_argument("--stride", type=int, default=8, metavar="S",
                   help="frames between window starts (8)")
    p.add_argument("--max-side", type=int, default=640, metavar="PX",
                   help="resize so that the longest side is at most PX (640; 0 keeps the size)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from motionbits.eval.sequences import scenes_from_sequence
    from motionbits.outputs import check_named

    if args.length < 2:  # else the library's message names ``length``, not the option
        raise ValueError(f"--length must be >= 2, got {args.length}")
    if args.stride < 1:
        raise ValueError(f"--stride must be >= 1, got {args.stride}")
    if args.max_side < 0:
        raise ValueError(f"--max-side must be >= 0, got {args.max_side}")
    check_named(args.out, "--out", "folder")  # else the current folder
    scenes = scenes_from_sequence(args.src, args.out, length=args.length, stride=args.stride,
                                  max_side=args.max_side)
    print(f"wrote {len(scenes)} scenes to {args.out}")
    return 0
