"""The user-facing error of the command line.

Command code raises :class:`InputError` for a failure the user can fix (a bad option, an
unreadable input, an output that cannot be written). ``motionbits.cli.main`` turns it, and
the standard ``ValueError`` / ``TypeError`` / ``OSError`` / ``ImportError`` that the
library raises on bad input, into one line on stderr and exit status 2; ``--debug`` shows
the traceback instead.
"""

from __future__ import annotations

__all__ = ["InputError"]


class InputError(ValueError):
    """A failure caused by the user's input or options; its message is one line that
    names the input and what is wrong with it."""
