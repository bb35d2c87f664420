"""The ``motionbits`` command line: one subcommand per module in ``motionbits.commands``."""

from __future__ import annotations

import argparse
import importlib
import sys

# Each module defines ``register(subparsers)``, which adds its parser and sets ``func``.
COMMAND_MODULES = (
    "motionbits.commands.segment",
    "motionbits.commands.bench",
    "motionbits.commands.eval",
    "motionbits.commands.synth",
    "motionbits.commands.benchmark",
    "motionbits.commands.scenes",
    "motionbits.commands.stack",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="motionbits",
        description="Segment every moving rigid body in a video by its motion alone (MotionBits).",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (FileNotFoundError, ValueError, TypeError) as exc:
        print(f"motionbits {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
