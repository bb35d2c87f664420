"""A resumable batch: which videos are left, the engines, the journal and the progress bars."""

from __future__ import annotations

import numbers
import os
import time
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from motionbits.batch.inputs import BatchInput
from motionbits.batch.job import clean_partial, remove_partial_dir
from motionbits.batch.journal import Journal
from motionbits.frames import whole_number

__all__ = ["BatchReport", "run_batch", "ENGINES", "JOURNAL_NAME"]

ENGINES = ("local", "ray")
JOURNAL_NAME = "batch.jsonl"


@dataclass(frozen=True)
class BatchReport:
    """What one ``run_batch`` call did.

    Attributes:
        done, failed: videos finished now, by status.
        skipped: videos already recorded by an earlier run (not redone).
        failed_total: videos of the batch whose record says failed (now or earlier).
        cleaned: unfinished outputs of interrupted runs removed at the start.
        seconds: wall time of the call.
    """

    done: int
    failed: int
    skipped: int
    failed_total: int
    cleaned: int
    seconds: float


class _Bars:
    """One bar for the batch (videos) and one per video in progress (frames)."""

    def __init__(self, total: int, quiet: bool):
        self.quiet = quiet
        self.batch = tqdm(total=total, unit="video", desc="batch", disable=quiet, position=0)
        self.videos: dict[str, tqdm] = {}

    def frame(self, name: str, done: int, total: int | None) -> None:
        if self.quiet:
            return
        bar = self.videos.get(name)
        if bar is None:  # the lowest free line below the batch bar
            taken = {b.pos for b in self.videos.values()}
            line = next(i for i in range(1, len(taken) + 2) if i not in taken)
            bar = self.videos[name] = tqdm(total=total, unit="frame", desc=name[:24],
                                           leave=False, position=line)
            bar.pos = line
        bar.update(done - bar.n)

    def video(self, record: dict, name: str) -> None:
        bar = self.videos.pop(name, None)
        if bar is not None:
            bar.close()
        self.batch.update(1)
        if record["status"] == "failed":
            self.batch.write(f"failed: {record['input']}: {record['error']}")

    def close(self) -> None:
        for bar in self.videos.values():
            bar.close()
        self.batch.close()


def run_batch(items: list[BatchInput], out_dir: str, options: dict | None = None, *,
              engine: str = "local", workers: int | None = None, address: str | None = None,
              retry_failed: bool = False, quiet: bool = False) -> BatchReport:
    """Segment every video of ``items`` into ``out_dir/<name>/``, resuming an earlier run.

    Videos with a record in ``out_dir/batch.jsonl`` are skipped ("done" always, "failed"
    unless ``retry_failed``); outputs of interrupted runs (``out_dir/.partial``) are
    removed first. Each finished video gets one record, written by this process.

    Args:
        items: the videos (see :func:`motionbits.batch.expand_inputs`).
        out_dir: the batch folder (created if missing).
        options: ``segment`` options by argument name (``nodes``, ``window``, ...).
        engine: "local" (a process pool) or "ray".
        workers: processes (local; default: the CPUs) or CPUs of a local Ray instance.
        address: Ray cluster to join instead of starting one.
        retry_failed: run videos recorded as failed again.
        quiet: no progress bars.

    Raises (before any work):
        TypeError / ValueError: ``items`` not a list of :class:`BatchInput`, two of them
            with one path or one name (exact repeats run once), ``out_dir`` empty or a
            file, ``options`` not a dict of ``segment`` options with usable values, or
            ``engine`` / ``workers`` out of range.
    """
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
    if workers is not None and whole_number("workers", workers) < 1:
        raise ValueError(f"--workers must be >= 1, got {workers}")
    items = _check_items(items)
    if not isinstance(out_dir, (str, os.PathLike)) or not os.fspath(out_dir).strip():
        raise ValueError(f"out_dir must name the batch folder, got {out_dir!r:.40}")  # "": the current folder
    if Path(out_dir).exists() and not Path(out_dir).is_dir():
        raise ValueError(f"out_dir {out_dir} is a file, not a folder")
    _check_batch_options(options)
    t0 = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    journal = Journal(out / JOURNAL_NAME)
    cleaned = clean_partial(out)
    skip = {"done", "failed"} - ({"failed"} if retry_failed else set())
    todo = [it for it in items if journal.status(it.path) not in skip]
    names = {it.path: it.name for it in todo}
    counts = {"done": 0, "failed": 0}
    bars = _Bars(len(todo), quiet)

    def on_record(record: dict) -> None:
        journal.append(record)
        counts[record["status"]] += 1
        bars.video(record, names[record["input"]])

    kwargs = dict(on_record=on_record, on_progress=bars.frame)
    try:
        if todo and engine == "local":
            from motionbits.batch.local import default_workers, run_local

            run_local(todo, str(out), options or {}, workers=workers or default_workers(),
                      **kwargs)
        elif todo:
            from motionbits.batch.ray_engine import run_ray

            run_ray(todo, str(out), options or {}, address=address, workers=workers, **kwargs)
        clean_partial(out)  # what workers killed during this run left
    finally:
        bars.close()
        remove_partial_dir(out)
    failed_total = sum(journal.status(it.path) == "failed" for it in items)
    return BatchReport(counts["done"], counts["failed"], len(items) - len(todo), failed_total,
                       cleaned, time.perf_counter() - t0)


def _check_items(items: object) -> list[BatchInput]:
    """``items`` as a list without exact repeats; two videos of one path or of one output
    name are refused (the second output replaced the first, both recorded as done)."""
    if isinstance(items, (str, bytes)) or not isinstance(items, (list, tuple)) or not all(
            isinstance(it, BatchInput) for it in items):
        raise TypeError(f"items must be a list of BatchInput (see motionbits.batch.expand_inputs), "
                        f"got {items!r:.60}")
    unique = list(dict.fromkeys(items))
    for key in ("path", "name"):
        seen: dict[str, BatchInput] = {}
        for it in unique:
            other = seen.setdefault(getattr(it, key), it)
            if other is not it:
                raise ValueError(f"items hold two videos of {key} {getattr(it, key)!r} ({other.path} "
                                 f"as {other.name!r}, {it.path} as {it.name!r}); each video needs "
                                 "its own path and output name (expand_inputs gives them)")
    return unique


#: ``segment`` arguments that the batch sets itself, not an option.
_NOT_OPTIONS = {"input", "out", "overwrite", "quiet", "func", "command", "json", "debug"}


def _check_batch_options(options: object) -> None:
    """Every ``segment`` option check that needs no work, once for the batch (an unknown
    option was ignored; a bad value, or options that are not a dict, failed every video)."""
    import argparse

    from motionbits.batch.job import _segment_args
    from motionbits.commands.segment import _check_options

    if options is None:
        return
    if not isinstance(options, dict):
        raise TypeError(f"options must be a dict of segment options, got {type(options).__name__}")
    args = _segment_args({}, "input", Path("out"))
    known = sorted(set(vars(args)) - _NOT_OPTIONS)
    unknown = sorted(str(k) for k in options if k not in known)
    if unknown:
        raise ValueError(f"unknown segment option(s) {', '.join(map(repr, unknown))}; "
                         f"known: {', '.join(known)}")
    for key, value in options.items():
        default = getattr(args, key)
        if value is None or key in ("config", "flow", "backend", "refine", "sam2"):
            continue  # None: segment's default; names: checked by the config below
        if isinstance(default, bool) or key == "strict":
            if not isinstance(value, bool):
                raise TypeError(f"option {key!r} must be True or False, got {value!r:.40}")
        elif key == "fps":
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise TypeError(f"option 'fps' must be a number, got {value!r:.40}")
        else:
            whole_number(f"option {key!r}", value)
    _check_options(argparse.Namespace(**{**vars(args), **options}))
