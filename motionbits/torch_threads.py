"""A torch CPU thread count for one block of code (the learned options' model calls).

`MotionBitsSegmenter.update` runs on one BLAS/OpenMP thread (its matrix products are small
and extra threads only spin on a busy CPU). The learned models (RAFT flow, SAM2 refinement)
run inside that limit too unless given their own count, for which this sets
``torch.set_num_threads`` and restores the caller's count afterwards.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator

__all__ = ["torch_threads", "check_threads"]


def check_threads(threads: int | None, what: str) -> int | None:
    """`threads` as an int >= 1, or None (keep the caller's count)."""
    if threads is not None and int(threads) < 1:
        raise ValueError(f"{what} threads must be >= 1 or None, got {threads}")
    return None if threads is None else int(threads)


@contextmanager
def torch_threads(threads: int | None) -> Iterator[None]:
    """Run the block with ``torch.set_num_threads(threads)``; None leaves the count as it is."""
    import torch

    outer = torch.get_num_threads()
    torch.set_num_threads(threads or outer)
    try:
        yield
    finally:
        torch.set_num_threads(outer)
