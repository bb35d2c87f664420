"""One video of a batch: ``motionbits segment`` into a temporary folder, renamed when complete."""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import time
import uuid
from functools import partial
from pathlib import Path
from typing import Callable

__all__ = ["PARTIAL_DIR", "segment_job", "clean_partial", "remove_partial_dir"]

#: Folder of DIR where videos are written before they are complete (same file system,
#: so that the final rename is atomic).
PARTIAL_DIR = ".partial"

Reporter = Callable[[str, int, "int | None"], None]  # (name, frames done, frames in total)


class _ReportingBar:
    """A tqdm stand-in for ``segment``'s per-frame bar that reports to a callback."""

    def __init__(self, name: str, report: Reporter, total: int | None = None, **_):
        self.name, self.report, self.total, self.n = name, report, total, 0
        report(name, 0, total)

    def update(self, n: int = 1) -> None:
        self.n += n
        self.report(self.name, self.n, self.total)

    def close(self) -> None:
        pass


def _segment_args(options: dict, source: str, out: Path) -> argparse.Namespace:
    """``segment``'s parsed arguments for one video: its defaults, then the batch's options."""
    from motionbits.commands import segment

    parser = segment.register(argparse.ArgumentParser().add_subparsers())
    args = parser.parse_args([source, "--out", str(out), "--quiet"])
    for key, value in options.items():
        setattr(args, key, value)
    return args


def segment_job(source: str, name: str, out_dir: str, options: dict,
                report: Reporter | None = None) -> dict:
    """Segment one video into ``out_dir/name`` as ``motionbits segment`` writes it.

    The outputs are written under ``out_dir/.partial/`` and renamed to ``out_dir/name``
    once complete (an older, unrecorded ``out_dir/name`` is replaced). Errors of the video
    (unreadable, corrupt, bad frames...) are returned, not raised.

    Args:
        source: path of a video file or folder of frames.
        name: output folder name.
        out_dir: the batch folder.
        options: ``segment`` options by argument name (``nodes``, ``window``, ...).
        report: called as ``report(name, frames_done, frames_total)`` after every frame.

    Returns:
        A batch record: input, output, status ("done" / "failed"), frames, seconds, error.
    """
    t0 = time.perf_counter()
    final = Path(out_dir) / name
    tmp = Path(out_dir) / PARTIAL_DIR / f"{name}.{uuid.uuid4().hex[:12]}"
    record = {"input": source, "output": None, "status": "failed", "frames": None,
              "seconds": None, "error": None}
    try:
        tmp.parent.mkdir(parents=True, exist_ok=True)
        from motionbits.commands import segment

        args = _segment_args(options, source, tmp)
        progress = partial(_ReportingBar, name, report or (lambda *_: None))
        with contextlib.redirect_stdout(io.StringIO()):  # its summary line: the record says it
            segment.run(args, progress=progress)
        frames = json.loads((tmp / "summary.json").read_text())["frames"]
        for attempt in range(2):  # an unrecorded earlier output is replaced
            if final.exists():
                shutil.rmtree(final)
            try:
                os.rename(tmp, final)
                break
            except OSError:
                if attempt:
                    raise
        record.update(output=str(final), status="done", frames=frames)
    except Exception as exc:  # one bad video never stops the batch
        record["error"] = f"{type(exc).__name__}: {exc}"
        shutil.rmtree(tmp, ignore_errors=True)
    record["seconds"] = round(time.perf_counter() - t0, 3)
    return record


def clean_partial(out_dir: str | os.PathLike) -> int:
    """Remove what interrupted runs left under ``out_dir/.partial``; returns how many."""
    part = Path(out_dir) / PARTIAL_DIR
    if not part.is_dir():
        return 0
    left = list(part.iterdir())
    for p in left:
        shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink(missing_ok=True)
    return len(left)


def remove_partial_dir(out_dir: str | os.PathLike) -> None:
    """Remove ``out_dir/.partial`` if nothing is left in it."""
    try:
        (Path(out_dir) / PARTIAL_DIR).rmdir()
    except OSError:
        pass
