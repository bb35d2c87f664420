"""Output folders that are never half-written or stale.

A command writes into a fresh temporary folder next to the destination and renames it into
place only when everything succeeded; on any error the temporary folder is removed and the
destination is left as it was. An existing, non-empty destination is refused unless the
caller allows replacing it, and then it is replaced whole, never mixed with the new run.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from fnmatch import fnmatch
from pathlib import Path
from types import TracebackType

from motionbits.errors import InputError

__all__ = ["StagedFolder", "check_named", "check_output_file", "write_text_atomic"]


class StagedFolder:
    """Context manager: write into ``.path`` (a temporary sibling of ``dest``), then
    :meth:`publish` to rename it to ``dest``. Leaving the block without publishing (an
    error) deletes everything it created.

    Args:
        dest: the output folder.
        overwrite: replace a non-empty ``dest``; without it such a ``dest`` is refused.
        option: how the destination is named in error messages (e.g. ``"--out"``).
        replaceable: if given, ``overwrite`` replaces only a folder whose entries all
            match these names or glob patterns (a previous output of the same command), so that a mistyped
            ``--out`` never deletes unrelated files.

    Raises (on construction, before anything is written):
        InputError: ``dest`` is a file, non-empty without ``overwrite``, holds unrelated
            files, or its parent folder cannot be written.
    """

    def __init__(self, dest: str | os.PathLike, *, overwrite: bool = False, option: str = "--out",
                 replaceable: set[str] | None = None) -> None:
        self.dest = Path(dest)
        self.option = option
        check_named(dest, option, "folder")
        here = Path.cwd().resolve()
        if self.dest.name in ("", "..") or self.dest.resolve() in (here, *here.parents):
            # ".", "..", "/", the current folder by its path: no sibling to stage in
            raise InputError(f"{option} {self.dest} is the current folder, one above it or the "
                             f"root; name a folder of its own, e.g. {option} out")
        if self.dest.exists() and not self.dest.is_dir():
            raise InputError(f"{option} {self.dest} is a file, not a folder")
        if self.dest.is_dir():
            entries = sorted(p.name for p in self.dest.iterdir())
            if entries and not overwrite:
                raise InputError(
                    f"{option} {self.dest} already holds files ({_names(entries)}); pass "
                    "--overwrite to replace it, or choose another folder")
            alien = [e for e in entries if replaceable is not None
                     and not any(fnmatch(e, pattern) for pattern in replaceable)]
            if alien:
                raise InputError(
                    f"{option} {self.dest} holds files that this command did not write "
                    f"({_names(alien)}); --overwrite replaces only an earlier output: choose "
                    "another folder")
        self._made_parents = _missing_parents(self.dest)
        try:
            self.dest.parent.mkdir(parents=True, exist_ok=True)
            self.path = Path(tempfile.mkdtemp(prefix=f".{self.dest.name}.partial-",
                                              dir=self.dest.parent))
        except OSError as exc:
            self._remove_parents()
            raise InputError(f"cannot write {option} {self.dest}: "
                             f"{exc.strerror or exc}") from exc
        self.published = False

    def __enter__(self) -> "StagedFolder":
        return self

    def __exit__(self, kind: type | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if not self.published:
            shutil.rmtree(self.path, ignore_errors=True)
            self._remove_parents()

    def publish(self, inner: str | None = None) -> Path:
        """Move the finished folder (or its subfolder ``inner``) to ``dest``, replacing an
        old one whole; returns ``dest``."""
        old = None
        if self.dest.exists():
            old = self.dest.parent / f"{self.path.name}.old"
            self.dest.rename(old)
        (self.path if inner is None else self.path / inner).rename(self.dest)
        self.published = True
        if inner is not None:
            shutil.rmtree(self.path, ignore_errors=True)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.dest

    def _remove_parents(self) -> None:
        for p in self._made_parents:  # deepest first; only the ones we made, if still empty
            try:
                p.rmdir()
            except OSError:
                break


def _missing_parents(dest: Path) -> list[Path]:
    out = []
    p = dest.absolute().parent
    while not p.exists():
        out.append(p)
        p = p.parent
    return out


def _names(entries: list[str], limit: int = 3) -> str:
    more = f", ... {len(entries) - limit} more" if len(entries) > limit else ""
    return ", ".join(entries[:limit]) + more


def check_named(path: str | os.PathLike, option: str, what: str) -> None:
    """Raise InputError if ``path`` is empty or blank (``Path("")`` is the current
    folder): ``what`` is "folder" or "file", for the message."""
    if not os.fspath(path).strip():
        raise InputError(f"{option} is empty; name the {what} to write")


def check_output_file(path: str | os.PathLike, option: str) -> Path:
    """Fail early (before any work) if the file ``path`` could not be written later."""
    check_named(path, option, "file")
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{option} {path} is a folder, not a file")
    parent = path.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK):
        raise InputError(f"cannot write {option} {path}: {parent} is not a writable folder")
    return path


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to a temporary file next to ``path``, then rename it to ``path``:
    readers never see a half-written file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.partial-", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
