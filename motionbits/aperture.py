"""Flat links that move along themselves: the aperture problem in the shown masks (ours).

A long flat-coloured part of a body that moves along its own length -- a robot's arm
entering the view from the border -- shows no motion of its own: its edges run along the
motion and its inside has no texture, so "nothing moved" explains it as well as the body's
motion does, no MotionBit is born there and the pixel masks leave it to the background.
A shown MotionBit is therefore extended over a flat image region (colour gradient under
``FLAT_GRADIENT``) that

- touches the MotionBit's mask and reaches the image border (a link entering the view: a
  flat region inside the view is closed by edges across the motion, which the motion
  moves, and a table or wall around a body is mostly static);
- covers less than ``GROUND_SHARE`` of the image (a larger one reaching the border is the
  ground or a wall, which smeared flow next to a fast body can move with it);
- moves by the flow (more than ``move_threshold``) over ``MOVING_SHARE`` of its area;
- shows no visible change (``STILL_LEVELS``), yet the MotionBit's motion explains it and a
  band around it (its own edges) better than "nothing moved" by ``GAIN`` grey levels.

Once joined it stays joined -- also when the body stops -- while it touches the MotionBit
and the motion explains it no worse than "nothing moved" by ``KEEP_TOLERANCE``. A join is
remembered under the group of the MotionBit that made it (:func:`carried_joins`): a
newborn piece of an arm that joined its flat link is often merged into the arm's first
MotionBit a frame later, and the link must stay with the arm. Only the
masks shown are extended: the segmenter's state keeps the motion's masks (a joined region
fed back into the clustering came back as a MotionBit of its own and split the body).
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from motionbits.boxes import label_boxes, run_counts
from motionbits.evidence import photometric_residual
from motionbits.twists import rigid_matrix

__all__ = ["FlatLinks", "flat_link_candidates", "flat_regions", "half_colour_gradient",
           "join_flat_links", "carried_joins",
           "reaches_border", "ground_regions", "FLAT_GRADIENT", "MOVING_SHARE",
           "STILL_LEVELS", "GAIN", "KEEP_TOLERANCE", "GROUND_SHARE"]

#: grey levels per px: a pixel whose colour gradient (largest over R, G, B) is below this
#: is flat.
FLAT_GRADIENT = 6.0
#: share of a flat region whose flow must move for it to join a MotionBit ...
MOVING_SHARE = 0.7
#: ... grey levels (3x3 mean, over the region and its band): "nothing moved" misses it by
#: less than this (no visible change) ...
STILL_LEVELS = 4.0
#: ... and the MotionBit's motion explains it better than "nothing moved" by this much.
GAIN = 0.5
#: grey levels: a region joined at the last frame stays while the motion explains it no
#: worse than "nothing moved" by this much.
KEEP_TOLERANCE = 1.0
#: px: the band around a region whose edges the motion must explain too ...
BAND = 3
#: ... and the reach within which a region touches a mask and takes the edge pixels
#: around it (2 px of the half-resolution regions).
REACH = 4
#: A region joined at the last frame is the same region if it holds this share of it.
KEPT_SHARE = 0.5
#: A flat region that reaches the image border and covers at least this share of the
#: image is the ground or a wall (a plain white table), not a link: it never joins a
#: MotionBit, and a mask that covers little of it loses its pixels there
#: (:func:`motionbits.masks.trim_flat_background`). Fast motion smears the flow over a
#: third of such a table (``02_cups.mp4``, 16 frames: the table's pixels under a mark
#: 6.3% -> 0.5% on average, 38% -> 0.6% at the worst frame; round 32). The links joined
#: on 80 generated robot and hand scenes cover at most 5% of the image (round 44).
GROUND_SHARE = 0.1


def reaches_border(stats: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(R,) bool: which regions of :func:`flat_regions`' ``stats`` ((R, 5) int32, OpenCV's
    component stats) reach the border of an image of ``shape`` (H, W)."""
    x, y, w, h = (stats[:, i] for i in range(4))
    return (x == 0) | (y == 0) | (x + w >= shape[1]) | (y + h >= shape[0])


def ground_regions(stats: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(R,) bool: which regions of :func:`flat_regions`' ``stats`` are the ground or a
    wall -- they reach the border of the (H, W) image and cover ``GROUND_SHARE`` of it."""
    return reaches_border(stats, shape) & (stats[:, cv2.CC_STAT_AREA]
                                           >= GROUND_SHARE * shape[0] * shape[1])


def half_colour_gradient(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 frame -> ((H + 1) // 2, (W + 1) // 2) float32 colour gradient at half
    resolution: the 3x3 Sobel magnitude of the lightly smoothed half-size frame, the
    largest over R, G, B (what :func:`flat_regions` thresholds)."""
    h, w = rgb.shape[:2]
    half = cv2.resize(rgb, ((w + 1) // 2, (h + 1) // 2), interpolation=cv2.INTER_AREA)
    smooth = cv2.GaussianBlur(half, (0, 0), 0.5).astype(np.float32)
    gx = cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3)
    grad = cv2.magnitude(gx, gy)
    # the largest over R, G, B (cv2.max: numpy's max along the last axis is 20x slower)
    return cv2.max(cv2.max(grad[..., 0], grad[..., 1]), grad[..., 2])


def flat_regions(rgb: np.ndarray, max_gradient: float = FLAT_GRADIENT,
                 half_gradient: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Connected regions of flat colour, found at half resolution (4x cheaper; a link is
    wider than a few px).

    Args:
        rgb: (H, W, 3) uint8 frame.
        max_gradient: grey levels per px (largest over R, G, B) under which a pixel is flat.
        half_gradient: ``half_colour_gradient(rgb)`` if already computed.

    Returns:
        (flat, regions, stats): (H, W) bool flat pixels, (H, W) int32 region of each pixel
        (0 = not flat) and the (n, 5) ``cv2.connectedComponentsWithStats`` stats (x, y,
        width, height, area) of each region, in full-resolution px (row 0: the pixels that
        are not flat).
    """
    h, w = rgb.shape[:2]
    grad = half_colour_gradient(rgb) if half_gradient is None else half_gradient
    # a 3x3 Sobel reads 8x the grey levels per px of a ramp; one px here is two of the frame
    flat = grad < 8 * 2 * max_gradient
    _, regions, stats = cv2.connectedComponentsWithStats(flat.astype(np.uint8),
                                                         connectivity=4)[:3]
    regions = cv2.resize(regions, (w, h), interpolation=cv2.INTER_NEAREST)
    stats = stats * np.array([2, 2, 2, 2, 4])
    stats[:, 2] = np.minimum(stats[:, 0] + stats[:, 2], w) - stats[:, 0]
    stats[:, 3] = np.minimum(stats[:, 1] + stats[:, 3], h) - stats[:, 1]
    return regions > 0, regions, stats


class FlatLinks(NamedTuple):
    """The flat regions next to MotionBits that :func:`join_flat_links` tests
    (:func:`flat_link_candidates`)."""

    #: (H, W) bool flat pixels and (H, W) int32 flat region of each pixel (0 = not flat)
    flat: np.ndarray
    regions: np.ndarray
    #: (n, 5) ``cv2.connectedComponentsWithStats`` stats of each region (full-resolution px)
    stats: np.ndarray
    #: (MotionBit index into ``ids``, region, joined at the last frame) of each test
    pairs: list[tuple[int, int, bool]]


def flat_link_candidates(labels: np.ndarray, ids: np.ndarray, rgb: np.ndarray,
                         speed: np.ndarray, joined: np.ndarray, *, move_threshold: float,
                         min_area: int,
                         flat_look: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
                         ) -> FlatLinks | None:
    """The flat regions that may join a MotionBit: those touching its mask that moved with
    it and reach the border, or that it joined at the last frame (no motion needed).

    Args:
        labels: (H, W) int32 label map (0 = background).
        ids: (K,) ids with a cluster now.
        rgb: (H, W, 3) uint8 current frame.
        speed: (H, W) float32 length of the backward flow relative to the camera.
        joined: (H, W) int32 pixels joined at the last frame, carried to this one, under
            their group's id (:func:`carried_joins`): a region stays joined to that id.
        move_threshold: px; a pixel's flow moves above this.
        min_area: px; smaller regions never join.
        flat_look: ``flat_regions(rgb)`` if already computed.

    Returns:
        The regions and the (MotionBit, region) pairs to test, or None where there is none.
    """
    if not len(ids):
        return None
    flat, regions, stats = flat_regions(rgb) if flat_look is None else flat_look
    n = len(stats)
    area = np.maximum(stats[:, cv2.CC_STAT_AREA], 1).astype(np.float64)
    moving = speed > move_threshold
    moving_share = run_counts(regions[moving], n) / area
    free = run_counts(regions[labels == 0], n) / area >= 0.5
    border = reaches_border(stats, labels.shape)
    # the ground or a wall is no link
    eligible = (area >= min_area) & free & ~ground_regions(stats, labels.shape)
    eligible[0] = False  # not a region: the pixels that are not flat
    new = eligible & border & (moving_share >= MOVING_SHARE)
    was = joined > 0
    if not (new.any() or (was.any() and eligible.any())):
        return None
    h, w = labels.shape
    reach = np.ones((2 * REACH + 1, 2 * REACH + 1), np.uint8)
    boxes = label_boxes(labels)
    was_id, was_region = joined[was], regions[was]  # pixels joined at the last frame
    pairs = []
    for k, lab in enumerate(ids.tolist()):
        if lab > len(boxes) or boxes[lab - 1] is None:
            continue
        rows, cols = boxes[lab - 1]  # the mask's box, grown by the reach
        near_box = (slice(max(rows.start - REACH, 0), min(rows.stop + REACH, h)),
                    slice(max(cols.start - REACH, 0), min(cols.stop + REACH, w)))
        mask = (labels[near_box] == lab).astype(np.uint8)
        near = np.unique(regions[near_box][(cv2.dilate(mask, reach) > 0) & (mask == 0)])
        kept = np.bincount(was_region[was_id == lab], minlength=n) / area >= KEPT_SHARE
        pairs += [(k, int(c), bool(kept[c]))
                  for c in near[np.where(kept[near], eligible[near], new[near])]]
    return FlatLinks(flat, regions, stats, pairs) if pairs else None


def join_flat_links(labels: np.ndarray, links: FlatLinks | None, ids: np.ndarray,
                    thetas: np.ndarray, trans: np.ndarray, cur_gray: np.ndarray,
                    prev_gray: np.ndarray, still: np.ndarray) -> np.ndarray:
    """The label map with the candidate flat ``links`` (:func:`flat_link_candidates`)
    that the MotionBit's motion explains joined to it.

    Args:
        labels: (H, W) int32 label map (0 = background).
        links: the candidates (None: nothing to join).
        ids: (K,) ids with a cluster now, backward motions ``thetas`` (K,), ``trans``
            (K, 2) (current -> previous, relative to the camera).
        cur_gray, prev_gray: (H, W) float32 grey frames (``prev_gray`` camera-stabilised).
        still: (H, W) float32 grey levels by which "nothing moved" misses each pixel.

    Returns:
        (H, W) int32 label map: ``labels`` plus the joined regions (only background
        pixels change; ``labels`` itself where none joins).
    """
    if links is None:
        return labels
    h, w = labels.shape
    x, y, bw, bh = (links.stats[:, i] for i in range(4))  # each region's box
    band_kernel = np.ones((2 * BAND + 1, 2 * BAND + 1), np.uint8)
    reach = np.ones((2 * REACH + 1, 2 * REACH + 1), np.uint8)
    static = cv2.blur(still, (3, 3))
    out = labels.copy()
    for k, c, kept in links.pairs:
        box = (slice(max(y[c] - BAND, 0), min(y[c] + bh[c] + BAND, h)),
               slice(max(x[c] - BAND, 0), min(x[c] + bw[c] + BAND, w)))
        region = links.regions[box] == c
        band = cv2.dilate(region.astype(np.uint8), band_kernel) > 0
        moved = photometric_residual(cur_gray, prev_gray, rigid_matrix(thetas[k], trans[k]),
                                     box)[band].mean()
        nothing = static[box][band].mean()
        if (moved <= nothing + KEEP_TOLERANCE if kept
                else nothing < STILL_LEVELS and moved <= nothing - GAIN):
            grown = cv2.dilate(region.astype(np.uint8), reach) > 0  # with its edge pixels
            sub = out[box]
            sub[grown & (sub == 0) & (region | ~links.flat[box])] = ids[k]
    return out


def carried_joins(with_links: np.ndarray, labels: np.ndarray, group_of: dict[int, int]
                  ) -> np.ndarray:
    """The pixels :func:`join_flat_links` added, each under the group of the MotionBit
    that joined it, to be carried to the next frame as its ``joined``.

    Args:
        with_links: (H, W) int32 label map with the joined regions.
        labels: (H, W) int32 label map before the join.
        group_of: each present id -> its group's representative id (ids not in it keep
            their own).

    Returns:
        (H, W) int32: the group's id on the joined pixels, 0 elsewhere.
    """
    lut = np.arange(int(max([with_links.max(initial=0), *group_of.keys(), 0])) + 1,
                    dtype=np.int32)
    for i, r in group_of.items():
        if r:
            lut[i] = r
    return np.where(with_links != labels, lut[with_links], 0).astype(np.int32)
