"""A shared thread pool for the independent pieces of one frame's work.

A stream is segmented one frame at a time, but some steps hold several independent
pieces (one ECC alignment per moving MotionBit, one MCL per connected component). Their
heavy calls (OpenCV, BLAS, numpy's array loops) release the GIL, so on a machine with a
free core they overlap; results do not depend on it (each piece is computed alone and
the results are kept in order).
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, Sequence, TypeVar

__all__ = ["thread_map", "split_work", "MAX_WORKERS"]

#: Threads of the shared pool (one per core, at most 4: the pieces are few).
MAX_WORKERS = max(1, min(4, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                         else os.cpu_count() or 1))

T = TypeVar("T")
R = TypeVar("R")
_lock = threading.Lock()
_pool: tuple[int, ThreadPoolExecutor] | None = None  # (pid that made it, pool)


def _shared_pool() -> ThreadPoolExecutor:
    global _pool
    with _lock:
        if _pool is None or _pool[0] != os.getpid():  # a forked child makes its own
            _pool = (os.getpid(), ThreadPoolExecutor(MAX_WORKERS, "motionbits"))
        return _pool[1]


def thread_map(fn: Callable[[T], R], items: Sequence[T]) -> list[R]:
    """``[fn(x) for x in items]``, the calls spread over the shared pool (inline when there
    is one item or one core)."""
    if len(items) < 2 or MAX_WORKERS < 2:
        return [fn(x) for x in items]
    return list(_shared_pool().map(fn, items))


def split_work(costs: Sequence[float], parts: int = MAX_WORKERS) -> list[list[int]]:
    """Indices of ``costs`` in at most ``parts`` groups of similar total cost (largest
    first, each to the lightest group); empty groups are dropped, each group keeps its
    indices in increasing order."""
    groups: list[list[int]] = [[] for _ in range(max(1, parts))]
    load = [0.0] * len(groups)
    for i in sorted(range(len(costs)), key=lambda i: -costs[i]):
        g = load.index(min(load))
        groups[g].append(i)
        load[g] += costs[i]
    return [sorted(g) for g in groups if g]
