"""``--engine ray``: one Ray task per video, on a local Ray instance or an existing cluster.

Needs the ``ray`` extra (``pip install motionbits[ray]``). On a cluster every node must
have motionbits installed and see the batch folder at the same path (a shared file
system): the workers write the outputs, this process writes ``batch.jsonl``.
"""

from __future__ import annotations

from typing import Callable, Iterable

from motionbits.batch.inputs import BatchInput
from motionbits.batch.job import segment_job

__all__ = ["import_ray", "run_ray", "segment_video_task", "TASK_RETRIES"]

#: Times Ray runs a video again when its worker process dies (killed, out of memory, a
#: node lost); then it is recorded as failed.
TASK_RETRIES = 2


def import_ray():
    """The ``ray`` module; ImportError naming the extra if it is not installed (the
    ``batch`` command calls it before it writes anything)."""
    try:
        import ray
    except ImportError:
        raise ImportError("--engine ray needs Ray: pip install 'motionbits[ray]'") from None
    return ray


def segment_video_task(item: BatchInput, out_dir: str, options: dict, progress) -> dict:
    import cv2
    from threadpoolctl import threadpool_limits

    cv2.setNumThreads(1)  # the task holds one CPU
    with threadpool_limits(1):
        # fire and forget: a task blocked in ray.get would lend its CPU to another task
        return segment_job(item.path, item.name, out_dir, options,
                           report=lambda *msg: progress.put.remote(msg))


class _Progress:
    """Actor collecting (name, frames done, frames in total) from the tasks."""

    def __init__(self):
        self.items: list[tuple] = []

    def put(self, msg: tuple) -> None:
        self.items.append(msg)

    def take(self) -> list[tuple]:
        items, self.items = self.items, []
        return items


def run_ray(items: Iterable[BatchInput], out_dir: str, options: dict, *, address: str | None,
            workers: int | None, on_record: Callable[[dict], None],
            on_progress: Callable[[str, int, "int | None"], None]) -> None:
    """Segment ``items`` as Ray tasks (one CPU each), calling ``on_record`` in this process
    for each finished video and ``on_progress(name, done, total)`` per frame.

    Args:
        address: an existing cluster (``ray://host:10001`` or ``host:6379``, or "auto");
            ``None`` starts a local Ray instance for this batch.
        workers: CPUs of the local instance (default: all); ignored with ``address``.
    """
    ray = import_ray()
    started = not ray.is_initialized()
    if started:
        kwargs = {"address": address} if address else {"num_cpus": workers}
        ray.init(include_dashboard=False, log_to_driver=False, **kwargs)
    try:
        progress = ray.remote(num_cpus=0)(_Progress).remote()
        task = ray.remote(num_cpus=1, max_retries=TASK_RETRIES)(segment_video_task)
        refs = {task.remote(item, out_dir, options, progress): item for item in items}

        def drain() -> None:
            for msg in ray.get(progress.take.remote()):
                on_progress(*msg)

        while refs:
            done, _ = ray.wait(list(refs), num_returns=1, timeout=0.25)
            drain()
            for ref in done:
                item = refs.pop(ref)
                try:
                    record = ray.get(ref)
                except ray.exceptions.RayError as exc:  # the worker died on every try
                    record = {"input": item.path, "output": None, "status": "failed",
                              "frames": None, "seconds": None,
                              "error": f"{type(exc).__name__}: {str(exc).splitlines()[0]}"}
                on_record(record)
        drain()
    finally:
        if started:
            ray.shutdown()
