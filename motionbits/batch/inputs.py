"""Which videos a batch holds: files, folders, globs and list files, expanded once."""

from __future__ import annotations

import glob
import hashlib
import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from motionbits.video import is_frame_file

__all__ = ["BatchInput", "expand_inputs", "LIST_SUFFIXES", "VIDEO_SUFFIXES"]

#: Files read as lists of inputs (one path, folder or glob a line; ``#`` starts a comment).
LIST_SUFFIXES = (".txt", ".list")
#: Files a folder is searched for (a file named explicitly is tried whatever its suffix).
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".mpg", ".mpeg")


@dataclass(frozen=True)
class BatchInput:
    """One video of a batch.

    Attributes:
        path: absolute path of a video file or of a folder of frames.
        name: output folder name, unique in the batch: the input's stem, or
            ``stem-<8 hex of the path>`` where two inputs share a stem or the stem is
            that of the batch's own files (``batch.jsonl``, ``.partial``).
    """

    path: str
    name: str


def _holds_images(folder: Path) -> bool:
    return any(is_frame_file(p) for p in folder.iterdir())


def _from_folder(folder: Path) -> list[Path]:
    """A folder of frames is one video; otherwise every video file and every folder of
    frames below it (recursively, sorted)."""
    if _holds_images(folder):
        return [folder]
    found = []
    for p in sorted(folder.rglob("*")):
        if p.is_file() and p.suffix.lower() in VIDEO_SUFFIXES:
            found.append(p)
        elif p.is_dir() and _holds_images(p):
            found.append(p)
    return found


def _expand(item: str, base: Path, *, from_list: bool, reading: tuple[Path, ...] = ()) -> list[Path]:
    """``reading``: the list files being read, outermost first (a list naming itself, or
    lists naming each other, would recurse for ever)."""
    if any(c in item for c in "*?["):
        pattern = item if Path(item).is_absolute() else str(base / item)
        matches = sorted(glob.glob(pattern, recursive=True))
        if not matches:
            raise ValueError(f"no file matches {item!r}")
        return [q for m in matches if Path(m).resolve() not in reading  # "*" in a list: not itself
                for q in _expand(m, base, from_list=from_list, reading=reading)]
    path = Path(item) if Path(item).is_absolute() else base / item
    if path.is_dir():
        return _from_folder(path)
    if path.suffix.lower() in LIST_SUFFIXES and path.is_file():
        return _read_list(path, reading)
    if not path.exists() and not from_list:
        raise FileNotFoundError(f"input not found: {item}")
    return [path]  # a missing file named in a list fails as a video of the batch


def _read_list(path: Path, reading: tuple[Path, ...] = ()) -> list[Path]:
    key = path.resolve()
    if key in reading:
        chain = " -> ".join(str(p) for p in (*reading[reading.index(key):], key))
        raise ValueError(f"list file {path} names itself (through {chain}); a list must not "
                         "include itself")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"list file {path} is not text (UTF-8): it must name one video, "
                         "folder or glob per line") from None
    out = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            out.extend(_expand(line, path.parent, from_list=True, reading=(*reading, key)))
    return out


def expand_inputs(items: list[str], cwd: Path | None = None) -> list[BatchInput]:
    """Expand the command line's INPUTS into the batch's videos, in order, without repeats.

    Args:
        items: video files, folders (a folder of frames is one video; any other folder
            stands for every video file and folder of frames below it), glob patterns
            (``**`` recurses) and list files (``.txt`` / ``.list``; relative lines are
            read from the list's folder).
        cwd: folder that relative items are read from (default: the current one).

    Raises:
        FileNotFoundError: an item on the command line does not exist.
        ValueError: an empty item, a glob that matches nothing, or nothing left to process.
        TypeError: ``items`` is not a list (a str is one input: pass ``[path]``).
    """
    if isinstance(items, (str, bytes, os.PathLike)) or not isinstance(items, (list, tuple)):
        # a str was read letter by letter: "/" searched the whole file system
        raise TypeError(f"items must be a list of inputs, e.g. [{str(items)!r:.40}], got "
                        f"{type(items).__name__}")
    base = (cwd or Path.cwd()).resolve()
    paths: list[str] = []
    seen = set()
    for item in items:
        if not str(item).strip():  # Path("") is the current folder
            raise ValueError(f"the input path is empty ({str(item)!r}); pass a video, a folder, "
                             "a glob or a list file")
        for p in _expand(str(item), base, from_list=False):
            key = str(p.resolve())
            if key not in seen:
                seen.add(key)
                paths.append(key)
    if not paths:
        raise ValueError("the inputs hold no video (files, folders of frames or globs)")
    from motionbits.batch.job import PARTIAL_DIR
    from motionbits.batch.runner import JOURNAL_NAME

    stems = [Path(p).stem for p in paths]
    count = Counter(stems)
    # a stem that names the batch's own files gets the suffix too (batch.jsonl.mp4 was
    # written over the journal, .partial.mp4 into the folder of unfinished outputs)
    count.update(s for s in stems if s in (JOURNAL_NAME, PARTIAL_DIR))
    return [BatchInput(p, s if count[s] == 1 else f"{s}-{hashlib.sha1(p.encode()).hexdigest()[:8]}")
            for p, s in zip(paths, stems)]
