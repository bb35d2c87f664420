"""MotionBit identities across frames and the incremental temporal state.

The temporal constraints of the paper need every earlier label map carried to the current
frame. Two nodes were together at every earlier frame iff they fall in the same class of
the *meet* (common refinement) of all earlier label partitions, so one integer map of
that meet, carried by the flow and refined by each new label map, holds all the
information at constant memory.
"""

from __future__ import annotations

from typing import Callable

import cv2
import numpy as np
from scipy import ndimage
from scipy.optimize import linear_sum_assignment

from motionbits.boxes import run_starts

__all__ = ["refine_history", "match_ids", "identify_clusters", "NOVEL_SHARE"]

#: Side (nodes) of the square in which a node counts as interior to its cluster (all of
#: it in one cluster); a new MotionBit needs at least one interior node.
INTERIOR_WINDOW = 3
#: A MotionBit born at the last frame is also confirmed, if it moves, when more than this
#: share of its nodes show something new where they stand (unlike the static world last
#: seen there): a body tumbling in 3D, whose images no 2D motion explains.
NOVEL_SHARE = 0.5


def refine_history(history: np.ndarray, labels: np.ndarray, margin: int = 0) -> np.ndarray:
    """Meet of a history partition with a new label map, compactly renumbered.

    Mask boundaries are uncertain by a few pixels (flow is smooth across motion
    boundaries), and the meet of many maps would turn that uncertainty into a band of
    tiny classes around every body, cutting its edge nodes off for good. So only pixels
    farther than ``margin`` px from a label boundary refine the partition; the others
    take the class of the nearest such interior pixel.

    Args:
        history: (H, W) int class map (0 = background at every earlier frame).
        labels: (H, W) int label map of the new frame (0 = background).
        margin: half-width in px of the uncertain band around label boundaries.

    Returns:
        (H, W) int32 classes; 0 marks pixels background in every map.
    """
    top = int(labels.max()) + 1
    # the pair (history, label) as one integer: int32 where it fits (faster to build and
    # to look up), else int64
    key = history.astype(np.int32 if (int(history.max()) + 1) * top < 1 << 31 else np.int64)
    key *= top
    key += labels
    rows, cols = np.flatnonzero(labels.any(axis=1)), np.flatnonzero(labels.any(axis=0))
    if margin > 0 and len(rows):
        # only the labelled box grown by 2 margin + 1 px can hold non-interior pixels, and
        # its outer ring is interior: the whole-image result, computed on the box
        grow = 2 * margin + 1
        h, w = labels.shape
        box = (slice(max(rows[0] - grow, 0), min(rows[-1] + grow + 1, h)),
               slice(max(cols[0] - grow, 0), min(cols[-1] + grow + 1, w)))
        # morphology on uint16 where the ids fit (twice as fast), else float32 (exact < 2^24)
        lab = labels[box].astype(np.uint16 if labels.max() < 1 << 16 else np.float32)
        square = np.ones((2 * margin + 1, 2 * margin + 1), np.uint8)
        interior = cv2.dilate(lab, square) == cv2.erode(lab, square)
        if interior.any() and not interior.all():
            outside = ~interior
            _, nearest = cv2.distanceTransformWithLabels(
                outside.view(np.uint8), cv2.DIST_L2, 3, labelType=cv2.DIST_LABEL_PIXEL)
            interior_flat = np.flatnonzero(interior.ravel())
            edge = np.flatnonzero(outside.ravel())  # interior pixels are their own nearest
            sub = key[box].ravel()  # a copy: the box is not contiguous in ``key``
            sub[edge] = sub[np.take(interior_flat, nearest.ravel()[edge] - 1)]
            key[box] = sub.reshape(interior.shape)
    # compact renumbering by rank; class 0 stays "background in every map"
    largest = int(key.max())
    if largest < 4 * key.size:  # a table lookup, without np.unique's sort
        # run by run (the pixels come in long runs of one key): the keys present, and
        # each run's rank repeated over it
        flat = key.ravel()
        start = run_starts(flat)
        present = np.zeros(largest + 1, np.int64)
        present[flat[start]] = 1
        rank = (np.cumsum(present) - (1 if present[0] else 0)).astype(np.int32)
        return np.repeat(rank[flat[start]], np.diff(start, append=flat.size)).reshape(key.shape)
    uniq, inv = np.unique(key.ravel(), return_inverse=True)
    inv = inv + (0 if uniq[0] == 0 else 1)
    return inv.reshape(labels.shape).astype(np.int32)


def match_ids(cluster_of_node: np.ndarray, prior_of_node: np.ndarray, n_clusters: int,
              min_iou: float) -> dict[int, int]:
    """Give clusters the ids of the earlier MotionBits they overlap most (Hungarian on IoU).

    Args:
        cluster_of_node: (n,) cluster index 1..K per node (0 = none).
        prior_of_node: (n,) earlier MotionBit id per node (0 = none), carried to this frame.
        n_clusters: K.
        min_iou: a match needs at least this node-level IoU.

    Returns:
        cluster index -> earlier id, for the matched clusters only.
    """
    old_ids = np.unique(prior_of_node[prior_of_node > 0])
    if n_clusters == 0 or len(old_ids) == 0:
        return {}
    old_index = np.searchsorted(old_ids, prior_of_node)
    old_index = np.where(prior_of_node > 0, old_index + 1, 0)
    table = np.zeros((n_clusters + 1, len(old_ids) + 1), np.int64)
    np.add.at(table, (cluster_of_node, old_index), 1)
    inter = table[1:, 1:].astype(np.float64)
    size_c = table[1:, :].sum(1, keepdims=True)
    size_o = table[:, 1:].sum(0, keepdims=True)
    iou = inter / np.maximum(size_c + size_o - inter, 1)
    rows, cols = linear_sum_assignment(-iou)
    return {int(r) + 1: int(old_ids[c]) for r, c in zip(rows, cols) if iou[r, c] >= min_iou}


def identify_clusters(node_cluster: np.ndarray, displacement: np.ndarray,
                      prior_nodes: np.ndarray, evidence: Callable[[], np.ndarray],
                      shape: tuple[int, int], next_id: int, tentative: set[int], *,
                      min_nodes: int, match_iou: float, move_threshold: float,
                      motion_evidence: float, novel: Callable[[], np.ndarray] | None = None
                      ) -> tuple[np.ndarray, np.ndarray, set[int], int]:
    """Drop noise clusters and give each cluster a stable MotionBit id.

    A cluster continues the earlier MotionBit it overlaps most (:func:`match_ids`); a
    cluster that continues none is a new MotionBit only if it moves now (eq. 4), which
    keeps static leftovers of a body's old place from becoming bodies of their own -- and
    only if its flow explains its images better than "static" (``evidence()``, grey
    levels per node, averaged over the cluster), which keeps textureless regions with
    flow smeared in from a moving neighbour from becoming bodies. A MotionBit born at the
    last frame (``tentative``) stands only if it visibly moves again now -- its flow
    explains its images, or (``novel``) most of it shows something new where it stands: a
    block tumbling as it is pushed changes its look, and no 2D motion explains it.

    Args:
        node_cluster: (n,) int cluster index of each node (0 = none).
        displacement: (n,) float px each node's local motion moves it.
        prior_nodes: (n,) int earlier MotionBit id of each node, carried (0 = none).
        evidence: called at most once, when some cluster needs it: (n,) float grey levels
            by which the flow explains each node's neighbourhood better than "static".
        shape: (rows, cols) of the node grid.
        next_id: the id the next new MotionBit gets.
        tentative: ids born at the last frame, not yet confirmed.
        min_nodes: clusters with fewer nodes are noise.
        match_iou, move_threshold, motion_evidence: the config's values.
        novel: None, or called at most once: (n,) bool, nodes that look unlike the static
            world last seen standing still there (:meth:`StaticMemory.changed`).

    Returns:
        node_ids (n,) int64 MotionBit id of each node (0 = none); ids (K,) int64 the ids
        present, in cluster order; the ids born now (the next ``tentative``); the next
        ``next_id``.
    """
    counts = np.bincount(node_cluster, minlength=1)
    big = np.flatnonzero(counts >= min_nodes)
    big = big[big > 0]
    remap = np.zeros(len(counts), np.int64)
    remap[big] = np.arange(1, len(big) + 1)
    cluster = remap[node_cluster]
    matched = match_ids(cluster, prior_nodes, len(big), match_iou)
    grid = cluster.reshape(shape)
    # a node is interior iff its neighbourhood holds one cluster value only
    interior = (ndimage.maximum_filter(grid, INTERIOR_WINDOW, mode="nearest")
                == ndimage.minimum_filter(grid, INTERIOR_WINDOW, mode="nearest")).ravel()
    has_interior = np.bincount(cluster[interior], minlength=len(big) + 1) > 0
    ids = []
    newborn = set()
    for c in range(1, len(big) + 1):
        sel = cluster == c
        moves = np.median(displacement[sel]) > move_threshold
        if c in matched:
            i = matched[c]
            ids.append(i if i not in tentative or (moves and (
                np.mean(evidence()[sel]) > motion_evidence
                or (novel is not None and np.mean(novel()[sel]) > NOVEL_SHARE))) else 0)
        elif has_interior[c] and moves and np.mean(evidence()[sel]) > motion_evidence:
            ids.append(next_id)
            newborn.add(next_id)
            next_id += 1
        else:
            ids.append(0)
    ids = np.asarray(ids, np.int64)
    node_ids = np.concatenate([[0], ids])[cluster]
    return node_ids, ids[ids > 0], newborn, next_id
