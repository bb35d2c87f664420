"""Bodies that arrived out of their motion's sight: new at rest where the static world was (ours).

:class:`motionbits.setdown.SetDown` finds a body that its carrier leaves behind while the
body's pixels still carry the carrier's label. Often they do not: a gripper that carries
a block from above hides it, and lifting away it reveals the block already at rest (no
pixel of it ever held a label that moved with it); a block knocked across the table
stops within a frame or two, before a MotionBit holds it. What is left is the evidence of
background subtraction, gated by motion: where a MotionBit passed, something other than
the static world seen there before now stands still. :class:`Arrivals` keeps, per pixel,
the look of the static world where it was last seen still and *unlabelled*, and the id of
the last MotionBit that covered the pixel since. A piece of the current frame arrived when

- the static world was seen at its pixels before a MotionBit covered them, and they now
  differ from it by more than ``covered`` grey levels (largest channel, 5x5 mean);
- it stands still (mean ``|I_t - I_t-1|`` over 5x5 below ``rest``), holds no label, is
  compact (an opening by one grid cell keeps it) and covers ``SETDOWN_CELLS`` grid cells;
- it is not the static world under other light: a cast shadow, or the end of one, keeps
  the colour (median change of chromaticity below ``LIGHT_CHROMA``) and, after one gain,
  the texture (mean residual below ``LIGHT_RESIDUAL`` grey levels);
- it is not background that a body uncovered where the memory saw only that body (a body
  at rest from the first frame, then moved away): such a piece continues the surface
  around it (its mean colour within ``SURROUND_DIFFERENCE`` on every channel of that of
  a ring of unlabelled pixels around it) while what the memory saw there did not. Where
  the memory saw the surface too, a piece that changed arrived even in the surface's
  mean colour (a pale cube set down on veined marble) -- under a still camera: once the
  memory has followed a moving camera, a piece like its surroundings never arrived.

Pieces are sought where a MotionBit passed and, within ``NEAR_CELLS`` grid cells, around
each MotionBit that stands still now. A piece beside a MotionBit that stands still, and
not larger than that MotionBit has been seen, is the rest of that body and takes its id
(a block set down is often marked only where the carrier's motion showed on it; the rest
of it stands beside that mark, unlike the table seen there before); any other piece that
lies mostly where a MotionBit passed takes the id of the MotionBit that last covered it
there, if that one stands still beside it, and else becomes a new MotionBit, confirmed at
the next frame if it still stands there (as SetDown's pieces): shown at once if it is
solid and no moving MotionBit surrounds it, else from the next frame
(:meth:`motionbits.setdown.SetDown.adopt`; docs/reading_the_paper.md,
"Bodies that arrived", round 21).

A body may also arrive where no MotionBit ever was: the flow read it moving (a block
carried under a hand whose MotionBit held the hand only), and no cluster took it. The
memory also keeps where the flow was seen moving since the static world was last seen
still there; a piece of such pixels that passes the tests above and touches no MotionBit
is a new MotionBit of its own (its parts within one grid cell are one piece, and pieces
found at one frame within ``JOIN_CELLS`` grid cells are one body). Such pieces do not
wait. docs/reading_the_paper.md, "Moving cameras", round 33. The same search takes the
pieces of the first one that a MotionBit covered in less than half and that stand beside
no MotionBit at rest, where the flow was seen moving on at least half of them and that
stand out from their surroundings as the third search asks (below; a block carried under
a gripper whose MotionBit held only its edge; round 49).

Both searches miss a body that arrived where none of them looks, and one that stood still
unlabelled for a frame: the memory then takes it for the static world. The scene's first
look (:class:`motionbits.completion.FirstLook`: each pixel as first seen still and
unlabelled, never overwritten) still tells it apart. A third search takes, unlabelled and
mostly where a MotionBit passed or the flow saw motion since the stream began (a body
arrives only where something moved), a piece that

- differs from the first look (by more than ``covered``, and not as a cast shadow: the
  same colour and texture under a smooth gain), stands still, is compact and covers
  ``SETDOWN_CELLS`` grid cells, and did so at the last frame too (a body that stopped,
  not a passing shadow or a frame of smeared flow);
- is not the first look under other light, and stands out from its unlabelled
  surroundings (mean colour, ``SURROUND_DIFFERENCE``) ``FIRST_LOOK_CONTRAST`` times as
  much as the first look did there. The table a body left continues the surface around
  it; an edge that a moving camera's model misaligns stood out in the first look too.

Such a piece beside a MotionBit that stands still, and not larger than that MotionBit
has been seen, is the rest of that body; beside none, a new MotionBit (shown as the other
arrivals are). Moving-camera pick-and-place: +2.2 / +0.6 mIoU on the two sets of seeds
it was developed on, +2.1 on five held-out seeds (docs/reading_the_paper.md, "Bodies that
arrived", round 41).

Under a moving camera the memory follows the static world's model (homography and
parallax) before each search.
It is folded in with :class:`motionbits.revealed.StaticMemory`'s pixels seen still, so it
is off when that memory is (config ``reveal_tolerance`` = 0).

Measured on the pick-and-place track (docs/reading_the_paper.md, "Bodies that arrived").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import cv2
import numpy as np

from motionbits.boxes import grow_box, label_areas, nonzero_box
from motionbits.revealed import (SHADOW_WINDOW, WINDOW, _color_difference, dimmed, follow_ids,
                                 follow_known, follow_look, light_change)
from motionbits.setdown import COMPACT_CELLS, SETDOWN_CELLS

if TYPE_CHECKING:  # completion.py imports this module
    from motionbits.completion import FirstLook

__all__ = ["Arrivals", "Arrival", "LIGHT_CHROMA", "LIGHT_RESIDUAL", "SURROUND_DIFFERENCE",
           "JOIN_CELLS", "FIRST_LOOK_CONTRAST", "surroundings_colour"]

#: Largest median change of chromaticity (each channel over the sum of the three) of a
#: piece that is the static world under other light ...
LIGHT_CHROMA = 0.06
#: ... where the remembered look times one gain (the median ratio of the brightness) also
#: matches within this mean residual (grey levels).
LIGHT_RESIDUAL = 12.0
#: A piece whose mean colour is within this (grey levels, every channel) of its
#: surroundings' continues the surface around it.
SURROUND_DIFFERENCE = 15.0
#: px, the ring of surroundings: between these distances from the piece.
SURROUND_RING = (3, 10)
#: Fewest surrounding pixels for that test (else it is not made).
SURROUND_MIN = 20
#: px: a piece within this of a MotionBit's pixels touches it.
TOUCH = 2
#: Grid cells within which pieces of a body that no MotionBit followed, found at one
#: frame, are one body (a block's faces, parted by its edges).
JOIN_CELLS = 3
#: Grid cells around a MotionBit standing still within which the rest of its body is
#: sought. Pick-and-place mIoU 42.4 -> 49.5, robot / hand 62.5 / 62.0 -> 64.1 / 63.1
#: (round 17, docs/reading_the_paper.md, "Bodies that arrived").
NEAR_CELLS = 5
#: A piece found against the first look stands out from its surroundings at least this
#: many times as much as the first look did there (module docstring; round 41).
FIRST_LOOK_CONTRAST = 3.0

#: (rows, cols) slices of an image box, the (h, w) bool piece inside it, and the id of the
#: MotionBit that last covered it.
Arrival = tuple[tuple[slice, slice], np.ndarray, int]


class Arrivals:
    """The static world seen still and unlabelled, and what covered it since.

    Each frame, :meth:`find` (before the label map is final) then :meth:`update`.

    Args:
        shape: (H, W) of the working frames.
        covered: grey levels (largest channel, ``WINDOW`` mean) by which a pixel must
            differ from the remembered static world (config ``reveal_covered``).
        rest: grey levels; a pixel is at rest when its mean ``|I_t - I_t-1|`` is below this
            (config ``carry_tolerance``).
        tolerance: grey levels; the first look under a cast shadow matches the current
            frame within this (config ``reveal_tolerance``,
            :func:`motionbits.revealed.dimmed`).
    """

    def __init__(self, shape: tuple[int, int], covered: float, rest: float,
                 tolerance: float) -> None:
        self.covered, self.rest, self.tolerance = covered, rest, tolerance
        self.background = np.zeros((*shape, 3), np.uint8)  # remembered RGB
        self.known = np.zeros(shape, bool)  # seen still and unlabelled at some frame
        self.visited = np.zeros(shape, np.int32)  # last MotionBit over it since (0: none)
        self._waiting = np.zeros(shape, bool)  # this frame's pieces still too small
        self._largest: dict[int, int] = {}  # id present -> its largest area so far (px)
        self._followed = False  # carried along a moving camera's model at some frame
        self.stirred = np.zeros(shape, bool)  # seen moving since last seen still, unlabelled
        self._unlike_first: np.ndarray | None = None  # last frame's pixels unlike the first look
        self.passed = np.zeros(shape, bool)  # covered by a MotionBit or seen moving, ever

    def follow(self, world: np.ndarray) -> None:
        """Carry the memory to the current frame of a moving camera, as
        :meth:`StaticMemory.follow` does: each pixel takes what was remembered where its
        static world was in the last frame (``world``, (H, W, 2) float32,
        ``CameraMotion.world``); it is known only where all four pixels it is read from
        were, and what has just come into view is unknown."""
        self._followed = True
        self.known = follow_known(self.known, world)
        self.background = follow_look(self.background, world)
        self.visited = follow_ids(self.visited, world)
        self.stirred = follow_ids(self.stirred.view(np.uint8), world) > 0
        if self._unlike_first is not None:
            self._unlike_first = follow_ids(self._unlike_first.view(np.uint8), world) > 0
        self.passed = follow_ids(self.passed.view(np.uint8), world) > 0

    def find(self, cur: np.ndarray, change: np.ndarray, labels: np.ndarray,
             cell: tuple[float, float], moving: set[int],
             first_look: FirstLook | None = None) -> list[Arrival]:
        """Pieces of the current frame that arrived (module docstring).

        Args:
            cur: (H, W, 3) uint8 current RGB frame.
            change: (H, W) float32 grey change since the last frame
                (:func:`motionbits.revealed.grey_change`): what stands still is under
                ``rest``.
            labels: (H, W) int32 label map of this frame.
            cell: (w, h) px of one grid cell.
            moving: ids of the MotionBits that move now.
            first_look: the scene as first seen, followed to this frame (None: no third
                search).

        Returns:
            One :data:`Arrival` per piece, in no particular order.
        """
        self._waiting[:] = False
        standing = label_areas(labels) > 0  # id -> it stands still now
        standing[0] = False
        standing[[i for i in moving if i < standing.size]] = False
        candidate = self.visited > 0
        if standing.any():  # and around the MotionBits standing still (on their box)
            reach = int(round(NEAR_CELLS * max(cell)))
            still = np.zeros(labels.shape, bool)  # on the labels' box (standing[0] is False)
            labelled = nonzero_box(labels)
            still[labelled] = np.take(standing, labels[labelled])
            box = grow_box(nonzero_box(still), reach, labels.shape)
            candidate[box] |= cv2.dilate(still[box].view(np.uint8),
                                         np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)) > 0
        candidate &= self.known & (labels == 0)
        # a body that no MotionBit followed (the flow read its motion, no cluster took it):
        # seen moving since the static world was seen there, at rest now apart from every
        # MotionBit; its pieces within JOIN_CELLS grid cells of each other are one body
        unfollowed = self.stirred & self.known & (labels == 0) & ~candidate
        searched = candidate | unfollowed
        # what stands still, once for the three searches
        at_rest = change < self.rest
        found = []
        if searched.any():
            # what looks unlike the remembered static world and stands still, once for
            # both searches, on the box of their pixels (grown by the window's reach, so
            # that its means are the whole image's)
            around = grow_box(nonzero_box(searched), WINDOW // 2, labels.shape)
            fresh = ((_color_difference(cur[around], self.background[around]) > self.covered)
                     & at_rest[around])
            for at, piece, ring in self._pieces(candidate, fresh, around, cur, labels, cell):
                body = _beside(ring, standing)
                visited = self.visited[at][piece]
                area = visited.size
                if body and area <= self._largest.get(body, 0):
                    parent = body  # the rest of the body standing beside it
                elif np.count_nonzero(visited) >= 0.5 * area:  # a MotionBit passed
                    parent = int(np.bincount(visited)[1:].argmax()) + 1
                else:
                    # seen moving where a MotionBit passed over less than half of it, and
                    # standing out where the first look did not: a body that no MotionBit
                    # followed, if it is one (the search below)
                    if (first_look is not None
                            and np.count_nonzero(self.stirred[at][piece]) >= 0.5 * area
                            and _stands_out(cur, first_look, labels, at, piece)):
                        unfollowed[at] |= piece
                    continue
                found.append((at, piece, parent))
            for at, piece, ring in self._pieces(unfollowed, fresh, around, cur, labels, cell,
                                                unfollowed=True):
                if not ring.any():
                    found.append((at, piece, 0))
        return found + self._unlike_first_look(cur, at_rest, labels, cell, standing,
                                               first_look, found)

    def _unlike_first_look(self, cur: np.ndarray, at_rest: np.ndarray, labels: np.ndarray,
                           cell: tuple[float, float], standing: np.ndarray,
                           first_look: FirstLook | None, found: list[Arrival]
                           ) -> list[Arrival]:
        """The third search (module docstring): unlabelled pieces ``at_rest`` ((H, W)
        bool), not among ``found``, mostly where something moved, that differ from
        ``first_look`` now and did at the last frame, stand out from their surroundings
        where the first look did not, and are beside no MotionBit standing still
        (``standing``: id -> bool) that is smaller (other arguments as :meth:`find`)."""
        before, self._unlike_first = self._unlike_first, None
        if first_look is None or not first_look.known.any():
            return []
        unlike = (first_look.known & (labels == 0) & at_rest
                  & (_color_difference(cur, first_look.look) > self.covered))
        for at, piece, _ in found:
            unlike[at][piece] = False
        side = max(1, int(round(COMPACT_CELLS * max(cell))))
        square = np.ones((side, side), np.uint8)
        min_area = SETDOWN_CELLS * cell[0] * cell[1]
        opened = cv2.morphologyEx(unlike.view(np.uint8), cv2.MORPH_OPEN, square)
        n, comp, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
        large = stats[1:, cv2.CC_STAT_AREA] >= min_area
        if large.any():
            # not where the first look is under a cast shadow now: tested only around the
            # pieces large enough (the shadow tests' windowed means cost more than the rest
            # of this search on the whole frame)
            x, y, w, h = stats[1:][large, :4].T
            box = grow_box((slice(y.min(), (y + h).max()), slice(x.min(), (x + w).max())),
                           SHADOW_WINDOW + side, labels.shape)
            unlike[box] &= ~first_look.relit(cur, box, unlike[box])
            unlike[box] &= ~dimmed(cur, first_look.look, first_look.known, box, self.tolerance,
                                   unlike[box])
            opened = cv2.morphologyEx(unlike.view(np.uint8), cv2.MORPH_OPEN, square)
            n, comp, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
        self._unlike_first = opened > 0
        if before is None:
            return []
        pieces = []
        for k in range(1, n):
            if stats[k, cv2.CC_STAT_AREA] < min_area:
                continue
            x, y, w, h = stats[k, :4]
            at = (slice(y, y + h), slice(x, x + w))
            piece = comp[at] == k
            area = int(stats[k, cv2.CC_STAT_AREA])
            if (np.count_nonzero(before[at][piece]) < 0.5 * area  # not there at the last frame
                    or _relit(cur[at], first_look.look[at], piece)
                    or np.count_nonzero(self.passed[at][piece]) < 0.5 * area  # nothing moved there
                    or not _stands_out(cur, first_look, labels, at, piece)):
                continue
            parent = _beside(_touching(labels, at, piece), standing)
            if parent and area > self._largest.get(parent, 0):
                continue  # larger than the body standing beside it: not its rest
            pieces.append((at, piece, parent))
        return pieces

    def _pieces(self, candidate: np.ndarray, fresh: np.ndarray, around: tuple[slice, slice],
                cur: np.ndarray, labels: np.ndarray, cell: tuple[float, float],
                unfollowed: bool = False
                ) -> list[tuple[tuple[slice, slice], np.ndarray, np.ndarray]]:
        """The pieces of ``candidate`` ((H, W) bool) that look unlike the remembered static
        world and stand still (``fresh``, (h, w) bool on the image box ``around``, which
        holds the candidates' box grown by the window's reach), are compact and large
        enough, and are neither the static world under other light nor the surface around
        them continued (module docstring); those still too small wait. For bodies no
        MotionBit followed (``unfollowed``), parts within one grid cell of each other count
        as one piece, and nothing waits. Each as (image box, (h, w) bool piece in it, (k,)
        int32 labels it touches)."""
        if not candidate.any():
            return []
        min_area = SETDOWN_CELLS * cell[0] * cell[1]
        # everything below happens on the box of the candidates
        box = grow_box(nonzero_box(candidate), WINDOW // 2, labels.shape)
        y0, x0 = box[0].start - around[0].start, box[1].start - around[1].start
        mask = (candidate[box] & fresh[y0:y0 + box[0].stop - box[0].start,
                                       x0:x0 + box[1].stop - box[1].start]).view(np.uint8)
        # a body uncovered a strip at a time grows a frame at a time: pieces too small or
        # too thin yet are not taken into the static world
        if not unfollowed:
            self._waiting[box] = mask > 0
        if cv2.countNonZero(mask) < min_area:  # no piece can be large enough
            return []
        square = np.ones((max(1, int(round(COMPACT_CELLS * max(cell)))),) * 2, np.uint8)
        opened = cv2.morphologyEx(mask, cv2.MORPH_OPEN, square)
        n, comp, stats, _ = cv2.connectedComponentsWithStats(
            cv2.dilate(opened, square) if unfollowed else opened, connectivity=8)
        pieces = []
        for k in range(1, n):
            if stats[k, cv2.CC_STAT_AREA] < min_area:
                continue
            x, y, w, h = stats[k, :4]
            piece = (comp[y:y + h, x:x + w] == k) & (opened[y:y + h, x:x + w] > 0)
            if np.count_nonzero(piece) < min_area:
                continue
            at = (slice(box[0].start + y, box[0].start + y + h),
                  slice(box[1].start + x, box[1].start + x + w))
            if not unfollowed:
                self._waiting[at][piece] = False
            if (_relit(cur[at], self.background[at], piece)
                    or _like_surroundings(cur, labels, at, piece,
                                          None if self._followed else self.background)):
                continue
            pieces.append((at, piece, _touching(labels, at, piece)))
        return pieces

    def place(self, labels: np.ndarray, arrivals: list[Arrival], moving: set[int], reach: int,
              next_id: int) -> tuple[np.ndarray, np.ndarray, dict[int, int], int]:
        """Put the pieces into the label map: a piece within ``reach`` px of the MotionBit
        that last covered it, while that MotionBit stands still, takes its id (the rest of
        that body); a piece no MotionBit followed (parent 0) within ``JOIN_CELLS * reach``
        px of another placed now takes that one's id (faces of one body); any other takes a
        new id.

        Args:
            labels: (H, W) int32 label map of this frame; changed in place.
            arrivals: from :meth:`find`.
            moving: ids of the MotionBits that move now.
            reach: px, one grid cell.
            next_id: the id the next new MotionBit gets.

        Returns:
            ``labels``, the (H, W) bool pixels placed (their ``earned`` map), the new ids
            -> the id that last covered them, and the next ``next_id``.
        """
        held = np.zeros(labels.shape, bool)
        born: dict[int, int] = {}
        unfollowed: list[int] = []  # new ids of the pieces no MotionBit followed
        for box, piece, parent in arrivals:
            near = labels[grow_box(box, reach, labels.shape)]
            joins = [] if parent else [i for i in unfollowed if (
                labels[grow_box(box, JOIN_CELLS * reach, labels.shape)] == i).any()]
            if parent and parent not in moving and (near == parent).any():
                new = parent
            elif joins:
                new = joins[0]
            else:
                new, next_id = next_id, next_id + 1
                born[new] = parent
                if not parent:
                    unfollowed.append(new)
            labels[box][piece] = new
            held[box][piece] = True
        return labels, held, born, next_id

    def update(self, cur: np.ndarray, calm: np.ndarray, labels: np.ndarray,
               moved: np.ndarray) -> None:
        """Fold in the current frame.

        Args:
            cur: (H, W, 3) uint8 current RGB frame.
            calm: (H, W) bool, seen standing still now (:meth:`StaticMemory.update`).
            labels: (H, W) int32 this frame's MotionBit ids.
            moved: (H, W) bool, seen moving now (reliable flow, relative to the camera).
        """
        free = calm & (labels == 0) & ~self._waiting
        # in place (boolean-mask assignment is several times slower)
        cv2.copyTo(cur, free.view(np.uint8), self.background)
        self.known |= free
        self.visited *= ~free
        self.stirred |= moved
        self.stirred &= ~free
        self.passed |= moved | (labels > 0)
        cv2.copyTo(labels, (labels > 0).view(np.uint8), self.visited)
        areas = label_areas(labels)
        self._largest = {int(i): max(self._largest.get(int(i), 0), int(areas[i]))
                         for i in np.flatnonzero(areas[1:]) + 1}


def _ring(shape: tuple[int, ...], box: tuple[slice, slice], piece: np.ndarray, near: int,
          far: int) -> tuple[tuple[slice, slice], np.ndarray]:
    """The pixels more than ``near`` and at most ``far`` px from ``piece`` (bool, in the
    image box ``box``; square distance) in an image of ``shape``: (image box, bool ring
    inside it)."""
    around = grow_box(box, far, shape)
    y0, x0 = around[0].start, around[1].start
    grown = np.zeros((around[0].stop - y0, around[1].stop - x0), np.uint8)
    grown[box[0].start - y0:box[0].stop - y0, box[1].start - x0:box[1].stop - x0] = piece
    outer = cv2.dilate(grown, np.ones((2 * far + 1, 2 * far + 1), np.uint8))
    inner = cv2.dilate(grown, np.ones((2 * near + 1, 2 * near + 1), np.uint8))
    return around, outer > inner


def _touching(labels: np.ndarray, box: tuple[slice, slice], piece: np.ndarray) -> np.ndarray:
    """(k,) int32 labels (> 0) of the (H, W) ``labels`` within ``TOUCH`` px of ``piece``
    (bool, in the image box ``box``), one per touching pixel."""
    around, ring = _ring(labels.shape, box, piece, 0, TOUCH)
    ring = labels[around][ring]
    return ring[ring > 0]


def _beside(touching: np.ndarray, standing: np.ndarray) -> int:
    """The id standing still (``standing``: id -> bool) that ``touching`` ((k,) ids,
    :func:`_touching`) names most often; 0 if none."""
    beside = touching[standing[touching]]
    return int(np.bincount(beside).argmax()) if beside.size else 0


def _relit(now: np.ndarray, then: np.ndarray, piece: np.ndarray) -> bool:
    """Whether the (h, w) bool ``piece`` of (h, w, 3) uint8 ``now`` is ``then`` under other
    light: the same chromaticity and, after one gain, the same grey levels."""
    chroma, gain, sum_now, sum_then = light_change(now[piece], then[piece])  # (n,) each
    gain = np.median(gain)
    residual = np.abs(sum_now - gain * sum_then).mean() / 3
    return bool(np.median(chroma) < LIGHT_CHROMA and residual < LIGHT_RESIDUAL)


def surroundings_colour(cur: np.ndarray, labels: np.ndarray, box: tuple[slice, slice],
                        piece: np.ndarray, known: np.ndarray | None = None
                        ) -> np.ndarray | None:
    """(3,) float64 mean colour in ``cur`` ((H, W, 3) uint8) of the unlabelled ring
    ``SURROUND_RING`` around ``piece`` (bool, in the image box ``box`` of the (H, W)
    ``labels``), only where ``known`` ((H, W) bool; None: everywhere); None where fewer
    than ``SURROUND_MIN`` such pixels surround it."""
    around_box, ring = _ring(labels.shape, box, piece, *SURROUND_RING)
    ring &= labels[around_box] == 0
    if known is not None:
        ring &= known[around_box]
    if np.count_nonzero(ring) < SURROUND_MIN:
        return None
    return cur[around_box][ring].mean(axis=0)


def _stands_out(cur: np.ndarray, first_look: FirstLook, labels: np.ndarray,
                box: tuple[slice, slice], piece: np.ndarray) -> bool:
    """Whether ``piece`` (bool, in the image box ``box``) stands out from its unlabelled
    surroundings (``SURROUND_RING``) in ``cur`` by ``SURROUND_DIFFERENCE`` (mean colour,
    largest channel) and by ``FIRST_LOOK_CONTRAST`` times as much as in the first look,
    where the first look knows ``SURROUND_MIN`` of those surroundings."""
    around = surroundings_colour(cur, labels, box, piece)
    if around is None:
        return False
    now = np.abs(cur[box][piece].mean(axis=0) - around).max()
    if now < SURROUND_DIFFERENCE:
        return False
    around = surroundings_colour(first_look.look, labels, box, piece, first_look.known)
    inside = piece & first_look.known[box]
    if around is None or not inside.any():
        return True
    then = np.abs(first_look.look[box][inside].mean(axis=0) - around).max()
    return bool(now >= FIRST_LOOK_CONTRAST * then)


def _like_surroundings(cur: np.ndarray, labels: np.ndarray, box: tuple[slice, slice],
                       piece: np.ndarray, remembered: np.ndarray | None) -> bool:
    """Whether ``piece`` (bool, in the image box ``box``) is background that continues its
    surroundings where the memory saw something else: its mean colour in ``cur`` is within
    ``SURROUND_DIFFERENCE`` of that of the unlabelled ring ``SURROUND_RING`` around it,
    and its mean colour in ``remembered`` ((H, W, 3) uint8, the static world seen) is
    not (None: not asked -- a memory carried along a moving camera's model is misaligned
    where the scene has depth, and a textured surface reads as changed there)."""
    around = surroundings_colour(cur, labels, box, piece)
    if around is None:
        return False
    inside = cur[box][piece].mean(axis=0)
    if np.abs(inside - around).max() >= SURROUND_DIFFERENCE:
        return False
    return remembered is None or bool(
        np.abs(remembered[box][piece].mean(axis=0) - around).max() >= SURROUND_DIFFERENCE)
