"""The ``motionbits`` command line: one subcommand per module in ``motionbits.commands``.

Every expected failure ends the same way, here and only here: one line
``motionbits COMMAND: error: MESSAGE`` on stderr and exit status 2 (argparse's convention
for bad usage). ``--debug`` (before or after the command) shows the traceback instead.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from motionbits.errors import InputError

# Each module defines ``register(subparsers)``, which adds its parser and sets ``func``.
COMMAND_MODULES = (
    "motionbits.commands.segment",
    "motionbits.commands.batch",
    "motionbits.commands.bench",
    "motionbits.commands.eval",
    "motionbits.commands.synth",
    "motionbits.commands.benchmark",
    "motionbits.commands.compare",
    "motionbits.commands.scenes",
    "motionbits.commands.stack",
)

#: Failures that are the input's or the environment's, not a bug: reported in one line.
#: (``ImportError``: a missing optional extra, whose message names the pip command.)
EXPECTED_ERRORS = (InputError, ValueError, TypeError, OSError, ImportError, MemoryError)

_DEBUG_HELP = "show the full traceback of an error instead of a one-line message"


class _Parser(argparse.ArgumentParser):
    """argparse's parser with its usage errors on one line (subcommand parsers too)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="motionbits",
        description="Segment every moving rigid body in a video by its motion alone (MotionBits).",
    )
    parser.add_argument("--debug", action="store_true", help=_DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    for command in sub.choices.values():  # also accepted after the command
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help=_DEBUG_HELP)
    return parser


def one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line (multi-line hints joined with '; ')."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    text = "; ".join(lines) or type(exc).__name__
    if isinstance(exc, MemoryError):
        text = f"out of memory ({text})"
    elif isinstance(exc, OSError) and exc.filename and str(exc.filename) not in text:
        text = f"{exc.filename}: {text}"
    return text


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not args.debug:  # FFmpeg's own log lines would precede ours; our message says it all
        os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    try:
        return int(args.func(args) or 0)
    except EXPECTED_ERRORS as exc:
        if args.debug:
            raise
        print(f"motionbits {args.command}: error: {one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if args.debug:
            raise
        print(f"motionbits {args.command}: error: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
