"""Did a MotionBit really move? Its origin image against its accumulated motion (ours).

A MotionBit can be born where the flow moved and the world did not: in the wake of an arm
sweeping in front of a wall, under smeared flow beside a fast body. Such a MotionBit then
stops, and a stopped MotionBit keeps its mask -- so it would stay for good. The test that
tells it from a body that really moved and stopped: keep the frame before its birth, and
the motion accumulated since (current -> that frame) both of the MotionBit and of the
static world (the camera's motion; identity for a static camera). If the world's motion
explains the MotionBit's pixels today clearly better than its own accumulated motion does,
it never moved: it is retired.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable
from dataclasses import dataclass

import cv2
import numpy as np

from motionbits.boxes import grow_box, label_areas, label_boxes, nonzero_box, run_counts
from motionbits.evidence import photometric_residual
from motionbits.masks import drop_labels
from motionbits.merging import STILL
from motionbits.revealed import StaticMemory
from motionbits.twists import rigid_matrix

__all__ = ["APART_CELLS", "NEAR_WORLD", "OWN_SHARE", "Origin", "origin_residuals", "moved_once",
           "moved_marks", "retire", "retire_shadows", "CarriedBodies", "BODY_CELLS",
           "BODY_SOLID_CELLS", "BODY_SHARE", "BODY_NEW_SHARE"]

#: px: below this median distance between where a MotionBit's own and the world's
#: accumulated motions put its pixels, the two cannot be told apart (no verdict).
MIN_SEPARATION = 2.0
#: About this many of a MotionBit's pixels measure that distance.
SEPARATION_SAMPLES = 200
IDENTITY = np.eye(3)
#: A moving MotionBit more than this share of whose pixels show the static world under a
#: shadow is a moving cast shadow, not a body ...
SHADOW_SHARE = 0.3
#: ... if it first moved at most this many frames ago: an older one has shown it is a body
#: (a body pushed in the agent's shadow looks like one) ...
SHADOW_AGE = 5
#: ... unless more than this share of it shows a shadow: a shadow that stood where the
#: memory never saw the static world lit (the arm's shadow on the wall at the first
#: frame) reads as one only once it has moved onto wall seen lit. On seeds 0 and 11 (70 +
#: 60 robot / hand scenes) an arm's dark link read up to 0.38, wall shadows 0.5-0.6.
OLD_SHADOW_SHARE = 0.5
#: A MotionBit found to be a moving cast shadow keeps the body it carried with its shadow
#: (:class:`CarriedBodies`): what is left of it without the pixels that look shadowed or
#: show the remembered colour, once opened by a square of ``BODY_SOLID_CELLS`` grid cells,
#: if that keeps ``BODY_SHARE`` of it and covers at least ``BODY_CELLS`` grid cells ...
BODY_SOLID_CELLS = 1
BODY_SHARE = 0.5
BODY_CELLS = 8
#: ... more than this share of it looks unlike the static world last seen there, and its
#: MotionBit's motion explains it better than standing still.
BODY_NEW_SHARE = 0.5
#: Grid cells around a MotionBit born at the last frame, now at rest, within which no
#: MotionBit may move for its one frame of motion to stand (:func:`moved_once`) ...
APART_CELLS = 7.5
#: ... or, where one does (the agent that knocked it, still beside it), its pixels beyond
#: that reach are judged alone if they are at least this share of it: a block knocked
#: beside the hand is born joined with the smeared flow or the shadow between them, and
#: until round 37 the whole MotionBit died unconfirmed (round 37, docs/reading_the_paper.md,
#: "Births need visible motion, twice") ...
OWN_SHARE = 0.25
#: ... and the static world must then explain them worse by this factor of
#: ``explained`` (config ``carry_tolerance``): beside a moving agent its wake and its
#: pieces left behind are the usual confusers, and the world explains those about as
#: well as the bound (round 37: 12.9-13.9 grey levels, against 25-61 for knocked blocks).
NEAR_WORLD = 2.0


@dataclass
class Origin:
    """Where a MotionBit came from.

    Attributes:
        frame: (H, W) float32 grey frame before its birth (shared, never modified).
        body: (3, 3) accumulated backward motion of the MotionBit (current -> birth frame).
        world: (3, 3) accumulated backward motion of the static world.
        moved: whether, at the last frame :func:`retire` judged it, its own motion
            explained its pixels (within ``explained``) better than the static world's
            did, by more than ``margin``, and the world's did not (worse than
            ``NEAR_WORLD`` x ``explained``): the body moved since its birth. (Round 58:
            a block nudged 1.8 cm read 29-36 grey levels by the world, a static cylinder
            whose birth frame had the hand beside it 14-16.)
    """

    frame: np.ndarray
    body: np.ndarray
    world: np.ndarray
    moved: bool = False

    def advance(self, body_step: np.ndarray, world_step: np.ndarray) -> None:
        """Compose one more frame's (3, 3) backward motions (current -> previous)."""
        self.body = self.body @ body_step
        self.world = self.world @ world_step


def _residual(frame: np.ndarray, motion: np.ndarray, cur: np.ndarray, box, inside) -> float:
    """Mean |cur - frame pulled back by ``motion``| over ``inside`` of the image box ``box``
    (NaN if less than half of those pixels come from inside ``frame``)."""
    if np.array_equal(motion, IDENTITY):  # a static camera's world: the box itself (the
        diff = np.abs(cur[box] - frame[box])[inside]  # bilinear warp gives the same)
        return float(diff.mean())
    to_frame = motion @ np.array(
        [[1.0, 0.0, box[1].start], [0.0, 1.0, box[0].start], [0.0, 0.0, 1.0]])
    size = (box[1].stop - box[1].start, box[0].stop - box[0].start)
    warped = cv2.warpPerspective(frame, to_frame, size,
                                 flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                 borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
    diff = np.abs(cur[box] - warped)[inside]
    diff = diff[np.isfinite(diff)]
    return float(diff.mean()) if diff.size > 0.5 * inside.sum() else np.nan


def origin_residuals(origin: Origin, cur_gray: np.ndarray, mask: np.ndarray,
                     min_separation: float, corner: tuple[int, int] = (0, 0)
                     ) -> tuple[float, float]:
    """Mean grey-level residuals (world, body) of the pixels ``mask`` (bool) of
    ``cur_gray`` against the origin frame pulled back by the static world's and by the
    MotionBit's accumulated motion; NaN when the two motions move its pixels less than
    ``min_separation`` px apart (nothing to tell) or its origin is out of view.

    ``mask`` is (H, W), or the image box whose top-left pixel is ``corner`` (y, x)."""
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        return np.nan, np.nan
    ys, xs = ys + corner[0], xs + corner[1]
    step = max(1, len(xs) // SEPARATION_SAMPLES)
    pts = np.stack([xs[::step], ys[::step], np.ones(len(xs[::step]))]).astype(np.float64)

    def apply(m):
        q = m @ pts
        return q[:2] / q[2]

    if np.median(np.linalg.norm(apply(origin.body) - apply(origin.world), axis=0)) < min_separation:
        return np.nan, np.nan
    box = slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1)
    inside = mask[box[0].start - corner[0]:box[0].stop - corner[0],
                  box[1].start - corner[1]:box[1].stop - corner[1]]
    return (_residual(origin.frame, origin.world, cur_gray, box, inside),
            _residual(origin.frame, origin.body, cur_gray, box, inside))


def moved_once(origins: dict[int, Origin], ids: Iterable[int], labels: np.ndarray,
               valid: np.ndarray, busy: np.ndarray, cam: np.ndarray | None,
               cur_gray: np.ndarray, reach: int, margin: float, explained: float
               ) -> set[int]:
    """Of the MotionBits ``ids`` born at the last frame that do not move now, those whose
    one frame of motion was a body's: their pixels (``labels == i`` where ``valid``) are
    explained by their own motion since the frame before their birth (mean residual
    within ``explained``), better by more than ``margin`` grey levels than by the static
    world's, which does not explain them -- :func:`retire`'s test, the other way round.
    Where a MotionBit moves now (``busy``) near the box of one, only its pixels farther
    than ``reach`` px from it are judged, if they are ``OWN_SHARE`` of it or more, and
    the world must then explain them worse than ``NEAR_WORLD`` x ``explained``.

    A block knocked across the table moves for a frame or two and stops; a MotionBit born
    the frame before in a moving agent's wake, or a piece of the agent, stands beside the
    agent, and the world explains a flicker of the flow.

    Args:
        origins: id -> its :class:`Origin` at the last frame (not changed here).
        ids: the candidate ids.
        labels: (H, W) int32 label map carried from the last frame.
        valid: (H, W) bool, where the carried labels hold.
        busy: (H, W) bool, the pixels of the MotionBits that move now (their nodes').
        cam: (3, 3) camera motion of this frame (current -> previous) or None (static).
        cur_gray: (H, W) float32 current grey frame.
        reach: px.
        margin, explained: grey levels (config ``retire_margin``, ``carry_tolerance``).

    Returns:
        The ids whose motion stands.
    """
    world = np.eye(3) if cam is None else cam
    moved = set()
    far = None  # (H, W) bool, farther than reach from every busy pixel (once needed)
    for i in ids:
        origin = origins.get(int(i))
        if origin is None:
            continue
        mask = (labels == i) & valid
        box = nonzero_box(mask)
        if box[0].start == box[0].stop:
            continue
        bound = explained
        if busy[grow_box(box, reach, mask.shape)].any():
            if far is None:
                far = cv2.distanceTransform((~busy).view(np.uint8), cv2.DIST_L2, 5) > reach
            own = mask & far
            if np.count_nonzero(own) < OWN_SHARE * np.count_nonzero(mask):
                continue
            mask, bound = own, NEAR_WORLD * explained
        # it stands still now: both accumulated motions advance by the world's
        at_rest = Origin(origin.frame, origin.body @ world, origin.world @ world)
        world_res, body_res = origin_residuals(at_rest, cur_gray, mask, MIN_SEPARATION)
        if world_res > bound and body_res < explained and world_res - body_res > margin:
            moved.add(int(i))
    return moved


def retire(labels: np.ndarray, origins: dict[int, Origin], ids: np.ndarray,
           thetas: np.ndarray, trans: np.ndarray, first_new: int, cam: np.ndarray | None,
           prev_gray: np.ndarray, cur_gray: np.ndarray, margin: float, *,
           explained: float = np.inf, first: Origin | None = None
           ) -> tuple[np.ndarray, dict[int, Origin]]:
    """Advance every MotionBit's origin by this frame's motions and retire those whose
    pixels the static world explains -- within ``explained`` grey levels (mean residual),
    from the frame before the MotionBit's birth or from the stream's first frame
    (``first``) -- and better, by more than ``margin`` grey levels, than their own
    accumulated motion (:func:`origin_residuals`). Where no frame explains them (a body
    carried and set down: the fitted motion of a body lowered in depth drifts, and the
    static world shows what was there before it arrived) the MotionBit stays; the first
    frame still explains background that an arm covered at a MotionBit's birth. Each
    origin that stays records whether the MotionBit's own motion explained it better
    (:attr:`Origin.moved`).

    Args:
        labels: (H, W) int32 label map of this frame.
        origins: id -> its :class:`Origin`, from the last frame (the Origins are advanced
            in place).
        ids: (K,) ids with a cluster now, backward motions ``thetas`` (K,), ``trans`` (K, 2)
            (relative to the camera); an id without one moves with the world.
        first_new: ids from this one on were born now: their origin is ``prev_gray``.
        cam: (3, 3) camera motion of this frame (current -> previous) or None (static).
        prev_gray: (H, W) float32 previous grey frame (not stabilised).
        cur_gray: (H, W) float32 current grey frame.
        margin: grey levels (config ``retire_margin``).
        explained: grey levels (config ``carry_tolerance``).
        first: the stream's first frame with the static world's motion since (its ``body``
            is not used; advanced in place), or None.

    Returns:
        ``labels`` without the retired MotionBits, and the origins of those present.
    """
    world = np.eye(3) if cam is None else cam
    own = {int(i): world @ np.vstack([rigid_matrix(th, t), [0.0, 0.0, 1.0]])
           for i, th, t in zip(ids, thetas, trans)}
    boxes = {i + 1: box for i, box in enumerate(label_boxes(labels)) if box}
    origins = {i: o for i, o in origins.items() if i in boxes}
    out = labels
    if first is not None:
        first.advance(world, world)
    for i, box in boxes.items():
        if i >= first_new:
            origins[i] = Origin(prev_gray, np.eye(3), np.eye(3))
        origin = origins.get(i)
        if origin is None:
            continue
        origin.advance(own.get(i, world), world)
        mask = labels[box] == i
        world_res, body_res = origin_residuals(origin, cur_gray, mask, MIN_SEPARATION,
                                               (box[0].start, box[1].start))
        if first is not None and np.isfinite(body_res):
            from_first = _residual(first.frame, first.world, cur_gray, box, mask)
            if np.isnan(world_res) or from_first < world_res:  # NaN: out of view then
                world_res = from_first
        if world_res < explained and world_res - body_res < -margin:
            out = np.where(out == i, 0, out)
            del origins[i]
        else:  # (False where either is NaN; the world's bound as beside a moving agent)
            origin.moved = bool(body_res < explained and world_res > NEAR_WORLD * explained
                                and world_res - body_res > margin)
    return out, origins


def moved_marks(shown: np.ndarray, labels: np.ndarray, origins: dict[int, Origin],
                moving: Collection[int]) -> set[int]:
    """The marks that bodies at rest now, known to have moved since their birth
    (:attr:`Origin.moved`), hold most of (an arm stopped at a clip's last frame has moved
    too, and its group's mark may hold mostly the table it left: that mark is not one).

    Args:
        shown: (H, W) int32 marks shown (0 = none).
        labels: (H, W) int32 label map of the MotionBits.
        origins: id -> its :class:`Origin` (after :func:`retire`).
        moving: ids of the MotionBits moving now (not counted).

    Returns:
        The labels of ``shown`` of which more than half the pixels are such MotionBits'.
    """
    moved = [i for i, origin in origins.items() if origin.moved and i not in moving]
    if not moved:
        return set()
    box = nonzero_box(shown)  # (on the marks' box only: this runs every frame)
    marks = shown[box]
    held = np.bincount(marks[np.isin(labels[box], moved) & (marks > 0)])
    if not held.any():
        return set()
    area = np.bincount(marks.ravel(), minlength=held.size)[:held.size]
    return {int(i) for i in np.flatnonzero(2 * held > area)}


@dataclass(frozen=True)
class CarriedBodies:
    """The bodies that MotionBits found to be moving cast shadows carried (ours, round 61).

    A block carried or pushed low over the table moves with its own shadow, and the flow
    clusters both into one MotionBit; once the shadow is most of it, the whole MotionBit
    was retired as a cast shadow, the block with it (held30: a carried block of 6,756 px
    gone at the clip's last frame). What is left of such a MotionBit without the pixels
    that show the remembered colour (under the shadow or another light) stays a MotionBit
    when it is a body: solid, unlike the static world last seen there, and moved by the
    MotionBit's motion. A shadow's own leftovers (its penumbra, the table it has just left,
    of the table's colour) are none of these; a body of the table's colour is retired with
    its shadow, as before.

    Args:
        cell: (w, h) px of one grid cell.
        cur, prev: (H, W) float32 grey frames (``prev`` camera-stabilised).
        ids, thetas, trans: (K,) ids with a cluster now and their backward motions (K,),
            (K, 2) (relative to the camera).
        evidence: grey levels (3x3 mean, config ``pixel_evidence``) by which the motion
            must explain the body better than standing still.
    """

    cell: tuple[float, float]
    cur: np.ndarray
    prev: np.ndarray
    ids: np.ndarray
    thetas: np.ndarray
    trans: np.ndarray
    evidence: float

    def body(self, rest: np.ndarray, lab: int, box: tuple[slice, slice],
             changed: np.ndarray) -> np.ndarray | None:
        """The body in ``rest`` ((h, w) bool on the image ``box``: MotionBit ``lab``'s
        pixels that do not look like the static world under a shadow or another light), or
        None. ``changed``: (H, W) bool, pixels that look unlike the static world last seen
        there (:meth:`StaticMemory.changed`)."""
        k = np.flatnonzero(self.ids == lab)
        if not len(k):
            return None
        side = max(1, int(round(BODY_SOLID_CELLS * max(self.cell))))
        body = cv2.morphologyEx(rest.view(np.uint8), cv2.MORPH_OPEN,
                                np.ones((side, side), np.uint8)) > 0
        n = np.count_nonzero(body)
        if (n < BODY_CELLS * self.cell[0] * self.cell[1]
                or n < BODY_SHARE * np.count_nonzero(rest)
                or changed[box][body].mean() <= BODY_NEW_SHARE):
            return None
        still = photometric_residual(self.cur, self.prev, STILL, box)[body].mean()
        motion = rigid_matrix(self.thetas[k[0]], self.trans[k[0]])
        moved = photometric_residual(self.cur, self.prev, motion, box)[body].mean()
        return body if still - moved > self.evidence else None


def retire_shadows(labels: np.ndarray, cur: np.ndarray, memory: StaticMemory,
                   moving: set[int], first_moved: dict[int, int], frame_index: int,
                   carried: CarriedBodies | None = None) -> np.ndarray:
    """``labels`` without the MotionBits that are moving cast shadows: MotionBits moving
    now, since at most ``SHADOW_AGE`` frames, more than ``SHADOW_SHARE`` of whose pixels
    show the static world as ``memory`` remembers it, only darker, with its colour and
    texture (:meth:`StaticMemory.shadowed`); older ones, more than ``OLD_SHADOW_SHARE``.

    An arm's shadow sweeping a table moves its edges, and the flow follows them; what is
    under it is the table, dimmed. A body that moves onto the table replaces its colour
    or its texture (a flat, darker grey on a flat grey table would pass for a shadow). A
    body that stands still under a passing shadow does not move (it is not tested); where
    the flow follows the shadow's edge across it all the same, the memory holds the body's
    own look, remembered with its id at rest, and those pixels do not count. One that has
    moved for longer has shown it is a body (it must look shadowed over more of its
    pixels). Given ``carried``, a MotionBit so found keeps the body it carried with its
    shadow (:class:`CarriedBodies`): its pixels that neither look shadowed nor show the
    remembered colour under another light (:meth:`StaticMemory.same_colour`: a shadow's
    penumbra or dark, the table a shadow has just left) and make a body; the rest of it is
    retired.

    Args:
        labels: (H, W) int32 label map of this frame.
        cur: (H, W, 3) uint8 current RGB frame.
        memory: the static world's look, between its ``observe`` and ``update``.
        moving: ids of the MotionBits moving now.
        first_moved: id -> the frame it first moved (:attr:`MotionSpans.first`).
        frame_index: this frame's index.
        carried: the test of what such a MotionBit keeps; None: nothing (retired whole).

    Returns:
        (H, W) int32 label map (``labels`` itself when nothing is retired).
    """
    if not moving:
        return labels
    young = {i for i in moving if frame_index - first_moved.get(i, frame_index) <= SHADOW_AGE}
    share = {i: SHADOW_SHARE if i in young else OLD_SHADOW_SHARE for i in moving}
    boxes = label_boxes(labels, max_label=max(moving))
    # an older one only if enough of it is darker at all (cheap; :meth:`shadowed` is not)
    tested = [i for i in moving if boxes[i - 1] is not None and (
        i in young or memory.dimmed_share(cur, labels, i, boxes[i - 1]) > OLD_SHADOW_SHARE)]
    if not tested:
        return labels
    # each tested MotionBit on its own box, or all on the box of them all where that is
    # smaller (:meth:`StaticMemory.shadowed` gives the whole image's answer, cropped)
    rows, cols = zip(*(boxes[i - 1] for i in tested))
    union = (slice(min(r.start for r in rows), max(r.stop for r in rows)),
             slice(min(c.start for c in cols), max(c.stop for c in cols)))
    parts = ([(boxes[i - 1], [i]) for i in tested]
             if sum(_box_area(boxes[i - 1]) for i in tested) < _box_area(union)
             else [(union, tested)])
    gone = []
    out, changed = labels, None
    for box, members in parts:
        # not where the memory holds a MotionBit's own look (its body, seen at rest): the
        # flow may follow a passing shadow's edge across it
        shadow = memory.shadowed(cur, box, labels)
        if shadow is None:
            return labels
        lab = labels[box]
        area = label_areas(lab)
        dark = run_counts(lab[shadow], len(area))
        found = [i for i in members if dark[i] > share[i] * area[i]]
        if carried is None or not found:
            gone += found
            continue
        other = ~(shadow | memory.same_colour(cur, box))
        if changed is None:
            changed = memory.changed()
        for i in found:
            mine = lab == i
            body = carried.body(mine & other, i, box, changed)
            if body is None:
                gone.append(i)
                continue
            if out is labels:
                out = labels.copy()
            out[box][mine & ~body] = 0
    return drop_labels(out, gone)


def _box_area(box: tuple[slice, slice]) -> int:
    return (box[0].stop - box[0].start) * (box[1].stop - box[1].start)
