"""Bodies set down: a piece a MotionBit leaves behind becomes a MotionBit of its own (ours).

While a hand carries a body, the two move as one, and the clustering (held together by
the paper's temporal constraints) gives them one MotionBit. When the hand lets go and
moves on, the body's pixels still carry that MotionBit's label, but its motion -- the
hand's -- no longer explains them and "static" does, so they would return to the
background although the body moved. A piece of a MotionBit lost this way becomes a new
MotionBit when

- it is compact (an opening by one grid cell keeps most of it), covers at least
  ``SETDOWN_CELLS`` grid cells, and most of its pixels *earned* their label (the
  MotionBit's motion once explained them better than "static");
- it is at rest now, and "static" explains it better than its MotionBit's motion by a
  visible margin;
- it *came with* its MotionBit: its pixels today, followed back along the MotionBit's
  motion over the last ``WINDOW`` frames (and standing still this frame), match the frame
  of then clearly better than the static world does, and within ``rest`` grey levels
  (:func:`motionbits.retirement.origin_residuals`, the test that retires MotionBits that
  never moved) -- or, where they do not match that closely (the carrier hid part of the
  body, or lifting it changed its scale), most of the piece looks unlike the static world
  last seen standing still there (``NEW_SHARE``; :meth:`StaticMemory.changed`): a body
  now stands where the table was. Background that a moving MotionBit uncovered or smeared
  its label onto fails this test: it was there all along, or what was there before was
  something else and it looks as the static world did;

and it is confirmed at the next frame if it still stands there, at rest. A solid piece
(a block, not the sliver a moving shadow's edge leaves) that no moving MotionBit borders
is shown at once, the others once confirmed (round 59: a block set down at the clip's
last frame was held back one frame too many). A piece lost next to a piece set down
earlier by the same MotionBit joins it.

State: the last ``WINDOW`` grey frames and each MotionBit's motion at those frames.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Collection
from dataclasses import dataclass, field

import cv2
import numpy as np

from motionbits.boxes import grow_box, label_areas, nonzero_box
from motionbits.evidence import photometric_residual
from motionbits.merging import STILL
from motionbits.nodes import binary_fill_holes
from motionbits.retirement import MIN_SEPARATION, Origin, origin_residuals
from motionbits.twists import rigid_matrix

__all__ = ["SetDown", "SETDOWN_CELLS", "EARNED_SHARE", "COMPACT_SHARE", "COMPACT_CELLS",
           "REST_SHARE", "NEW_SHARE", "WINDOW", "SOLID_CELLS", "BESIDE_MOVING_SHARE"]

#: A piece left behind must cover at least this many grid cells ...
SETDOWN_CELLS = 8
#: ... this share of its pixels must have earned their label ...
EARNED_SHARE = 0.5
#: ... and an opening by a square of ``COMPACT_CELLS`` grid cells must keep this share of
#: it (compact: the strip of background a moving body uncovers is not). One cell, not two:
#: a small block seen at 45 degrees, part of it still under the fingers, is a band ~9 px
#: across, which an 11 px square removed (pick-and-place, docs/reading_the_paper.md,
#: "Bodies set down").
COMPACT_SHARE = 0.5
COMPACT_CELLS = 1
#: Frames over which a piece must be seen to have come with its MotionBit.
WINDOW = 3
#: ... or, where the followed-back look does not match (the carrier hid the body, a lift
#: changed its scale), this share of it looks unlike the static world last seen there.
NEW_SHARE = 0.5
#: At the next frame it is confirmed if it still holds this share of its area.
REST_SHARE = 0.5
#: A piece set down or found at rest otherwise (:meth:`SetDown._hold`) is shown at once if
#: an opening by a square of this many grid cells keeps ``COMPACT_SHARE`` of it (a block,
#: not the sliver a moving shadow's edge leaves) ...
SOLID_CELLS = 2
#: ... and moving MotionBits hold less than this share of the ring around it.
BESIDE_MOVING_SHARE = 1 / 3


@dataclass
class _Frame:
    gray: np.ndarray  # (H, W) float32 grey frame before this one (not stabilised)
    world: np.ndarray  # (3, 3) backward motion of the static world at this frame
    own: dict[int, np.ndarray]  # id -> (3, 3) backward motion of each MotionBit


@dataclass
class SetDown:
    """Pieces left behind by a moving MotionBit, across frames.

    Args:
        evidence: grey levels (3x3 mean) by which "static" must explain a piece better than
            its MotionBit's motion now, and its MotionBit's recent motion must explain it
            better than the static world (config ``pixel_evidence``).
        rest: grey levels; a piece is at rest when its mean |I_t - I_t-1| (3x3 mean) is
            below this (config ``carry_tolerance``).

    Attributes:
        pending: new id -> its area (px) at birth, for pieces not yet confirmed.
        held_back: the pending ids not shown until they are confirmed: those that are
            not solid or lie beside a moving MotionBit (:meth:`_hold`).
        parent: new id -> the id of the MotionBit it was left behind by.
    """

    evidence: float
    rest: float
    pending: dict[int, int] = field(default_factory=dict)
    held_back: set[int] = field(default_factory=set)
    parent: dict[int, int] = field(default_factory=dict)
    _past: deque = field(default_factory=lambda: deque(maxlen=WINDOW))

    def record(self, prev_gray: np.ndarray, ids: np.ndarray, thetas: np.ndarray,
               trans: np.ndarray, cam: np.ndarray | None) -> None:
        """Keep this frame's motions and the frame before it (at the end of each frame).

        Args:
            prev_gray: (H, W) float32 previous grey frame (not stabilised).
            ids, thetas, trans: ids with a cluster now and their backward motions
                (relative to the camera).
            cam: (3, 3) camera motion of this frame (current -> previous) or None (static).
        """
        world = np.eye(3) if cam is None else cam
        own = {int(i): world @ np.vstack([rigid_matrix(th, t), [0.0, 0.0, 1.0]])
               for i, th, t in zip(ids, thetas, trans)}
        self._past.append(_Frame(prev_gray, world, own))

    def confirm(self, labels: np.ndarray, cur: np.ndarray, prev: np.ndarray) -> np.ndarray:
        """Confirm the pieces set down at the last frame that still stand, at rest, on at
        least ``REST_SHARE`` of their area; drop the others.

        Args:
            labels: (H, W) int32 label map of this frame.
            cur, prev: (H, W) float32 grey frames (``prev`` camera-stabilised).

        Returns:
            ``labels`` without the dropped pieces.
        """
        out = labels
        for i, area in self.pending.items():
            m = labels == i
            if m.sum() < REST_SHARE * area or _mean_still(cur, prev, m) > self.rest:
                out = np.where(m, 0, out)
        self.pending = {}
        self.held_back = set()
        if self.parent:  # forget the parents of pieces that are gone
            present = set(np.unique(out).tolist())
            self.parent = {i: p for i, p in self.parent.items() if i in present}
        return out

    def split(self, labels: np.ndarray, prior: np.ndarray, prior_valid: np.ndarray,
              earned: np.ndarray, ids: np.ndarray, thetas: np.ndarray, trans: np.ndarray,
              cur: np.ndarray, prev: np.ndarray, cell: tuple[float, float], next_id: int,
              cam: np.ndarray | None, changed: np.ndarray | None,
              moving: Collection[int]) -> tuple[np.ndarray, np.ndarray, int]:
        """New MotionBits from the pieces that MotionBits with a cluster now left behind.

        Args:
            labels: (H, W) int32 label map of this frame.
            prior: (H, W) int32 last frame's labels carried to this frame.
            prior_valid: (H, W) bool, where ``prior`` is trustworthy.
            earned: (H, W) bool, carried: where the pixel's label was earned.
            ids: (K,) ids with a cluster now, backward motions ``thetas`` (K,),
                ``trans`` (K, 2) (relative to the camera).
            cur, prev: (H, W) float32 grey frames (``prev`` camera-stabilised).
            cell: (w, h) px of one grid cell.
            next_id: the id the next new MotionBit gets.
            cam: (3, 3) camera motion of this frame (current -> previous) or None (static).
            changed: (H, W) bool or None, pixels that look unlike the static world last
                seen standing still there (:meth:`StaticMemory.changed`); None: no memory.
            moving: ids of the MotionBits that move now (a new piece beside one of them
                is held back, :meth:`_hold`).

        Returns:
            The label map with the new pieces, the (H, W) bool pixels they hold (their
            ``earned`` map, carried on), and the next ``next_id``.
        """
        held = np.zeros(labels.shape, bool)
        lost = (labels == 0) & (prior > 0) & prior_valid
        if len(self._past) < WINDOW or not lost.any():
            return labels, held, next_id
        out = labels.copy()
        fresh = []  # the new ids
        side = max(1, int(round(COMPACT_CELLS * max(cell))))
        kernel = np.ones((side, side), np.uint8)
        min_area = SETDOWN_CELLS * cell[0] * cell[1]
        # everything below happens on the box of the lost pixels (y0, x0: its corner)
        rows, cols = np.flatnonzero(lost.any(axis=1)), np.flatnonzero(lost.any(axis=0))
        y0, x0 = rows[0], cols[0]
        lost_prior = np.where(lost[y0:rows[-1] + 1, x0:cols[-1] + 1],
                              prior[y0:rows[-1] + 1, x0:cols[-1] + 1], 0)
        lost_area = label_areas(lost_prior)
        for lab, th, t in zip(ids, thetas, trans):
            if lab >= len(lost_area) or lost_area[lab] < min_area:
                continue
            mask = (lost_prior == lab).astype(np.uint8)
            n, comp, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
            for k in range(1, n):
                if stats[k, cv2.CC_STAT_AREA] < min_area:
                    continue
                x, y, w, h = stats[k, :4]
                piece = comp[y:y + h, x:x + w] == k
                box = slice(y0 + y, y0 + y + h), slice(x0 + x, x0 + x + w)
                if not _compact(piece, kernel) or earned[box][piece].mean() < EARNED_SHARE:
                    continue
                still = photometric_residual(cur, prev, STILL, box)[piece].mean()
                moved = photometric_residual(cur, prev, rigid_matrix(th, t), box)[piece].mean()
                if still > self.rest or moved - still < self.evidence:
                    continue
                full = np.zeros(labels.shape, bool)
                full[box] = piece
                world, body = self._came_with(int(lab), cur, full, cam)
                new_here = changed is not None and changed[box][piece].mean() > NEW_SHARE
                if not (world - body > self.evidence and (body < self.rest or new_here)):
                    continue
                new = self._neighbour(out, box, piece, int(lab), side)
                if new is None:
                    new, next_id = next_id, next_id + 1
                    fresh.append(new)
                    self.parent[new] = int(lab)
                out[box][piece] = new
                held[box][piece] = True
        self._hold(fresh, out, cell, moving)
        return out, held, next_id

    def adopt(self, pieces: dict[int, int], labels: np.ndarray, cell: tuple[float, float],
              moving: Collection[int]) -> None:
        """Take new MotionBits found at rest otherwise (:class:`motionbits.arrivals.Arrivals`;
        id -> the id they were left by) as pieces set down at this frame, confirmed at the
        next frame if they still stand there, and shown at once or held back as
        :meth:`split`'s (:meth:`_hold`).

        Args:
            pieces: new id -> the id of the MotionBit that last covered it.
            labels: (H, W) int32 label map of this frame, with the pieces.
            cell: (w, h) px of one grid cell.
            moving: ids of the MotionBits that move now.
        """
        self.parent.update(pieces)
        self._hold(pieces, labels, cell, moving)

    def _hold(self, pieces: Collection[int], labels: np.ndarray, cell: tuple[float, float],
              moving: Collection[int]) -> None:
        """Make the new ids ``pieces`` (in the (H, W) int32 ``labels``) pending, and hold
        back those that are not solid (an opening by a square of ``SOLID_CELLS`` grid
        cells keeps ``COMPACT_SHARE`` of the piece, holes filled: a cylinder's top whose
        middle has the table's colour is solid) or whose surrounding ring a moving
        MotionBit holds ``BESIDE_MOVING_SHARE`` of (it may be a part of that body its
        motion missed); the others are shown at once."""
        side = max(1, int(round(SOLID_CELLS * max(cell))))
        square = np.ones((side, side), np.uint8)
        for i in pieces:
            piece = labels == i
            self.pending[i] = int(np.count_nonzero(piece))
            box = grow_box(nonzero_box(piece), side, labels.shape)
            ring = labels[box][(cv2.dilate(piece[box].view(np.uint8), square) > 0) & ~piece[box]]
            if (not _compact(binary_fill_holes(piece[box]), square) or (
                    ring.size and np.isin(ring, list(moving)).mean() >= BESIDE_MOVING_SHARE)):
                self.held_back.add(i)

    def _came_with(self, lab: int, cur: np.ndarray, mask: np.ndarray,
                   cam: np.ndarray | None) -> tuple[float, float]:
        """Mean grey-level residuals (world, body) of the pixels ``mask`` of ``cur``
        against the frame ``WINDOW`` frames before the last one, pulled back by the static
        world's motion and by "moved with MotionBit ``lab`` (with the world where it had
        no cluster), then stood still this frame" (NaN: the two cannot be told apart)."""
        world_now = np.eye(3) if cam is None else cam
        body, world = np.eye(3), np.eye(3)
        for past in self._past:
            body = body @ past.own.get(lab, past.world)
            world = world @ past.world
        origin = Origin(self._past[0].gray, body @ world_now, world @ world_now)
        return origin_residuals(origin, cur, mask, MIN_SEPARATION)

    def _neighbour(self, labels: np.ndarray, box: tuple[slice, slice], piece: np.ndarray,
                   parent: int, reach: int) -> int | None:
        """An earlier piece of the same ``parent`` that ``piece`` touches, if any."""
        around = grow_box(box, reach, labels.shape)
        y0, x0 = around[0].start, around[1].start
        grown = np.zeros(labels[around].shape, np.uint8)
        grown[box[0].start - y0:box[0].stop - y0, box[1].start - x0:box[1].stop - x0] = piece
        grown = cv2.dilate(grown, np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)) > 0
        near = np.unique(labels[around][grown])
        same = [int(i) for i in near if self.parent.get(int(i)) == parent]
        return min(same) if same else None


def _compact(piece: np.ndarray, square: np.ndarray) -> bool:
    """Whether an opening by ``square`` keeps ``COMPACT_SHARE`` of the (h, w) bool
    ``piece`` (pixels outside the array count as the piece's, as OpenCV's erosion has
    it)."""
    opened = cv2.morphologyEx(piece.view(np.uint8), cv2.MORPH_OPEN, square)
    return np.count_nonzero(opened) >= COMPACT_SHARE * np.count_nonzero(piece)


def _mean_still(cur: np.ndarray, prev: np.ndarray, mask: np.ndarray) -> float:
    """Mean |cur - prev| (3x3 mean) over ``mask`` (0 if empty)."""
    if not mask.any():
        return 0.0
    ys, xs = np.nonzero(mask)
    box = slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1)
    return float(photometric_residual(cur, prev, STILL, box)[mask[box]].mean())
