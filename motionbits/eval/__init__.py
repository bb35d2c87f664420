"""MoRiBo-protocol evaluation: Overlap / Boundary P, R, F1, mIoU with Hungarian matching.

Public names:
    evaluate_frame(pred, gt, ignore=None) -> FrameScores   one final-frame label map pair
    summarize(frames) -> {"macro": ..., "pooled": ...}      aggregate over a dataset
    read_label_map / write_label_map                        16-bit PNG label maps

MoRiBo-format folders (scenes, tracks, ``evaluate_dataset``) are in
:mod:`motionbits.eval.dataset`.
    adjusted_rand_index(a, b)                               agreement of two partitions
"""

from motionbits.eval.agreement import adjusted_rand_index
from motionbits.eval.boundary import boundary_map, boundary_tolerance
from motionbits.eval.labelmaps import read_label_map, write_label_map
from motionbits.eval.matching import hungarian_match
from motionbits.eval.metrics import METRIC_KEYS, FrameScores, evaluate_frame, summarize
from motionbits.eval.overlap import contingency, overlap_scores

__all__ = [
    "adjusted_rand_index",
    "METRIC_KEYS",
    "FrameScores",
    "evaluate_frame",
    "summarize",
    "contingency",
    "overlap_scores",
    "hungarian_match",
    "boundary_map",
    "boundary_tolerance",
    "read_label_map",
    "write_label_map",
]
