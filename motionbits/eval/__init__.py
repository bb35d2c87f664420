"""MoRiBo-protocol evaluation: Overlap / Boundary P, R, F1, mIoU with Hungarian matching,
static FP and spurious predictions.

Public names:
    evaluate_frame(pred, gt, ignore=None) -> FrameScores   one final-frame label map pair
    summarize(frames) -> {"macro", "pooled", "false_positives"}   aggregate over a dataset
    read_label_map / write_label_map                        16-bit PNG label maps

MoRiBo-format folders (scenes, tracks, ``evaluate_dataset``) are in
:mod:`motionbits.eval.dataset`.
    adjusted_rand_index(a, b)                               agreement of two partitions
    scenes_from_sequence(src, out)                          DAVIS-style sequence -> scenes
    body_kinds(scene) / iou_by_kind(per_scene, kinds)       mean IoU per kind of body
    body_roles(scene)                                       agent, carried, knocked, pushed...
    loss_budget(per_scene)                                  100 - mIoU by how each mark fails
    compare_runs(a, b) / format_comparison(result)         two runs on the same scenes
    scene_changes(a, b) / format_scene_changes(rows)        ... which scenes moved, how
"""

from motionbits.eval.agreement import adjusted_rand_index
from motionbits.eval.boundary import boundary_counts, boundary_map, boundary_tolerance
from motionbits.eval.compare import (compare_runs, format_comparison, format_scene_changes,
                                     scene_changes)
from motionbits.eval.kinds import body_kinds, body_roles, iou_by_kind
from motionbits.eval.labelmaps import read_label_map, write_label_map
from motionbits.eval.losses import loss_budget
from motionbits.eval.matching import hungarian_match
from motionbits.eval.metrics import FP_KEYS, METRIC_KEYS, FrameScores, evaluate_frame, summarize
from motionbits.eval.overlap import contingency, overlap_scores
from motionbits.eval.sequences import scenes_from_sequence

__all__ = [
    "adjusted_rand_index",
    "METRIC_KEYS",
    "FP_KEYS",
    "FrameScores",
    "evaluate_frame",
    "summarize",
    "contingency",
    "overlap_scores",
    "hungarian_match",
    "boundary_map",
    "boundary_counts",
    "boundary_tolerance",
    "read_label_map",
    "write_label_map",
    "scenes_from_sequence",
    "body_kinds",
    "iou_by_kind",
    "body_roles",
    "loss_budget",
    "compare_runs",
    "format_comparison",
    "scene_changes",
    "format_scene_changes",
]
