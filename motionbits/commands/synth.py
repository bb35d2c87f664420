"""``motionbits synth``: generate MoRiBo-format benchmark scenes with MuJoCo."""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path

from motionbits.errors import InputError
from motionbits.outputs import StagedFolder, check_named

__all__ = ["register", "run"]

#: Most scenes per track: their folders are numbered with four digits.
MAX_SCENES = 10_000


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "synth",
        help="generate MoRiBo-format clips with exact ground truth (MuJoCo, [sim] extra)",
        description=(
            "Simulate tabletop scenes in MuJoCo (a gripper or a hand pushes free blocks, glued "
            "composites, drawers, doors, laptop lids) and write MoRiBo-format scenes: frames/, "
            "gt.png (every rigid body that moved during the clip, last frame), meta.json. "
            "Needs: pip install motionbits[sim]."
        ),
    )
    p.add_argument("--track", choices=("robot", "hand", "pickplace"), action="append",
                   required=True,
                   help="track to generate (repeat for several): robot, hand (pushes), pickplace "
                        "(harder: natural textures, shadows, an articulated hand or gripper "
                        "carries a block across the table while other bodies move)")
    p.add_argument("--scenes", type=int, default=40, metavar="N", help="scenes per track (40, at most 10000)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (0)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (DIR/<track>/...)")
    p.add_argument("--size", default="640x480", metavar="WxH", help="frame size (640x480)")
    p.add_argument("--frames", type=int, default=None, metavar="T",
                   help="frames per clip (default: random 12-16 per scene)")
    p.add_argument("--camera", default="static",
                   choices=("static", "pan", "orbit", "shake", "moving"),
                   help="camera motion (static): pan turns in place, orbit circles the table "
                        "(parallax), shake is hand-held jitter, moving draws one of the three "
                        "per scene; a moving camera writes to DIR/<track>-<camera>/")
    p.add_argument("--flow", action="store_true",
                   help="also write the exact optical flow of every frame pair, both "
                        "directions, with visibility masks (flow/NNNNN.npz; see docs/evaluation.md)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the tracks already in --out (default: refuse; other tracks "
                        "in --out are always kept)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError(f"--size must be WIDTHxHEIGHT like 640x480, got {text!r}") from None
    if w < 32 or h < 32:
        raise InputError(f"--size {text} is too small (at least 32x32)")
    return w, h


def run(args: argparse.Namespace) -> int:
    w, h = _size(args.size)
    check_named(args.out, "--out", "folder")  # else ./<track>
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise InputError(f"--out {args.out} is a file, not a folder")
    if args.scenes < 1:
        raise InputError("--scenes must be at least 1")
    if args.scenes > MAX_SCENES:  # 10**20: an OverflowError traceback from the progress bar
        raise InputError(f"--scenes must be at most {MAX_SCENES} (scene_0000 .. scene_9999), got {args.scenes}")
    if args.frames is not None and args.frames < 2:
        raise InputError("--frames must be at least 2")
    if args.seed < 0:  # numpy's seed sequence refuses it ("expected non-negative integer")
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    from motionbits.synth.mujoco_backend import import_mujoco
    from motionbits.synth.mujoco_moribo import generate_track

    import_mujoco()  # the [sim] extra: fails here, before any output
    # each track is written to a temporary folder renamed to --out/<track>[-<camera>] when
    # complete: never half-written; other tracks already in --out are kept
    names = {t: t if args.camera == "static" else f"{t}-{args.camera}"
             for t in dict.fromkeys(args.track)}
    with contextlib.ExitStack() as stack:
        staged = {t: stack.enter_context(StagedFolder(Path(args.out) / n, overwrite=args.overwrite,
                                                      replaceable={"scene_*"}))
                  for t, n in names.items()}
        for track, folder in staged.items():
            generate_track(track, args.scenes, args.seed, folder.path, width=w, height=h,
                           n_frames=args.frames, progress=not args.quiet, camera=args.camera,
                           flow=args.flow)
        for track, folder in staged.items():
            folder.publish(inner=names[track])
    print(f"wrote {', '.join(f'{args.out}/{n}' for n in names.values())}")
    return 0
