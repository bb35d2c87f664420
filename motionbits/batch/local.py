"""``--engine local``: a pool of worker processes on this machine, one BLAS thread each."""

from __future__ import annotations

import multiprocessing as mp
import os
import queue
import signal
from collections import deque
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Iterable

from motionbits.batch.inputs import BatchInput
from motionbits.batch.job import segment_job

__all__ = ["run_local", "default_workers"]

_progress_queue = None  # set in each worker by _init_worker


def _die_with_parent() -> None:
    """Linux: the kernel kills this worker when the batch process dies (even by kill -9),
    so that no orphan keeps writing into the batch folder."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def _init_worker(progress_queue) -> None:
    global _progress_queue
    _progress_queue = progress_queue
    # progress is best effort: a worker never waits at exit for its queue's feeder thread,
    # which blocks for good on the queue's lock if another worker was killed holding it
    progress_queue.cancel_join_thread()
    _die_with_parent()
    # Ctrl-C reaches the whole process group: a worker stops at once, without a traceback,
    # and the batch process reports the interruption (the video is redone on resume)
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, lambda *_: os._exit(130))
    import cv2
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)  # one BLAS / OpenMP thread per worker: the pool fills the cores
    cv2.setNumThreads(1)


def _report(name: str, done: int, total: int | None) -> None:
    _progress_queue.put((name, done, total))


def _job(item: BatchInput, out_dir: str, options: dict) -> dict:
    return segment_job(item.path, item.name, out_dir, options, report=_report)


def run_local(items: Iterable[BatchInput], out_dir: str, options: dict, *, workers: int,
              on_record: Callable[[dict], None],
              on_progress: Callable[[str, int, "int | None"], None]) -> None:
    """Segment ``items`` with ``workers`` processes, calling ``on_record`` in this process
    for each finished video (as they finish) and ``on_progress(name, done, total)`` per frame.

    A worker that dies (killed, out of memory, a crash in a decoder) breaks the pool: the
    videos it was running with are run again one at a time in a fresh process, and one
    whose process dies again there is recorded as failed. Each pool has a progress queue
    of its own: a worker killed while writing to one leaves its lock held for good.
    """
    ctx = mp.get_context("spawn")
    progress = ctx.Queue()
    pending = deque(items)
    suspects: deque[BatchInput] = deque()

    def drain() -> None:
        while True:
            try:
                on_progress(*progress.get_nowait())
            except queue.Empty:
                return

    def pool(n: int) -> ProcessPoolExecutor:
        nonlocal progress
        drain()
        progress.close()
        progress = ctx.Queue()
        return ProcessPoolExecutor(n, mp_context=ctx, initializer=_init_worker,
                                   initargs=(progress,))

    while pending or suspects:
        alone = bool(suspects)  # after a crash: the suspects, one at a time
        source = suspects if alone else pending
        size = 1 if alone else workers
        with pool(size) as ex:
            running = {}
            try:
                while source or running:
                    while source and len(running) < size:
                        item = source.popleft()
                        try:
                            running[ex.submit(_job, item, out_dir, options)] = item
                        except BrokenProcessPool:
                            source.appendleft(item)
                            raise
                    done, _ = wait(running, timeout=0.25, return_when=FIRST_COMPLETED)
                    drain()
                    broken = False
                    for fut in done:
                        if isinstance(fut.exception(), BrokenProcessPool):
                            broken = True
                        else:
                            running.pop(fut)
                            on_record(fut.result())
                    if broken:
                        raise BrokenProcessPool
            except BrokenProcessPool:
                drain()
                for item in running.values():
                    if alone:
                        on_record({"input": item.path, "output": None, "status": "failed",
                                   "frames": None, "seconds": None,
                                   "error": "the worker process died twice on this video "
                                            "(killed, out of memory or a crash)"})
                    else:
                        suspects.append(item)
    drain()
    progress.close()


def default_workers() -> int:
    """Worker processes by default: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)
