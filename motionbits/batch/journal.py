"""``batch.jsonl``: one JSON line per finished video, appended only by the batch's parent.

A video is done once its line is on disk (written in one ``write`` and ``fsync``ed). A
line torn by a crash (no final newline, or not JSON) is cut off when the journal is
opened again; a later line for the same input supersedes an earlier one.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["Journal", "RECORD_FIELDS"]

#: Keys of every record, in this order.
RECORD_FIELDS = ("input", "output", "status", "frames", "seconds", "error")


class Journal:
    """The records of a batch folder.

    Args:
        path: the ``batch.jsonl`` file (created if missing).

    Attributes:
        records: input path -> its latest record.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.records: dict[str, dict] = {}
        self.torn = 0  # bytes of a torn last line cut off when opening
        if self.path.exists():
            self._load()

    def _load(self) -> None:
        data = self.path.read_bytes()
        end = data.rfind(b"\n") + 1  # everything after the last newline is a torn write
        for line in data[:end].splitlines():
            try:
                rec = json.loads(line)
                self.records[rec["input"]] = rec
            except (ValueError, KeyError, TypeError):
                raise ValueError(f"{self.path} is not a MotionBits batch journal: bad line "
                                 f"{line[:80]!r}") from None
        if end < len(data):
            self.torn = len(data) - end
            with open(self.path, "r+b") as f:
                f.truncate(end)

    def append(self, record: dict) -> None:
        """Write one record durably (one line, flushed and fsynced)."""
        rec = {k: record.get(k) for k in RECORD_FIELDS}
        line = (json.dumps(rec) + "\n").encode()
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, line)
            os.fsync(fd)
        finally:
            os.close(fd)
        self.records[rec["input"]] = rec

    def status(self, path: str) -> str | None:
        """Status of an input path: "done", "failed", or ``None`` if never finished."""
        rec = self.records.get(path)
        return None if rec is None else rec["status"]
