"""The segmenter's second thread: work that OpenCV or numpy does without the GIL, run
beside the main thread's (the camera's motion while the labels are carried, the memories
while the masks shown are made).

Where OpenCV may use one thread only (``cv2.setNumThreads(1)``, as each worker of
``motionbits batch`` is set: the pool of processes fills the cores), the work runs inline
instead, in the same order; the results are the same either way.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor, Future, ThreadPoolExecutor

import cv2

__all__ = ["second_thread"]


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
