"""Completing a body's mark by colour (ours; the paper prompts SAM2 instead).

Motion marks only the parts of a body where the flow read it: a cylinder's evenly lit top
that slid, the far half of a door, a block's wooden top whose grain the flow smeared. The
mask found there is precise but partial. Each shown mask of a MotionBit at rest now that
reaches no image border, or a small one that does (``BORDER_MARK_SHARE``: a body the view
cuts, not an arm or hand that enters the frame; round 62), is grown by OpenCV's GrabCut
(colour models of the mask and of its surroundings, cut along the image's edges) within
a box around it: the pixels the cut gives to the body, joined to the mask and not another
mask's, are the body's too -- unless they run out to the box's frame where it is not the
image's border that the mask reaches, or add more than ``BORDER_GROWTH`` times the mask
where they reach it (a mark spilled onto a plain table would take the table as far as the
box goes; the cut is then tried once more in a box twice as far out, for a mark on a
small part of its body, such as a block's top face whose sides run past the first box) --
nor, for a mark at rest, where they add more than ``GROWTH`` times the mark (the mark a
cast shadow left on the table, round 64).
The marks too small to show are completed last (:func:`complete_small_marks`), where no
other mark is, and shown only if their body then covers the smallest shown size; one that
touches another mark is the rest of that mark's body and joins it. The segmenter's state
keeps the motion's masks.

The mark of a MotionBit moving now is completed only where at least
``OPEN_OUTLINE_SHARE`` of its outline runs where the image shows no edge: there the mask
stops inside its body (a lid whose far half the flow did not read). A mask whose outline
follows image edges is left as its motion gives it -- each cut costs milliseconds a frame
on 2 CPU cores, and completing every moving mark took the segmenter from 2.9x to 3.8x
its flow stage's time on the built-in clip, whose bodies' masks already end at their
edges.

Within a stream, the cut also knows what the scene looked like before (:class:`FirstLook`,
each pixel as first seen standing still and unlabelled): pixels within the box that now
look otherwise, other than by a cast shadow, start on the body's side of the cut --
unless another mask holds them (another body, or the hand beside it: its colours are
not the body's). A body's faces that its motion did not mark (a cylinder's dark side
under its textured top) differ from the table first seen there, so its colours enter
the body's model instead of the background's; pixels that still look as first seen stay
on the background's side unless their colours say otherwise (the body's top may be the
table's colour).

A mark at rest also gives back the pixels of its own mask that the cut puts on the
background's side, when they are under ``TRIM_SHARE`` of it (the table beside a block
that its motion's mask took along); a moving mark only grows. Within a stream, no cut
adds a pixel that shows the scene first seen there under a cast shadow
(:meth:`FirstLook.relit`; round 42). A mark at rest also gives back, however much of
it they are, the pixels of its mask where the stream's memories see the static world
under a cast shadow (``shadow``: :func:`motionbits.shadows.cast_shadows`) and the
texture first seen there shows through, correlated (:meth:`FirstLook.shows_texture`), and
the thin rim of mask left around them (the shadow test misses a shadow's hard edges): the
block's shadow that its mark took along is often half of the mark, and then its colours
are in the body's model and the cut keeps it (round 50).

Within a stream, a mark at rest takes the cut found for it at the last frame again while
it and the image under it have not changed (:class:`CutMemory`): GrabCut's answer turns
on the mark's exact outline, and a block at rest was completed at one frame and not at
the next. Under a moving camera the cuts are carried along the static world's model
(:meth:`CutMemory.follow`). A mark at rest still lying on the body carried to it, under
an image that matches the carried one within a pixel, is cut anew; where that cut finds
less than ``FOLLOW_LARGER`` of the carried body, it is cut once more with that body on
the body's side from the start (a carried body drifts a little from frame to frame; the
cut follows the image's edges), and takes the carried body, less the table under a
shadow now, where that cut finds nothing (round 53).

Measured in docs/results.md, "Completing marks by colour" (rounds 20 to 22).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import cv2
import numpy as np

from motionbits.arrivals import SURROUND_DIFFERENCE, surroundings_colour
from motionbits.boxes import (at_border, grow_box, label_areas, label_boxes, nonzero_box,
                              pieces_holding)
from motionbits.flow import pixel_grid
from motionbits.masks import EDGELESS_GRADIENT, drop_labels, outline_gradient
from motionbits.revealed import (SHADOW_CHROMA, SHADOW_GAIN, SHADOW_WINDOW, WINDOW,
                                 _color_difference, brightness, follow_known, follow_look,
                                 gain_of, light_change, texture_shows)

__all__ = ["complete_masks", "complete_small_marks", "CutMemory", "FirstLook",
           "COMPLETION_REACH", "WIDER", "COMPLETION_SIDE", "OPEN_OUTLINE_SHARE",
           "FIRST_SEEN_KNOWN", "FIRST_SEEN_CHANGED", "UNCOVERED_KNOWN", "UNCOVERED_CONTRAST",
           "UNCOVERED_IOU", "TRIM_SHARE", "TRIM_OPEN", "SHADOW_RIM", "SHOWN_CORRELATION",
           "SHOWN_SHARE", "TEXTURE_WINDOW", "SHADOW_TEXTURE", "TOUCH_SHARE",
           "BORDER_MARK_SHARE", "BORDER_GROWTH", "GROWTH"]

#: A mark at rest that reaches the image's border is completed when it covers at most
#: this share of the image (a body the view cuts; an arm or hand entering the view is
#: larger: without the bound, sim40's hand track lost 4.5 mIoU, round 62) ...
BORDER_MARK_SHARE = 0.01
#: ... and a cut that reaches the image's border adds at most this many times the mark
#: (a mark beside the border took the table along it, 126,000 px, without it).
BORDER_GROWTH = 3
#: A cut adds at most this many times a mark at rest: a body's faces that its motion did not
#: mark, not the table around the mark a cast shadow left there (19,600 px around 2,900,
#: held33 seed 607 scene_0007). At the last frames of 120 moving-camera pick-and-place
#: scenes no cut of a mark at rest that added over 4 times it took a body's pixels, but
#: with 4 a robot's cylinder, grown from its top face at an earlier frame, was lost (round
#: 64). A moving mark's cut (an arm and the block it carries) and a small mark's (a piece
#: of a body set down, grown to its body) are not bounded so.
GROWTH = 6

#: The box GrabCut works in: the mask's box grown by this share of its longer side
#: (+ ``COMPLETION_MARGIN`` px); the box's outermost ``COMPLETION_FRAME`` px are the
#: background's for sure. 0.75 since the cut starts from the first look (round 25: a
#: top face's mark reaches its body's sides only in a wider box; pickplace 60.5 -> 63.5,
#: docs/results.md, "Completing marks by colour").
COMPLETION_REACH = 0.75
#: A cut that runs out to its box's frame is tried again in a box grown this many times
#: as far (the mark of a block's top face, seen from above at an angle, is a third of it).
WIDER = 2.0
COMPLETION_MARGIN = 8
COMPLETION_FRAME = 2
#: GrabCut runs on the box scaled down to at most this many px on its longer side (its
#: time grows with the box's pixels; at 64 px mIoU fell by 0.2-0.5; 96 until round 42,
#: whose boxes of 200-300 px came back in blocks of 2-3 px: 192 read +0.5 / +0.8 mIoU on
#: 239 moving-camera pick-and-place scenes, docs/results.md, "Finer cuts, and cuts that
#: also trim (round 42)") ...
COMPLETION_SIDE = 192
#: ... for this many iterations (2: the same mIoU on the last frames of the pickplace
#: and seed-7 robot / hand scenes).
COMPLETION_ITERATIONS = 1
#: A mark at rest loses the pixels the cut gives to the background (pieces that an
#: opening by a ``TRIM_OPEN`` px square keeps) when they are under this share of it: the
#: table beside a block that its motion's mask took along (a larger share is a cut that
#: went wrong, and the mark is left as its motion gives it).
TRIM_SHARE = 0.5
TRIM_OPEN = 3
#: px: a mark at rest that gives back a cast shadow (``shadow`` of :func:`complete_masks`)
#: also gives back what an opening by a square of this side removes from it within this
#: reach of that shadow: the shadow's hard edges, which the shadow test misses (round 50).
SHADOW_RIM = 5
#: ... and gives back only the pieces of that shadow that show the texture first seen
#: there (:meth:`FirstLook.shows_texture`): on this share or more of their textured
#: pixels, grey levels correlated by this much or more over a window of this many px,
#: where the first look's grey levels vary by this standard deviation or more (a plain
#: table under a shadow and a dark, speckled cylinder over marble pass the shadow test
#: alike; only the texture carried through tells them apart).
SHOWN_CORRELATION = 0.5
SHOWN_SHARE = 0.5
TEXTURE_WINDOW = 9
SHADOW_TEXTURE = 3.0
#: px: a pixel the cut gives to a body is the table under a shadow where it has the
#: chromaticity of the background within this window, dimmed (:func:`_shadowed`).
COMPLETION_SHADOW_WINDOW = 31
#: A moving MotionBit's mark is completed only where this share of its outline (within
#: :data:`motionbits.masks.OUTLINE_BAND` px) has an image gradient under
#: :data:`motionbits.masks.EDGELESS_GRADIENT` (on the built-in clip its moving masks show
#: 0.01-0.19; on generated lids and blocks 0.25-0.8).
OPEN_OUTLINE_SHARE = 0.25
#: A mark at rest takes the cut found for it at the last frame again (:class:`CutMemory`)
#: while it overlaps the mark that cut was found for by this IoU ...
RECALL_IOU = 0.8
#: ... and at most this share of the body's pixels changed by more than ``RECALL_LEVEL``
#: grey levels (any channel) since.
RECALL_CHANGED = 0.05
RECALL_LEVEL = 12
#: Under a moving camera a cut is carried along the static world's model
#: (:meth:`CutMemory.follow`), into a box grown by this many px; it is recalled while at
#: least ``FOLLOW_INSIDE`` of the mark lies within one px of the body carried, the mark
#: covers at least ``FOLLOW_AREA`` of the area it had, and the image matches the carried
#: one within one px (the model's error) as ``RECALL_CHANGED`` asks. Where the new cut
#: finds less than ``FOLLOW_LARGER`` of the body carried, the cut is made again with that
#: body on the body's side. Round 53: a block's mark completed at one frame and not at
#: the next, where the camera had moved (docs/results.md, "Cuts carried by the camera's
#: model").
FOLLOW_MARGIN = 2
FOLLOW_INSIDE = 0.9
FOLLOW_AREA = 0.5
FOLLOW_LARGER = 0.85
#: A mark stands as first seen (:meth:`FirstLook.as_first_seen`) when the first look
#: knows at least this share of its pixels ...
FIRST_SEEN_KNOWN = 0.3
#: ... and at most this share of those look otherwise now (a static body marked through
#: parallax or smeared flow; a block kicked 2 cm changes 16-24% of its first look; of the
#: marks matched to a body at the last frame of 140 generated pick-and-place scenes, none
#: changed less than 10.6%; docs/reading_the_paper.md,
#: "Marks that stand as first seen are not shown", rounds 33 and 36).
FIRST_SEEN_CHANGED = 0.08
#: Steps per unit of a brightness ratio in the median gain of
#: :meth:`FirstLook.texture_kept` (uint8 levels: ratios up to 2.55; a shadow's are under
#: ``SHADOW_GAIN[1]``).
GAIN_LEVELS = 100
#: px: the texture test's answer at a pixel reads the pixels this far (the median's
#: window, then the residual's mean).
TEXTURE_REACH = SHADOW_WINDOW // 2 + WINDOW // 2
#: A mark shows the surface around it where a body was first seen
#: (:meth:`FirstLook.uncovered`) only where the first look knows this share of it or more.
UNCOVERED_KNOWN = 0.5
#: A mark shows the surface around it where a body was first seen when the first look
#: there lies this many times as far from the surroundings' mean colour as the mark does
#: now (:meth:`FirstLook.uncovered`). Read off eight marks found at the last frame of
#: generated pick-and-place scenes by the test without it: 2.8-9.4 for the table a body
#: left, 1.8 and 2.0 for the marks of two bodies nudged 1.7 cm that cover the table
#: beside them too (docs/reading_the_paper.md,
#: "Marks left where a body was are not shown").
UNCOVERED_CONTRAST = 2.5
#: A mark found uncovered (:meth:`FirstLook.uncovered`) stays found while it overlaps the
#: mark found at the last frame by this intersection over union.
UNCOVERED_IOU = 0.5
#: A mark too small to show that completion grew past the minimum
#: (:func:`complete_small_marks`) is the rest of the body of a mark it touches along this
#: share of its outline or more, and takes that mark's label (round 45).
TOUCH_SHARE = 0.25


def complete_masks(label_map: np.ndarray, rgb: np.ndarray, moving: Collection[int] = (),
                   gradient: np.ndarray | None = None,
                   memory: CutMemory | None = None,
                   first_look: FirstLook | None = None,
                   labels: Collection[int] | None = None,
                   shadow: np.ndarray | None = None, growth: float = GROWTH) -> np.ndarray:
    """Grow each mask over the rest of its body (GrabCut): every mask at rest that reaches
    no image border or covers at most ``BORDER_MARK_SHARE`` of the image, a moving one
    that reaches no image border where its outline stops inside its body.

    Args:
        label_map: (H, W) int32 labels (0 = background).
        rgb: (H, W, 3) uint8 frame at the same size.
        moving: labels whose MotionBit moves now: completed only where at least
            ``OPEN_OUTLINE_SHARE`` of their outline shows no image edge.
        gradient: (H, W) float32 image gradient
            (:func:`motionbits.evidence.gradient_magnitude`); None: moving masks are left
            as they are.
        memory: the cuts found at earlier frames of a stream (:class:`CutMemory`), updated
            in place; None: every mask is cut anew.
        first_look: the scene as first seen in the stream (:class:`FirstLook`); None:
            the cut starts from the mask alone.
        labels: the masks to grow; None: all.
        shadow: (H, W) bool, where the static world shows under a cast shadow
            (:func:`motionbits.shadows.cast_shadows`): no mask at rest keeps those of its
            pixels that show the texture ``first_look`` saw there (nor the thin rim left
            around them, ``SHADOW_RIM``) and no cut adds them; None (or no
            ``first_look``): no such test.
        growth: a cut adds at most this many times a mask at rest (``GROWTH``; np.inf: no
            bound but the others).

    Returns:
        (H, W) int32 label map: each such mask plus the background pixels its body's
        colours take within its box, where they stay off the box's frame, and a mask at
        rest less the pixels they give to the background (``TRIM_SHARE``)
        (``label_map`` itself if nothing changes).
    """
    if not label_map.any():
        if memory is not None:
            memory.keep({})
        return label_map
    border = at_border(label_map)
    # a mark at the image's border is completed only at rest and small (an arm or hand
    # entering the view is not a body the view cuts)
    small = label_areas(label_map) <= BORDER_MARK_SHARE * label_map.size
    out = label_map
    found: dict[int, _Cut] = {}  # the cuts of the marks at rest, for the memory
    for i, box in enumerate(label_boxes(label_map)):
        label = i + 1
        if box is None or (labels is not None and label not in labels):
            continue
        if border[label] and (label in moving or not small[label]):
            continue
        if label in moving and (gradient is None or not _open_outline(label_map, label, box,
                                                                      gradient)):
            continue
        cut = None if memory is None or label in moving else memory.recall(label_map, label,
                                                                             box, rgb)
        if cut is None or cut.followed:
            carried = None if cut is None else _unshadowed(cut, label_map, label, rgb,
                                                           first_look)
            bound = np.inf if label in moving else growth
            cut = _cut(label_map, label, box, rgb, out, first_look, trim=label not in moving,
                       shadow=shadow, growth=bound)
            if carried is not None and (cut is None or np.count_nonzero(cut.body)
                                        < FOLLOW_LARGER * np.count_nonzero(carried.body)):
                cut = _cut(label_map, label, box, rgb, out, first_look,
                           trim=label not in moving, shadow=shadow, prior=carried,
                           growth=bound) or carried
        if cut is None:
            continue
        if label not in moving:
            found[label] = cut
        if out is label_map:
            out = label_map.copy()
        sub = out[cut.rows, cut.cols]
        sub[cut.body & (sub == 0)] = label
        if label not in moving:  # what a trim took (a moving mark's cut only grows it)
            sub[(sub == label) & ~cut.body] = 0
    if memory is not None:
        memory.keep(found)
    return out


def complete_small_marks(pieces: np.ndarray, label_map: np.ndarray, rgb: np.ndarray,
                         min_area: float, moving: Collection[int] = (),
                         gradient: np.ndarray | None = None,
                         first_look: FirstLook | None = None) -> np.ndarray:
    """The marks hidden as smaller than ``min_area``, grown by :func:`complete_masks` after
    the others (where no other mark is), and shown where their body then covers
    ``min_area``: a body set down is marked where its carrier's motion showed on it, and
    the trims may leave that part small. One that stands as ``first_look`` saw it is not
    shown (nothing moved there). One that touches another mark along ``TOUCH_SHARE`` of
    its outline or more is the rest of that mark's body and takes its label (one body,
    one mark) -- if it is not larger than that mark; otherwise it is not shown.

    Args:
        pieces: (H, W) int32 labels before the small marks were hidden (0 = background).
        label_map: (H, W) int32 labels shown, the others completed.
        rgb: (H, W, 3) uint8 frame at the same size.
        min_area: px, the area a mark must cover to be shown.
        moving, gradient, first_look: as for :func:`complete_masks`.

    Returns:
        (H, W) int32 label map (``label_map`` itself if no mark was hidden).
    """
    # the labels there were and are not shown (sorted)
    hidden = np.setdiff1d(np.flatnonzero(label_areas(pieces)[1:]) + 1,
                          np.flatnonzero(label_areas(label_map)[1:]) + 1)
    if not hidden.size:
        return label_map
    put = np.isin(pieces, hidden) & (label_map == 0)
    if not put.any():
        return label_map
    both = label_map.copy()
    both[put] = pieces[put]
    out = complete_masks(both, rgb, moving, gradient, None, first_look,
                         labels={int(label) for label in hidden}, growth=np.inf)
    area = label_areas(out)
    out = drop_labels(out, [label for label in hidden
                            if label >= area.size or area[label] < min_area])
    if first_look is not None:  # nothing moved where one stands as first seen
        out = drop_labels(out, np.intersect1d(first_look.as_first_seen(out, rgb), hidden))
    boxes = label_boxes(out, int(hidden[-1]))
    ring = np.ones((3, 3), np.uint8)
    for label in hidden:
        box = boxes[label - 1]
        if box is None:
            continue
        rows, cols = grow_box(box, 1, out.shape)
        sub = out[rows, cols]
        mask = sub == label
        around = sub[(cv2.dilate(mask.view(np.uint8), ring) > 0) & ~mask]
        others = around[(around > 0) & (around != label)]
        if others.size and others.size >= TOUCH_SHARE * around.size:
            # the rest of a body is not larger than the mark it joins (a wall panel
            # grown out of a speck beside an arm's mark is not the arm)
            joined = np.bincount(others).argmax()
            sub[mask] = joined if area[joined] >= area[label] else 0
    return out


@dataclass(frozen=True)
class _Cut:
    """The body GrabCut found for a mask: its pixels ``body`` (h, w) bool within the box
    (``rows``, ``cols``), the mask's (less those a trim took) and those the cut added,
    from the mask (h, w) bool on the (h, w, 3) uint8 image ``rgb`` of that box;
    ``followed`` once carried by a moving camera's model (:meth:`CutMemory.follow`)."""
    rows: slice
    cols: slice
    mask: np.ndarray
    rgb: np.ndarray
    body: np.ndarray
    followed: bool = False


def _cut(label_map: np.ndarray, label: int, box: tuple[slice, slice], rgb: np.ndarray,
         out: np.ndarray, first_look: FirstLook | None = None, trim: bool = False,
         shadow: np.ndarray | None = None, prior: _Cut | None = None,
         growth: float = np.inf) -> _Cut | None:
    """The body's rest that GrabCut finds for mask ``label`` (its box ``box``) in a box
    around it, where no mask of ``out`` is yet -- starting on the body's side, with the
    mask, from what looks otherwise than ``first_look`` saw there -- less, if ``trim``,
    the mask's pixels it gives to the background (``TRIM_SHARE``) and those under a cast
    ``shadow`` ((H, W) bool or None); None where it changes nothing. A cut that runs out
    to its box's frame is tried once more in a box ``WIDER`` times as far out: a top
    face's mark may be a small part of its body. A ``prior`` cut (one carried along a
    moving camera's model) puts its body on the body's side too. A cut that adds more
    than ``growth`` times the mask is not taken."""
    side = max(box[0].stop - box[0].start, box[1].stop - box[1].start)
    for share in (COMPLETION_REACH, WIDER * COMPLETION_REACH):
        cut, ran_out = _cut_within(label_map, label, grow_box(
            box, int(share * side) + COMPLETION_MARGIN, label_map.shape), rgb, out, first_look,
            trim, shadow, prior, growth)
        if not ran_out:
            return cut
    return None


def _cut_within(label_map: np.ndarray, label: int, around: tuple[slice, slice],
                rgb: np.ndarray, out: np.ndarray, first_look: FirstLook | None,
                trim: bool = False, shadow: np.ndarray | None = None,
                prior: _Cut | None = None, growth: float = np.inf
                ) -> tuple[_Cut | None, bool]:
    """:func:`_cut` in the image box ``around``: (the cut or None, whether it ran out to
    the box's frame)."""
    rows, cols = around
    mask = label_map[rows, cols] == label
    free = out[rows, cols] == 0  # where no mask is yet
    trimap = np.full(mask.shape, cv2.GC_BGD, np.uint8)
    f = COMPLETION_FRAME
    # the box's frame is the background's for sure, but where it is the image's border and
    # the mark reaches it (a body the view cuts; a mark inside the view that a cut takes to
    # the border took the scenery around it: 02_cups.mp4's foliage, round 62)
    edge = (rows.start == 0 and mask[0].any(), rows.stop == label_map.shape[0]
            and mask[-1].any(), cols.start == 0 and mask[:, 0].any(),
            cols.stop == label_map.shape[1] and mask[:, -1].any())  # top, bottom, left, right
    trimap[0 if edge[0] else f:mask.shape[0] if edge[1] else -f,
           0 if edge[2] else f:mask.shape[1] if edge[3] else -f] = cv2.GC_PR_BGD
    relit = None  # the scene first seen there, under a cast shadow now
    if first_look is not None:  # (another mark's pixels are not this body's)
        relit = first_look.relit(rgb, (rows, cols), first_look.known[rows, cols])
        trimap[first_look.changed(rgb, (rows, cols), relit) & (trimap == cv2.GC_PR_BGD)
               & free] = cv2.GC_PR_FGD
    if prior is not None:  # the body carried here starts on the body's side too
        trimap[_in_box(prior.body, (prior.rows, prior.cols), around)
               & (trimap == cv2.GC_PR_BGD) & free] = cv2.GC_PR_FGD
    trimap[mask] = cv2.GC_PR_FGD
    body = _grab_cut(rgb[rows, cols], trimap)
    if body is None:
        return None, False
    cast = None  # the table under a cast shadow, showing the texture first seen there
    if shadow is not None and first_look is not None:  # (tested where it could matter:
        shaded = shadow[rows, cols] & first_look.known[rows, cols]  # the mark or its growth)
        if (shaded & ((body & free) | (mask if trim else False))).any():
            cast = first_look.shows_texture(rgb, (rows, cols), shaded)
    if trim and cast is not None and (cast & mask).any():
        kept = _without_shadow(_trimmed(mask & ~cast, body), cast & mask)
    else:
        kept = _trimmed(mask, body) if trim else mask
    # the pieces of the cut that hold mask pixels, where no mask is yet
    new = pieces_holding(body & (free | kept), kept) & free
    if new.any():  # ... less the table under a shadow (the body's cast shadow is its colour),
        new &= ~_shadowed(rgb[rows, cols], free & ~new)  # by the colours around it
        if relit is not None:  # ... and by the scene first seen there (round 42)
            new &= ~relit
        if cast is not None:  # ... and by the stream's memories (round 50)
            new &= ~cast
    if not new.any():
        if kept is mask:
            return None, False
        return _Cut(rows, cols, mask, rgb[rows, cols].copy(), kept), False
    # a cut that runs out to its box's frame found no body's rest (a plain table) --
    # or the box was too small for it
    if _reaches_frame(new, edge):
        return None, True
    # one that reaches the image's border is a body the view cuts, not the table along it;
    # one that adds many times the mark took the table or wall around it
    added = np.count_nonzero(new)
    if added > growth * np.count_nonzero(mask) or (
            _reaches_frame(new) and added > BORDER_GROWTH * np.count_nonzero(mask)):
        return None, False
    return _Cut(rows, cols, mask, rgb[rows, cols].copy(), kept | new), False


def _in_box(mask: np.ndarray, at: tuple[slice, slice], box: tuple[slice, slice]
            ) -> np.ndarray:
    """(h, w) bool: the bool ``mask`` on the image box ``at`` seen on the image box ``box``
    (False outside ``at``)."""
    out = np.zeros((box[0].stop - box[0].start, box[1].stop - box[1].start), bool)
    r0, r1 = max(box[0].start, at[0].start), min(box[0].stop, at[0].stop)
    c0, c1 = max(box[1].start, at[1].start), min(box[1].stop, at[1].stop)
    if r1 > r0 and c1 > c0:
        out[r0 - box[0].start:r1 - box[0].start, c0 - box[1].start:c1 - box[1].start] = mask[
            r0 - at[0].start:r1 - at[0].start, c0 - at[1].start:c1 - at[1].start]
    return out


def _unshadowed(cut: _Cut, label_map: np.ndarray, label: int, rgb: np.ndarray,
                first_look: FirstLook | None) -> _Cut:
    """A carried ``cut`` less the pixels it adds to the mark ``label`` of ``label_map``
    that show the table under a shadow in the (H, W, 3) uint8 frame ``rgb`` now, as
    :func:`_cut_within` leaves them out (by the colours around them and, given
    ``first_look``, by the scene first seen there)."""
    rows, cols = cut.rows, cut.cols
    added = cut.body & (label_map[rows, cols] != label)
    if not added.any():
        return cut
    drop = _shadowed(rgb[rows, cols], ~cut.body)
    if first_look is not None:
        drop |= first_look.relit(rgb, (rows, cols), first_look.known[rows, cols])
    drop &= added
    if not drop.any():
        return cut
    return _Cut(rows, cols, cut.mask, cut.rgb, cut.body & ~drop, followed=True)


def _without_shadow(kept: np.ndarray, shadow: np.ndarray) -> np.ndarray:
    """(h, w) bool ``kept`` less its thin parts (those an opening by ``SHADOW_RIM`` px
    removes) within ``SHADOW_RIM`` px of the (h, w) bool ``shadow`` it lost: the rim of a
    cast shadow, whose hard edges the shadow test misses."""
    square = np.ones((SHADOW_RIM, SHADOW_RIM), np.uint8)
    thin = kept & ~(cv2.morphologyEx(kept.view(np.uint8), cv2.MORPH_OPEN, square) > 0)
    return kept & ~(thin & (cv2.dilate(shadow.view(np.uint8), square) > 0))


def _trimmed(mask: np.ndarray, body: np.ndarray) -> np.ndarray:
    """(h, w) bool ``mask`` less its pixels outside the cut's ``body`` ((h, w) bool), in
    pieces an opening by ``TRIM_OPEN`` px keeps, when they are under ``TRIM_SHARE`` of it
    (``mask`` itself otherwise)."""
    gone = mask & ~body
    if not gone.any() or np.count_nonzero(gone) >= TRIM_SHARE * np.count_nonzero(mask):
        return mask
    gone = cv2.morphologyEx(gone.view(np.uint8), cv2.MORPH_OPEN,
                            np.ones((TRIM_OPEN, TRIM_OPEN), np.uint8)) > 0
    return mask & ~gone if gone.any() else mask


class CutMemory:
    """The cuts found for the marks at rest at the last frame (one stream).

    GrabCut's answer for a mark depends on the mark's exact outline and on its colour
    models' random start: on a block at rest whose mark changed by a few pixels from frame
    to frame, one frame's cut found the block's other face and the next found nothing. A
    body that has not moved, under an image that has not changed, is where it was: the cut
    found for its mark is used again while the mark overlaps the one it was found for by
    ``RECALL_IOU`` and at most ``RECALL_CHANGED`` of the body's pixels changed by more
    than ``RECALL_LEVEL`` grey levels (a hand passing in front, the camera moving) -- and
    spares the cut's milliseconds. Under a moving camera, :meth:`follow` carries the cuts
    along the static world's model; such a cut is recalled on looser tests (``FOLLOW_*``)
    and, where a new cut finds less of its body, seeds another (:func:`complete_masks`),
    which it stands in for only where that one finds nothing.
    """

    def __init__(self) -> None:
        self._cuts: dict[int, _Cut] = {}

    def recall(self, label_map: np.ndarray, label: int, box: tuple[slice, slice],
               rgb: np.ndarray) -> _Cut | None:
        """The cut found for ``label`` at the last frame, if its mask (box ``box`` in the
        (H, W) ``label_map``) and the (H, W, 3) uint8 image ``rgb`` still fit it."""
        cut = self._cuts.get(label)
        if cut is None or not _inside(box, (cut.rows, cut.cols)):
            return None
        mask = label_map[cut.rows, cut.cols] == label
        now = rgb[cut.rows, cut.cols]
        if cut.followed:  # the mark still lies on the body carried here, which looks as it
            ring = np.ones((3, 3), np.uint8)  # did within one px
            near = cv2.dilate(cut.body.view(np.uint8), ring) > 0
            area = np.count_nonzero(mask)
            if (np.count_nonzero(mask & near) < FOLLOW_INSIDE * area
                    or area < FOLLOW_AREA * np.count_nonzero(cut.mask)):
                return None
            change = cv2.max(cv2.subtract(cv2.erode(cut.rgb, ring), now),
                             cv2.subtract(now, cv2.dilate(cut.rgb, ring))).max(axis=2)
        else:
            if np.count_nonzero(mask & cut.mask) < RECALL_IOU * np.count_nonzero(mask | cut.mask):
                return None
            change = cv2.absdiff(now, cut.rgb).max(axis=2)
        change = change[cut.body]
        if np.count_nonzero(change > RECALL_LEVEL) > RECALL_CHANGED * change.size:
            return None
        return cut

    def follow(self, world: np.ndarray) -> None:
        """Carry the cuts to the current frame of a moving camera along the static world's
        model (``world``: (H, W, 2) float32, :func:`motionbits.camera.world_maps`): a body
        at rest moves with the static world. Each cut's box moves by its pixels' median
        motion (grown by ``FOLLOW_MARGIN`` px, clipped to the frame); its masks are carried
        to the nearest pixel, its image bilinearly. A cut carried off the frame is
        forgotten."""
        h, w = world.shape[:2]
        xs, ys = pixel_grid(h, w)
        carried = {}
        for label, cut in self._cuts.items():
            y0, x0 = cut.rows.start, cut.cols.start
            came = world[cut.rows, cut.cols]
            dy = int(round(float(np.median(ys[cut.rows, cut.cols] - came[..., 1]))))
            dx = int(round(float(np.median(xs[cut.rows, cut.cols] - came[..., 0]))))
            m = FOLLOW_MARGIN
            rows = slice(max(y0 + dy - m, 0), min(cut.rows.stop + dy + m, h))
            cols = slice(max(x0 + dx - m, 0), min(cut.cols.stop + dx + m, w))
            if rows.stop - rows.start < 2 or cols.stop - cols.start < 2:
                continue
            at = world[rows, cols] - np.array([x0, y0], np.float32)  # in the old box
            body, mask = (cv2.remap(a.view(np.uint8), at, None, cv2.INTER_NEAREST,
                                    borderMode=cv2.BORDER_CONSTANT, borderValue=0) > 0
                          for a in (cut.body, cut.mask))
            if body.any():
                carried[label] = _Cut(rows, cols, mask, cv2.remap(
                    cut.rgb, at, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE),
                    body, followed=True)
        self._cuts = carried

    def keep(self, cuts: dict[int, _Cut]) -> None:
        """Remember these cuts (label -> cut) instead of the last frame's."""
        self._cuts = cuts


class FirstLook:
    """Each pixel's look when it was first seen standing still and unlabelled (one
    stream): the scene before anything moved there.

    Unlike :class:`motionbits.arrivals.Arrivals`' memory it is never overwritten: a body
    set down keeps differing from it however long it rests, and so do the faces of a
    body that its motion did not mark.

    Args:
        shape: (H, W) of the working frames.
        covered: grey levels (``WINDOW`` mean, largest channel) by which a pixel must
            differ from its first look to look otherwise (config ``reveal_covered``).
        tolerance: grey levels (``WINDOW`` mean) within which a shadow leaves the first
            look's texture, dimmed (config ``reveal_tolerance``; :meth:`relit`).
    """

    def __init__(self, shape: tuple[int, int], covered: float, tolerance: float) -> None:
        self.covered, self.tolerance = covered, tolerance
        self.look = np.zeros((*shape, 3), np.uint8)
        self.known = np.zeros(shape, bool)
        # id -> (box, mark in it) of the marks found by :meth:`uncovered` at the last frame
        self._uncovered: dict[int, tuple[tuple[slice, slice], np.ndarray]] = {}

    def update(self, cur: np.ndarray, calm: np.ndarray, labels: np.ndarray) -> None:
        """Remember the (H, W, 3) uint8 frame ``cur`` where it is seen for the first
        time standing still (``calm``, (H, W) bool) and unlabelled (``labels``, (H, W)
        int32)."""
        first = calm & (labels == 0) & ~self.known
        cv2.copyTo(cur, first.view(np.uint8), self.look)
        self.known |= first

    def follow(self, world: np.ndarray) -> None:
        """Carry the memory along a moving camera (``world``, (H, W, 2) float32,
        ``CameraMotion.world``), as :meth:`motionbits.arrivals.Arrivals.follow` does."""
        self.look = follow_look(self.look, world)
        self.known = follow_known(self.known, world)

    def as_first_seen(self, label_map: np.ndarray, rgb: np.ndarray,
                      moved: Collection[int] = ()) -> np.ndarray:
        """Ids of the marks that stand where and as they were first seen: the first look
        knows ``FIRST_SEEN_KNOWN`` of the mark's pixels and at most ``FIRST_SEEN_CHANGED``
        of those look otherwise now (:meth:`changed`). Nothing moved there.

        Args:
            label_map: (H, W) int32 marks (0 = background).
            rgb: (H, W, 3) uint8 current frame.
            moved: marks whose body is known to have moved since its birth (its own
                motion explains its pixels better than the static world's,
                :func:`motionbits.retirement.moved_marks`): never among them. A uniform
                block nudged less than its size looks much as first seen.

        Returns:
            (K,) int64 ids, ascending.
        """
        box = nonzero_box(label_map)
        labels = label_map[box].ravel()
        if not labels.size:
            return np.zeros(0, np.int64)
        area = np.bincount(labels)
        seen = np.bincount(labels[self.known[box].ravel()], minlength=area.size)
        candidate = (area > 0) & (seen >= FIRST_SEEN_KNOWN * area)
        candidate[0] = False
        candidate[[i for i in moved if i < candidate.size]] = False
        if not candidate.any():
            return np.zeros(0, np.int64)
        differs = self._differs(rgb, box)
        # a shadow only where the first look's texture shows through it too: a grey body
        # on a grey table is darker than the table, but it is not the table (both tested
        # only at the pixels they decide, of the marks the first look knows well enough:
        # the windowed median is the costly part)
        relit = self.relit(rgb, box, differs & candidate[label_map[box]])
        if relit.any():
            near = grow_box(nonzero_box(relit), TEXTURE_REACH, relit.shape)
            rows = slice(box[0].start + near[0].start, box[0].start + near[0].stop)
            cols = slice(box[1].start + near[1].start, box[1].start + near[1].stop)
            relit[near] &= self.texture_kept(rgb, (rows, cols))
        changed = np.bincount(labels[(differs & ~relit).ravel()], minlength=area.size)
        same = candidate & (changed <= FIRST_SEEN_CHANGED * seen)
        return np.flatnonzero(same)

    def uncovered(self, label_map: np.ndarray, rgb: np.ndarray,
                  candidates: Collection[int]) -> list[int]:
        """Ids among ``candidates`` whose marks show the surface around them where the
        first look saw something else: the table a body at rest when first seen has left
        (a smeared flow's MotionBit born in its wake stays there). The mark's mean colour
        is within ``SURROUND_DIFFERENCE`` of its unlabelled surroundings' (on every
        channel), and the first look's, over the ``UNCOVERED_KNOWN`` share or more of the
        mark that it knows, at least that far and ``UNCOVERED_CONTRAST`` times as far as
        the mark's. A mark found so stays found while it stays among ``candidates`` and
        overlaps the mark found at the last frame by ``UNCOVERED_IOU`` (its outline, and
        with it its colour, changes from frame to frame; an id that now stands for another
        group of MotionBits is judged again).

        Args:
            label_map: (H, W) int32 marks (0 = background).
            rgb: (H, W, 3) uint8 current frame.
            candidates: ids of the marks at rest.

        Returns:
            The ids, ascending.
        """
        boxes = label_boxes(label_map)
        found = {}
        for i in sorted(i for i in candidates if 0 < i <= len(boxes) and boxes[i - 1]):
            box = boxes[i - 1]
            mark = label_map[box] == i
            if i in self._uncovered and _iou(self._uncovered[i], (box, mark)) >= UNCOVERED_IOU:
                found[i] = (box, mark)
                continue
            known = self.known[box] & mark
            if np.count_nonzero(known) < UNCOVERED_KNOWN * np.count_nonzero(mark):
                continue
            around = surroundings_colour(rgb, label_map, box, mark)
            if around is None:
                continue
            now = np.abs(rgb[box][mark].mean(axis=0) - around).max()
            then = np.abs(self.look[box][known].mean(axis=0) - around).max()
            if now < SURROUND_DIFFERENCE and then >= max(SURROUND_DIFFERENCE,
                                                          UNCOVERED_CONTRAST * now):
                found[i] = (box, mark)
        self._uncovered = found
        return sorted(found)

    def changed(self, rgb: np.ndarray, box: tuple[slice, slice], relit: np.ndarray
                ) -> np.ndarray:
        """(h, w) bool: pixels of the image box ``box`` of the (H, W, 3) uint8 frame
        ``rgb`` that look otherwise than first seen, other than by a cast shadow (``relit``,
        (h, w) bool, from :meth:`relit` at least where they differ)."""
        return self._differs(rgb, box) & ~relit

    def _differs(self, rgb: np.ndarray, box: tuple[slice, slice]) -> np.ndarray:
        """(h, w) bool: known pixels of the box that differ from their first look by more
        than ``covered`` (``WINDOW`` mean, largest channel), shadow or not."""
        return self.known[box] & (_color_difference(rgb[box], self.look[box]) > self.covered)

    def relit(self, rgb: np.ndarray, box: tuple[slice, slice], where: np.ndarray
              ) -> np.ndarray:
        """(h, w) bool: pixels of the image box ``box`` of the (H, W, 3) uint8 frame
        ``rgb``, among those ``where`` ((h, w) bool; the others are False), that look as
        first seen under a cast shadow: the same chromaticity within ``SHADOW_CHROMA`` at
        a fraction ``SHADOW_GAIN`` of the brightness (``SHADOW_WINDOW`` means). Loose on
        purpose: a body of the table's colour, darker, passes it too
        (:meth:`texture_kept` tells them apart, for :meth:`as_first_seen`); where a
        shadow may be, completion and the arrivals' search do not grow (a moving camera's
        shadows fail the texture test in part, at their hard edges and where the followed
        first look is off by a pixel)."""
        window = (SHADOW_WINDOW, SHADOW_WINDOW)
        chroma, gain, _, _ = light_change(cv2.blur(rgb[box], window)[where],
                                          cv2.blur(self.look[box], window)[where])
        relit = where.copy()
        relit[where] = ((chroma < SHADOW_CHROMA) & (gain > SHADOW_GAIN[0])
                        & (gain < SHADOW_GAIN[1]))
        return relit

    def shows_texture(self, rgb: np.ndarray, box: tuple[slice, slice], shadow: np.ndarray
                      ) -> np.ndarray:
        """(h, w) bool: the pieces of ``shadow`` ((h, w) bool, in the image box ``box``)
        through which the (H, W, 3) uint8 frame ``rgb`` shows the texture first seen there,
        dimmed or not: of a piece's pixels where the first look has texture (grey levels'
        standard deviation over ``SHADOW_TEXTURE`` within ``TEXTURE_WINDOW`` px), at least
        ``SHOWN_SHARE`` have both images' grey levels correlated by ``SHOWN_CORRELATION``
        or more there. A shadow dims a texture and keeps it (but for the window that
        straddles its hard edge); a body's dark, speckled face over it has a texture of its
        own."""
        now = cv2.cvtColor(rgb[box], cv2.COLOR_RGB2GRAY).astype(np.float32)
        then = cv2.cvtColor(self.look[box], cv2.COLOR_RGB2GRAY).astype(np.float32)
        window = (TEXTURE_WINDOW, TEXTURE_WINDOW)
        mean_now, mean_then = cv2.blur(now, window), cv2.blur(then, window)
        var_now = cv2.blur(now * now, window) - mean_now * mean_now
        var_then = cv2.blur(then * then, window) - mean_then * mean_then
        covariance = cv2.blur(now * then, window) - mean_now * mean_then
        textured = shadow & (var_then > SHADOW_TEXTURE ** 2)
        shown = textured & (covariance > SHOWN_CORRELATION
                            * np.sqrt(np.maximum(var_now * var_then, 1e-6)))
        n, pieces = cv2.connectedComponents(shadow.view(np.uint8), connectivity=8)
        votes = np.bincount(pieces[textured], minlength=n)
        agree = np.bincount(pieces[shown], minlength=n)
        taken = (votes > 0) & (agree >= SHOWN_SHARE * votes)
        taken[0] = False
        return taken[pieces]

    def texture_kept(self, rgb: np.ndarray, box: tuple[slice, slice]) -> np.ndarray:
        """(h, w) bool: where the first look's texture shows through the (H, W, 3) uint8
        frame ``rgb`` in the image box ``box``, dimmed by the ratio of brightness of most
        of the ``SHADOW_WINDOW`` window (its median, in steps of 1/``GAIN_LEVELS``: a hard
        shadow edge in the window is no change of texture, as a window mean would read;
        :func:`motionbits.revealed.texture_shows`)."""
        sum_now, sum_then = brightness(rgb[box]), brightness(self.look[box])
        levels = np.clip(gain_of(sum_now, sum_then) * GAIN_LEVELS, 0, 255).astype(np.uint8)
        gain = cv2.medianBlur(levels, SHADOW_WINDOW).astype(np.float32) / GAIN_LEVELS
        return texture_shows(sum_now, sum_then, gain, self.tolerance)


def _iou(a: tuple[tuple[slice, slice], np.ndarray],
         b: tuple[tuple[slice, slice], np.ndarray]) -> float:
    """Intersection over union of two masks, each as (image box, bool mask in it)."""
    (ra, ca), ma = a
    (rb, cb), mb = b
    box = (slice(min(ra.start, rb.start), max(ra.stop, rb.stop)),
           slice(min(ca.start, cb.start), max(ca.stop, cb.stop)))
    first, second = _in_box(ma, (ra, ca), box), _in_box(mb, (rb, cb), box)
    union = np.count_nonzero(first | second)
    return np.count_nonzero(first & second) / union if union else 0.0


def _inside(box: tuple[slice, slice], outer: tuple[slice, slice]) -> bool:
    """Whether the (rows, cols) ``box`` lies within ``outer``."""
    return (box[0].start >= outer[0].start and box[0].stop <= outer[0].stop
            and box[1].start >= outer[1].start and box[1].stop <= outer[1].stop)


def _reaches_frame(new: np.ndarray,
                   edge: tuple[bool, bool, bool, bool] = (False, False, False, False)) -> bool:
    """Whether the (h, w) bool pixels ``new`` come within one px of the box's frame (its
    outermost ``COMPLETION_FRAME`` px, the background's for sure), but on the sides
    ``edge`` (top, bottom, left, right: the image's border, where the mark reaches it)."""
    reach = COMPLETION_FRAME + 1
    return bool((not edge[0] and new[:reach].any()) or (not edge[1] and new[-reach:].any())
                or (not edge[2] and new[:, :reach].any())
                or (not edge[3] and new[:, -reach:].any()))


def _open_outline(label_map: np.ndarray, label: int, box: tuple[slice, slice],
                  gradient: np.ndarray) -> bool:
    """Whether at least ``OPEN_OUTLINE_SHARE`` of the outline of mask ``label`` runs where
    the image shows no edge (gradient under ``EDGELESS_GRADIENT``): the mask stops inside
    its body."""
    return bool(np.mean(outline_gradient(label_map, label, box, gradient)
                        < EDGELESS_GRADIENT) >= OPEN_OUTLINE_SHARE)


def _shadowed(rgb: np.ndarray, background: np.ndarray) -> np.ndarray:
    """(h, w) bool: pixels of ``rgb`` (h, w, 3) uint8 that look like the ``background``
    pixels (h, w) bool within ``COMPLETION_SHADOW_WINDOW`` px of them, under a shadow: the
    same chromaticity (each of red and green over the sum of the three, within
    :data:`motionbits.revealed.SHADOW_CHROMA`) at a fraction of their brightness in
    :data:`motionbits.revealed.SHADOW_GAIN` -- a shadow dims the light on a surface, not
    its colour."""
    light = rgb.astype(np.float32) + 1.0
    total = light.sum(axis=2)
    weight = background.astype(np.float32)
    window = (COMPLETION_SHADOW_WINDOW, COMPLETION_SHADOW_WINDOW)
    seen = cv2.blur(weight, window)
    near = seen > 0.05
    seen += 1e-6
    shadow = near.copy()
    for c in range(2):
        chroma = light[..., c] / total
        around = cv2.blur(chroma * weight, window) / seen
        shadow &= np.abs(chroma - around) < SHADOW_CHROMA
    around = cv2.blur(total * weight, window) / seen
    return shadow & (total > SHADOW_GAIN[0] * around) & (total < SHADOW_GAIN[1] * around)


def _grab_cut(rgb: np.ndarray, trimap: np.ndarray) -> np.ndarray | None:
    """(h, w) bool: GrabCut's foreground on ``rgb`` (h, w, 3) uint8 from the (h, w) uint8
    ``cv2.GC_*`` trimap, run at most ``COMPLETION_SIDE`` px on a side; None where it
    cannot run (no background or no foreground pixels to model)."""
    h, w = trimap.shape
    scale = min(1.0, COMPLETION_SIDE / max(h, w))
    image = np.ascontiguousarray(rgb)
    if scale < 1.0:
        size = (max(int(round(w * scale)), 1), max(int(round(h * scale)), 1))
        image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
        small = cv2.resize(trimap, size, interpolation=cv2.INTER_NEAREST)
    else:
        small = trimap.copy()
    fg = (small == cv2.GC_PR_FGD) | (small == cv2.GC_FGD)
    if not fg.any() or fg.all():
        return None
    # GrabCut seeds its colour models by k-means++ from OpenCV's global random generator:
    # seeded here, the same frames give the same marks in any order and process (this
    # resets that generator for any other user of it in the process)
    cv2.setRNGSeed(0)
    try:
        cv2.grabCut(image, small, None, np.zeros((1, 65)), np.zeros((1, 65)),
                    COMPLETION_ITERATIONS, cv2.GC_INIT_WITH_MASK)
    except cv2.error:  # too few samples for a colour model
        return None
    if scale < 1.0:
        small = cv2.resize(small, (w, h), interpolation=cv2.INTER_NEAREST)
    return (small == cv2.GC_PR_FGD) | (small == cv2.GC_FGD)
