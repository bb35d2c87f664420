"""The segmenter's second thread: work that OpenCV or numpy does without the GIL, run
beside the main thread's (the camera's motion while the labels are carried; the residual
of "nothing moved", the static world's memory, the frame's flat regions and what "nothing
moved" costs at each pixel while the twists are fitted and clustered; the memories, the
reported twists' refinement -- a :class:`Task` the main thread runs itself if it needs
the result before the second thread started it -- and the label history's fold while the
masks shown are made).

Where OpenCV may use one thread only (``cv2.setNumThreads(1)``, as each worker of
``motionbits batch`` is set: the pool of processes fills the cores), the work runs inline
instead, in the same order; the results are the same either way.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from functools import partial
from typing import Any

import cv2

__all__ = ["Task", "second_thread"]


class _Inline(Executor):
    """An executor that runs each task at once, in the caller's thread."""

    def submit(self, fn: Callable, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # re-raised by future.result(), as a thread's would be
            future.set_exception(exc)
        return future


def second_thread() -> Executor:
    """One worker thread (started on first use, ended with the executor) where OpenCV may
    use more than one thread; else an executor that runs each task inline."""
    if cv2.getNumThreads() > 1:
        return ThreadPoolExecutor(max_workers=1, thread_name_prefix="motionbits")
    return _Inline()


class Task:
    """``fn(*args)`` handed to an executor whose queue may hold other work first: the
    caller that needs its result before the executor got to it runs it in its own thread
    rather than wait behind that work."""

    def __init__(self, executor: Executor, fn: Callable, /, *args: Any) -> None:
        self._call = partial(fn, *args)
        self._future = executor.submit(self._call)

    def result(self) -> Any:
        """``fn(*args)``: run here if the executor has not started it, else waited for
        (its exception re-raised)."""
        if self._future.cancel():
            self._future = _Inline().submit(self._call)
        return self._future.result()
