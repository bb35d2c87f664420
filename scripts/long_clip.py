"""Write a long generated video for streaming and batch measurements.

The built-in demo scene (``motionbits.synth.demo_clip``, 480x640 by default) is rendered
for ``--period`` frames and played forward and back again until ``--frames`` frames are
written, so the bodies keep moving (and turning round) for as long as asked while only
one period is ever held in memory.

    python scripts/long_clip.py /tmp/long.mp4 --frames 2000 --size 480x640
"""

from __future__ import annotations

import argparse
from itertools import chain, cycle, islice

import cv2

from motionbits.synth import demo_clip


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", help="output video (.mp4, mp4v codec)")
    p.add_argument("--frames", type=int, default=2000, help="frames to write (default: %(default)s)")
    p.add_argument("--size", default="480x640", help="HxW (default: %(default)s)")
    p.add_argument("--period", type=int, default=40, help="frames per sweep (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="texture and noise seed (default: %(default)s)")
    p.add_argument("--fps", type=float, default=10.0, help="frame rate (default: %(default)s)")
    args = p.parse_args(argv)
    h, w = (int(v) for v in args.size.lower().split("x"))
    frames = demo_clip(n_frames=args.period, size=(h, w), seed=args.seed).frames
    sweep = chain(range(len(frames)), range(len(frames) - 2, 0, -1))  # 0..P-1, P-2..1
    writer = cv2.VideoWriter(args.out, cv2.VideoWriter_fourcc(*"mp4v"), args.fps, (w, h))
    if not writer.isOpened():
        raise SystemExit(f"could not open {args.out} for writing")
    for i in islice(cycle(list(sweep)), args.frames):
        writer.write(cv2.cvtColor(frames[i], cv2.COLOR_RGB2BGR))
    writer.release()
    print(f"wrote {args.out}: {args.frames} frames {h}x{w}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
