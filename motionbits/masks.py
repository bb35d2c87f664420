"""Pixel-resolution MotionBit masks from node clusters (paper Sec. 5.2, last step).

The paper prompts SAM2 with each cluster. The weight-free default here: every cluster gets
one rigid motion fitted to its nodes; each pixel near a cluster takes the label whose
motion best explains the pixel's own backward flow and its colour -- the static background
and last frame's label compete too, the latter with a small credit so that a body that stops keeps
its mask -- and specks are removed.
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from motionbits.aperture import (FLAT_GRADIENT, flat_regions, ground_regions,
                                 half_colour_gradient, reaches_border)
from motionbits.boxes import at_border, grow_box, label_areas, label_boxes, label_pieces
from motionbits.evidence import photometric_residual
from motionbits.nodes import NodeGrid, binary_fill_holes
from motionbits.twists import kabsch_2d, rigid_matrix

__all__ = ["fit_cluster_motions", "StaticCost", "static_cost", "assign_pixels", "fill_holes",
           "remove_specks", "drop_labels", "hide_small", "hide_edgeless", "outline_gradient",
           "snap_to_edges", "trim_flat_background", "flat_looks", "SPECK_CELLS",
           "EDGELESS_GRADIENT", "HALO_FLAT_GRADIENT", "HALO_MASK_SHARE", "hide_thin",
           "THIN_SHARE", "THIN_PIECE_SHARE"]

#: The refit of a cluster's motion keeps nodes within this many times the RANSAC inlier
#: threshold, or this many times the median residual if that is larger ...
REFIT_FACTOR = 3.0
#: ... over this many refits.
REFITS = 2
#: Side (px) of the square over which photometric residuals are averaged.
PHOTO_WINDOW = 3
#: A detached piece of a label smaller than this many grid cells is a speck.
SPECK_CELLS = 2
#: A mark of which an opening by a square of one grid cell (rounded up) keeps less than
#: this share is stripes, not a body (:func:`hide_thin`).
THIN_SHARE = 0.25
#: A detached piece of a mark, other than its largest, of which that opening keeps less
#: than this share is not shown (:func:`hide_thin`): a sliver of a shadow's edge or of a
#: grain line that took the mark's label, away from its body (round 45).
THIN_PIECE_SHARE = 0.5
#: grey levels per px (Sobel, 5x5 mean; :func:`motionbits.evidence.gradient_magnitude`): a
#: mask whose outline shows less image gradient than this over all but
#: ``1 - OUTLINE_QUANTILE`` of it, within ``OUTLINE_BAND`` px, is edgeless ...
EDGELESS_GRADIENT = 3.0
OUTLINE_QUANTILE = 0.9
OUTLINE_BAND = 3
#: A flat image region -- colour gradient under ``HALO_FLAT_GRADIENT`` grey levels per px,
#: half :data:`motionbits.aperture.FLAT_GRADIENT`: a body of the table's own material
#: joins the table's region through its weaker edges at 6 -- of which a mask covers less
#: than ``HALO_MASK_SHARE``: that mask's pixels in it are a halo.
HALO_FLAT_GRADIENT = 3.0
HALO_MASK_SHARE = 0.25
#: ... and a flat region of which one mask covers at least ``FACE_MASK_SHARE`` is that
#: body's face: the mask takes the rest of it (a flat arm whose flow read no motion in
#: patches). Round 13, on the 40 + 40 robot / hand scenes, 0.45 instead: hand mIoU 58.1
#: -> 57.6, static FP 0.3 -> 0.4%.
FACE_MASK_SHARE = 0.6
#: ... or, for a mask seen whole (it reaches no image border: not an arm or hand that
#: enters the frame), a closed flat region (inside the image) of which it covers at least
#: ``CLOSED_FACE_SHARE`` and that is at most ``CLOSED_FACE_GROWTH`` times the mask: a
#: face of that body closed by its edges (a door, a drawer front, a block's side whose
#: flow read motion on a part only). Round 20, on the robot / hand / pickplace scenes:
#: mIoU 64.9 / 64.7 / 50.9 -> 65.2 / 65.5 / 51.4; without the border condition (round
#: 19) an arm or hand took the table squares it crossed (64.2 / 64.2 / 51.4).
CLOSED_FACE_SHARE = 0.35
CLOSED_FACE_GROWTH = 2.0


def fit_cluster_motions(points: np.ndarray, back_points: np.ndarray, weights: np.ndarray,
                        node_labels: np.ndarray, labels: np.ndarray, inlier_threshold: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """One rigid backward motion q ~ R p + t per label, robust to a few stray nodes.

    Args:
        points, back_points: (n, 2) node positions and their backward-flow targets.
        weights: (n,) flow reliability of each node.
        node_labels: (n,) label of each node (0 = none).
        labels: (K,) the labels to fit.
        inlier_threshold: px; the refit keeps nodes within ``REFIT_FACTOR`` x this residual.

    Returns:
        theta (K,), t (K, 2) of the backward motion (current -> previous) of each label.
    """
    thetas = np.zeros(len(labels))
    trans = np.zeros((len(labels), 2))
    for i, lab in enumerate(labels):
        sel = node_labels == lab
        p = points[sel].astype(np.float64)
        q = back_points[sel].astype(np.float64)
        w = weights[sel].astype(np.float64) + 1e-6
        th, t = kabsch_2d(p, q, w)
        for _ in range(REFITS):
            c, s = np.cos(th), np.sin(th)
            pred = p @ np.array([[c, s], [-s, c]]) + t
            r = np.linalg.norm(pred - q, axis=1)
            cut = max(REFIT_FACTOR * inlier_threshold, float(np.median(r)) * REFIT_FACTOR)
            th, t = kabsch_2d(p, q, w * (r < cut))
        thetas[i], trans[i] = th, t
    return thetas, trans


def _support_box(grid: NodeGrid, node_labels: np.ndarray, label: int
                 ) -> tuple[slice, slice, np.ndarray] | None:
    """Pixels whose grid node has ``label`` in its 3x3 node neighbourhood, as a box
    (rows, cols) of the image and the (h, w) bool mask inside it; ``None`` if empty.

    Equals dilating the node mask by one node and upsampling it with nearest-neighbour
    (cv2.INTER_NEAREST's rule: pixel x reads node floor(x * cols / width)), on the box only.
    """
    m = (node_labels == label).reshape(grid.rows, grid.cols).view(np.uint8)
    m = cv2.dilate(m, np.ones((3, 3), np.uint8))
    col0, row0, n_cols, n_rows = cv2.boundingRect(m)  # the node box
    if n_cols == 0:
        return None
    node_y, node_x = grid.pixel_nodes  # non-decreasing: a node box is a pixel box
    rows = slice(np.searchsorted(node_y, row0), np.searchsorted(node_y, row0 + n_rows))
    cols = slice(np.searchsorted(node_x, col0), np.searchsorted(node_x, col0 + n_cols))
    return rows, cols, m[node_y[rows]][:, node_x[cols]].view(bool)


class StaticCost(NamedTuple):
    """What "nothing moved" costs at each pixel of a frame before any MotionBit competes
    (:func:`static_cost`; :func:`assign_pixels`). Each (H, W) float32."""

    #: grey levels: how far "nothing moved" misses the pixel (``PHOTO_WINDOW`` mean)
    photo: np.ndarray
    #: px: the static motion's cost -- its flow residual (the flow's length) weighted by
    #: ``texture``, plus the photometric term
    cost: np.ndarray
    #: px: the prior's credit, where the carried label is valid (else 0)
    credit: np.ndarray
    #: px: the cost a MotionBit must beat: ``cost``, less the credit where the
    #: background keeps it (no carried label, or one its motion never earned)
    best: np.ndarray
    #: in [0, 1]: weight of a flow residual (1 = textured, its flow measured)
    texture: np.ndarray


def static_cost(speed: np.ndarray, gradient: np.ndarray, still: np.ndarray,
                prior: np.ndarray, prior_valid: np.ndarray, earned: np.ndarray, *,
                flow_texture: float, bonus: float, photo_weight: float,
                revealed: np.ndarray | None = None) -> StaticCost:
    """The static motion's side of :func:`assign_pixels`, which reads nothing of the
    frame's clusters (the segmenter computes it while they are found).

    Args:
        speed: (H, W) float32 px the flow moves each pixel (the static motion's residual).
        gradient: (H, W) float32 grey levels per px of image gradient
            (:func:`motionbits.evidence.gradient_magnitude`); over ``flow_texture`` a
            pixel's flow counts in full, below it in proportion (flat pixels' flow is
            interpolated).
        still: (H, W) float32 grey levels by which "nothing moved" misses each pixel
            (:func:`motionbits.evidence.static_residual`).
        prior, prior_valid, earned: as in :func:`assign_pixels`.
        bonus, photo_weight: as in :func:`assign_pixels`.
        revealed: (H, W) bool or None, background seen again after a body uncovered it
            (:class:`motionbits.revealed.StaticMemory`): ``still`` there already holds the
            residual against the remembered background, and the static cost drops its flow
            term (the flow smears the body's motion into its wake).
    """
    texture = np.minimum(gradient / flow_texture, 1.0)
    photo = cv2.blur(still, (PHOTO_WINDOW, PHOTO_WINDOW))
    cost = texture * speed + photo_weight * photo
    if revealed is not None:
        cost[revealed] = photo_weight * photo[revealed]
    # last frame's label is credited where it was carried consistently; against the
    # background, a MotionBit's label only where its motion once showed in the images
    # (``earned``): elsewhere the background gets the same credit
    credit = prior_valid * np.float32(bonus)  # bonus or 0
    best = cost - credit * ((prior == 0) | ~earned)
    return StaticCost(photo, cost, credit, best, texture)


def assign_pixels(grid: NodeGrid, node_labels: np.ndarray, labels: np.ndarray, thetas: np.ndarray,
                  trans: np.ndarray, flow_back: np.ndarray, cur_gray: np.ndarray,
                  prev_gray: np.ndarray, static: StaticCost, prior: np.ndarray,
                  prior_valid: np.ndarray, earned: np.ndarray, *,
                  bonus: float, photo_weight: float, evidence: float, kept: np.ndarray,
                  ambiguous: float) -> tuple[np.ndarray, np.ndarray]:
    """Label every pixel by the motion that best explains it.

    The cost of a motion at a pixel is its flow residual (px), weighted by how much texture
    the pixel has, plus ``photo_weight`` times its photometric residual (grey levels, 3x3
    mean): flow is smooth across motion boundaries and interpolated over textureless
    regions, the images are not, so the photometric term puts the boundary where the
    texture says it is. Holes of a label's mask that no other
    label fills (a textureless interior) are filled: a rigid body's image has no holes.

    Args:
        grid: the node grid (its image size is the working resolution).
        node_labels: (n,) id of each node's cluster (0 = none).
        labels: (K,) ids of the clusters, with backward motions ``thetas`` (K,), ``trans``
            (K, 2).
        flow_back: (H, W, 2) flow current -> previous.
        cur_gray, prev_gray: (H, W) float32 grey frames.
        static: the static motion's cost (:func:`static_cost`, from these ``prior``,
            ``prior_valid``, ``earned``, ``bonus`` and ``photo_weight``).
        prior: (H, W) int32 last frame's label map carried to this frame.
        prior_valid: (H, W) bool, where ``prior`` is trustworthy (consistent flow).
        earned: (H, W) bool, carried like ``prior``: where the pixel's MotionBit once
            explained its images better than "static" by ``evidence`` grey levels. Only
            there does a carried MotionBit label get the credit against the background: a
            label smeared onto a flat region, where motion is not observable, does not
            persist on its own (against another MotionBit it keeps the credit).
        bonus: cost credited to the prior's label.
        photo_weight: px of cost per grey level of photometric residual.
        evidence: grey levels (3x3 mean) by which a label's motion must beat "static" at a
            pixel to earn it.
        kept: ids of earlier MotionBits without a cluster now (e.g. bodies that stopped);
            they compete with the static motion on their prior pixels.
        ambiguous: px; where a cluster's motion moves a pixel less than this, the motion
            cannot be told from the background (e.g. near a centre of rotation) and the
            node-level cluster label gets the same credit as the prior.

    Returns:
        (H, W) int32 label map and the (H, W) bool ``earned`` map of this frame.
    """
    h, w = flow_back.shape[:2]
    window = PHOTO_WINDOW
    texture, static_photo, credit = static.texture, static.photo, static.credit
    best = static.best.copy()
    out = np.zeros((h, w), np.int32)
    shown = np.zeros((h, w), bool)
    node_map = grid.to_image(node_labels.astype(np.int32))
    if len(kept):  # on each one's box of ``prior``
        kept_cost = static.cost - credit
        kept_boxes = label_boxes(prior, max_label=int(max(kept)))
    for lab in kept:
        box = kept_boxes[lab - 1]
        if box is None:
            continue
        on = (prior[box] == lab) & prior_valid[box]
        cost = kept_cost[box]
        better = on & (cost < best[box])
        best[box][better] = cost[better]
        out[box][better] = lab
        shown[box][better] = True
    for lab, th, t in zip(labels, thetas, trans):
        support = _support_box(grid, node_labels, lab)
        if support is None:
            continue
        rows, cols, inside = support
        box = rows, cols
        photo = photometric_residual(cur_gray, prev_gray, rigid_matrix(th, t), box, window)
        # the whole box at once (cheaper than gathering its ``inside`` pixels)
        px = np.arange(cols.start, cols.stop, dtype=np.float32)[None, :]
        py = np.arange(rows.start, rows.stop, dtype=np.float32)[:, None]
        c, s = np.cos(th), np.sin(th)
        mx = c * px - s * py + t[0] - px  # the model's backward displacement
        my = s * px + c * py + t[1] - py
        resid = np.hypot(mx - flow_back[rows, cols, 0], my - flow_back[rows, cols, 1])
        barely = np.hypot(mx, my) < ambiguous
        mine = prior[box] == lab
        own = (mine & prior_valid[box]) | (barely & (node_map[box] == lab))
        cost = texture[box] * resid + photo_weight * photo - bonus * own
        better = inside & (cost < best[box])
        best[box][better] = cost[better]
        out[box][better] = lab
        gain = static_photo[box] - photo
        shown[box][better] = ((gain > evidence) | (earned[box] & mine))[better]
    out = fill_holes(out)
    return out, shown & (out > 0)


def fill_holes(label_map: np.ndarray) -> np.ndarray:
    """Background pixels enclosed by one label take that label; (H, W) int32."""
    out = label_map.copy()
    for i, box in enumerate(label_boxes(label_map)):
        if box is None:
            continue
        sub = out[box]
        hole = binary_fill_holes(label_map[box] == i + 1) & (sub == 0)
        sub[hole] = i + 1
    return out


def remove_specks(label_map: np.ndarray, min_area: int) -> np.ndarray:
    """Zero every connected piece of a label smaller than ``min_area`` px, except the
    largest piece of each label (a small body is still a body)."""
    out = label_map.copy()
    for p in label_pieces(label_map):
        small = np.flatnonzero(p.areas < min_area)
        small = small[(small != 0) & (small != p.largest)]
        if len(small):
            out[p.box][np.isin(p.pieces, small)] = 0
    return out


def drop_labels(label_map: np.ndarray, ids: np.ndarray | list[int]) -> np.ndarray:
    """``label_map`` (H, W) int32 with the labels ``ids`` zeroed (itself if ``ids`` is
    empty)."""
    if not len(ids):
        return label_map
    return np.where(np.isin(label_map, ids), 0, label_map).astype(np.int32)


def hide_small(label_map: np.ndarray, min_area: float) -> np.ndarray:
    """Zero every label whose whole mask covers fewer than ``min_area`` px.

    Unlike :func:`remove_specks` (detached pieces of a label), a label smaller than this
    is not shown at all.

    Args:
        label_map: (H, W) int32 labels (0 = background).
        min_area: px.

    Returns:
        (H, W) int32 label map (``label_map`` itself if nothing is hidden).
    """
    area = label_areas(label_map)
    small = np.flatnonzero(area[1:] < min_area) + 1
    return drop_labels(label_map, small[area[small] > 0])


def hide_thin(label_map: np.ndarray, side: int) -> np.ndarray:
    """Zero every detached piece of a label, other than its largest, of which an opening by
    a ``side`` x ``side`` square keeps less than ``THIN_PIECE_SHARE``, and then every label
    of which the opening keeps less than ``THIN_SHARE`` of its pixels: stripes, not a
    body (the flow along a wood grain's lines or a shadow's edge under a moving camera).

    Args:
        label_map: (H, W) int32 labels (0 = background).
        side: px, the square's side (one grid cell).

    Returns:
        (H, W) int32 label map (``label_map`` itself if nothing is hidden).
    """
    square = np.ones((side, side), np.uint8)
    out = label_map
    thin = []
    for p in label_pieces(label_map):
        opened = cv2.morphologyEx(p.mark.view(np.uint8), cv2.MORPH_OPEN, square,
                                  borderType=cv2.BORDER_CONSTANT, borderValue=0)
        kept = np.bincount(p.pieces[opened > 0], minlength=len(p.areas))  # px each piece keeps
        stripe = kept < THIN_PIECE_SHARE * p.areas
        stripe[[0, p.largest]] = False  # the background; the largest piece
        if stripe.any():
            if out is label_map:
                out = label_map.copy()
            out[p.box][stripe[p.pieces]] = 0
        left = ~stripe
        left[0] = False  # what is left of the mark
        if kept[left].sum() < THIN_SHARE * p.areas[left].sum():
            thin.append(p.label)
    return drop_labels(out, thin)


def flat_looks(rgb: np.ndarray, half_gradient: np.ndarray | None = None
               ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...]:
    """The (H, W, 3) uint8 frame's flat regions as the flat links' test reads them
    (:func:`motionbits.aperture.flat_link_candidates`, ``FLAT_GRADIENT``) and as
    :func:`trim_flat_background` does (``HALO_FLAT_GRADIENT``): two
    :func:`motionbits.aperture.flat_regions` results, from ``half_gradient``
    (``half_colour_gradient(rgb)``) if already computed."""
    if half_gradient is None:
        half_gradient = half_colour_gradient(rgb)
    return (flat_regions(rgb, FLAT_GRADIENT, half_gradient),
            flat_regions(rgb, HALO_FLAT_GRADIENT, half_gradient))


def trim_flat_background(label_map: np.ndarray, rgb: np.ndarray,
                         flat_look: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
                         ) -> np.ndarray:
    """Give back to the background the mask pixels that lie in a flat region of the image
    of which their mask covers less than ``HALO_MASK_SHARE``; give a mask the rest of a
    flat region of which it covers at least ``FACE_MASK_SHARE`` (``CLOSED_FACE_SHARE`` of a
    closed region at most ``CLOSED_FACE_GROWTH`` times a mask that reaches no border).

    A mask that overhangs its body onto a flat table (smeared flow, a soft shadow that
    moves with the body) crosses no image edge: the overhang and the table around it are
    one flat region (:func:`motionbits.aperture.flat_regions`: colour gradient under
    ``HALO_FLAT_GRADIENT``), most of it outside the masks. Where several bodies move over
    one flat table, their overhangs can together cover most of it, each a small part. A
    body's own flat faces are closed by its edges, and mostly inside its mask: the
    background pixels of such a face (a flat link whose flow read no motion in patches,
    a gap between two MotionBits of one body) are the body's. A body seen whole whose flow
    read motion on a part of a face only (a door, a drawer front) covers less of it, but
    the face is closed (inside the image) and not much larger than the mask; an arm or a
    hand reaches the image border, and the table squares it crosses are closed too. A flat
    region that reaches the border and covers ``GROUND_SHARE`` of the image is the ground
    or a wall: a mask covering less than ``FACE_MASK_SHARE`` of it is an overhang there,
    however large (fast motion smears the flow over a third of a plain table).

    Args:
        label_map: (H, W) int32 labels (0 = background).
        rgb: (H, W, 3) uint8 frame at the same size.
        flat_look: ``motionbits.aperture.flat_regions(rgb, HALO_FLAT_GRADIENT)`` if
            already computed.

    Returns:
        (H, W) int32 label map: each mask of ``label_map`` less its halos, plus the
        background pixels of its faces.
    """
    if not label_map.any():
        return label_map
    _, regions, stats = flat_regions(rgb, HALO_FLAT_GRADIENT) if flat_look is None else flat_look
    area = np.maximum(stats[:, cv2.CC_STAT_AREA], 1).astype(np.float64)
    # the labelled pixels of flat regions (region 0: the pixels that are not flat), each
    # (region, label) pair as one integer: the share of its region each mask covers
    at = np.flatnonzero(((label_map > 0) & (regions > 0)).ravel())
    region, label = regions.ravel()[at], label_map.ravel()[at]
    pair = region.astype(np.int64) * (int(label_map.max()) + 1) + label
    share = np.bincount(pair)[pair] / area[region]
    closed = ~reaches_border(stats, label_map.shape)[region]
    # a large flat region that leaves the image is the ground or a wall: a mask keeps its
    # pixels there only if it holds most of it (a body's own face), not a halo's share
    ground = ground_regions(stats, label_map.shape)[region]
    out = label_map.astype(np.int32, copy=True)
    out.ravel()[at[(share < HALO_MASK_SHARE) | (ground & (share < FACE_MASK_SHARE))]] = 0
    # a flat region mostly inside one mask is that body's face: its uncovered pixels are
    # the body's too (where the flow read no motion on it), not the background's
    face = share >= FACE_MASK_SHARE
    # a closed flat region, a good part inside a mask seen whole, is that body's face too
    face |= (closed & ~at_border(label_map)[label] & (share >= CLOSED_FACE_SHARE)
             & (area[region] <= CLOSED_FACE_GROWTH * label_areas(label_map)[label]))
    if face.any():
        owner = np.zeros(len(area), np.int32)  # region -> the mask it belongs to (0: none)
        owner[region[face]] = label[face]
        # on the box of the faces (``flat_regions``' stats box each region's pixels)
        x, y, w, h = (stats[np.flatnonzero(owner), i] for i in range(4))
        box = (slice(y.min(), (y + h).max()), slice(x.min(), (x + w).max()))
        sub = out[box]
        background = sub == 0
        sub[background] = np.take(owner, regions[box][background])
    return out


def hide_edgeless(label_map: np.ndarray, gradient: np.ndarray) -> np.ndarray:
    """Zero every label whose outline runs where the image shows no edge.

    A body's outline is an image edge (its colour or shading against its surroundings);
    a patch of a flat table that a moving soft shadow or smeared flow left labelled looks
    like its surroundings. A mask is edgeless when the image gradient within
    ``OUTLINE_BAND`` px of its outline stays under ``EDGELESS_GRADIENT`` on
    ``OUTLINE_QUANTILE`` of those pixels: no motion could be seen on it, and the mark would
    point at nothing.

    Args:
        label_map: (H, W) int32 labels (0 = background).
        gradient: (H, W) float32 grey levels per px of image gradient
            (:func:`motionbits.evidence.gradient_magnitude`).

    Returns:
        (H, W) int32 label map (``label_map`` itself if nothing is hidden).
    """
    edgeless = [i + 1 for i, box in enumerate(label_boxes(label_map)) if box is not None
                and np.quantile(outline_gradient(label_map, i + 1, box, gradient),
                                OUTLINE_QUANTILE) < EDGELESS_GRADIENT]
    return drop_labels(label_map, edgeless)


def outline_gradient(label_map: np.ndarray, label: int, box: tuple[slice, slice],
                     gradient: np.ndarray) -> np.ndarray:
    """(k,) float32 image gradient at the k pixels within ``OUTLINE_BAND`` px of the
    outline of mask ``label`` (its bounding box ``box``), inside and out.

    Args:
        label_map: (H, W) int32 labels.
        label: the mask's label.
        box: (rows, cols) slices of its bounding box.
        gradient: (H, W) float32 grey levels per px
            (:func:`motionbits.evidence.gradient_magnitude`).
    """
    grown = grow_box(box, OUTLINE_BAND + 1, label_map.shape)
    mask = (label_map[grown] == label).astype(np.uint8)
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * OUTLINE_BAND + 1,) * 2)
    outline = (cv2.dilate(mask, disk) > 0) & (cv2.erode(mask, disk) == 0)
    return gradient[grown][outline]


def snap_to_edges(label_map: np.ndarray, rgb: np.ndarray, band: int) -> np.ndarray:
    """Trim each mask's outline, within ``band`` px of where the motion put it, back to
    the strongest image edge (marker-based watershed on the colour frame).

    Flow is smooth across motion boundaries and the photometric test is blind where both
    sides are flat, so a mask can overhang its body by a few pixels (a halo on the flat
    table along a moving arm). A pixel more than ``band`` px inside a mask (or on its
    medial axis, so thin parts keep a marker) keeps its label, a pixel more than ``band``
    px from every mask is background, and the band between is flooded from both by image
    gradient. Only pixels that the flood gives to the background are taken from a mask:
    nothing is added (a texture edge outside a mask cannot grow it), and where two masks
    meet, the motion keeps deciding.

    Args:
        label_map: (H, W) int32 labels (0 = background).
        rgb: (H, W, 3) uint8 frame at the same size.
        band: px (0 = return ``label_map`` unchanged).

    Returns:
        (H, W) int32 label map, each mask a subset of its mask in ``label_map``.
    """
    if band < 1 or not label_map.any():
        return label_map
    # everything happens on the box of the masks grown by the band (+1 px of background)
    ys, xs = np.nonzero(label_map.any(axis=1))[0], np.nonzero(label_map.any(axis=0))[0]
    h, w = label_map.shape
    box = (slice(max(ys[0] - band - 1, 0), min(ys[-1] + band + 2, h)),
           slice(max(xs[0] - band - 1, 0), min(xs[-1] + band + 2, w)))
    sub = label_map[box]
    near = cv2.dilate((sub > 0).astype(np.uint8), cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (2 * band + 1, 2 * band + 1)))
    markers = (near == 0).astype(np.int32)  # 1: the background's marker
    ridge_kernel = np.ones((3, 3), np.uint8)
    for i, lbox in enumerate(label_boxes(sub)):
        if lbox is None:
            continue
        rows = slice(max(lbox[0].start - 1, 0), lbox[0].stop + 1)
        cols = slice(max(lbox[1].start - 1, 0), lbox[1].stop + 1)
        mask = (sub[rows, cols] == i + 1).astype(np.uint8)
        dist = cv2.distanceTransform(mask, cv2.DIST_L2, 3)
        core = (dist > band) | ((dist > 0) & (dist >= cv2.dilate(dist, ridge_kernel)))
        markers[rows, cols][core] = i + 2
    flooded = cv2.watershed(np.ascontiguousarray(rgb[box]), markers)
    # a pixel leaves its mask only for the background's basin (between two masks the
    # motion decides), or as a watershed line (-1) on the background's edge
    to_background = flooded == 1
    to_background |= (flooded < 0) & (cv2.dilate(to_background.astype(np.uint8),
                                                  ridge_kernel) > 0)
    out = label_map.copy()
    out[box][to_background] = 0
    return out
