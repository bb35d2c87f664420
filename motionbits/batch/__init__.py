"""Many videos: a resumable batch on a process pool or Ray (``motionbits batch``).

Example:
    >>> from motionbits.batch import expand_inputs, run_batch          # doctest: +SKIP
    >>> report = run_batch(expand_inputs(["clips/*.mp4"]), "out", {"window": 30})  # doctest: +SKIP
"""

from motionbits.batch.inputs import BatchInput, expand_inputs
from motionbits.batch.job import PARTIAL_DIR, segment_job
from motionbits.batch.journal import Journal
from motionbits.batch.runner import ENGINES, JOURNAL_NAME, BatchReport, run_batch

__all__ = [
    "BatchInput",
    "BatchReport",
    "ENGINES",
    "JOURNAL_NAME",
    "Journal",
    "PARTIAL_DIR",
    "expand_inputs",
    "run_batch",
    "segment_job",
]
