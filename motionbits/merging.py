"""One rigid body, one MotionBit: merging MotionBits whose motions agree over time (ours).

The paper defines a MotionBit as the points that share one twist trajectory. Clustering a
single frame's twists splits a body wherever its flow is ambiguous (a textureless link
moving along itself, a part turning in depth), and the temporal constraints then keep the
pieces apart for good. This module joins them again at the level of MotionBit ids:

- two MotionBits that touch *agree* at a frame when one motion (an affine map, which also
  absorbs the scale change of a part moving in depth) fitted to both explains the images of
  each about as well as its own motion does (photometric residual, grey levels);
- they *disagree* when that union motion explains one of them clearly worse at two
  frames (or by twice as much at one: a single frame's flow can be wrong on a thin or
  textureless part), or when one was born out of pixels seen standing still while the
  other was moving (background counts as a label in the paper: a point that moved and
  one that did not are never one rigid body -- this keeps a pushed block apart from the
  gripper that pushes it);
- a MotionBit born out of pixels seen standing still while the other moved, where the
  other's motion would not have shown on them (a flat laptop lid beside the hand that
  pushes it), is *doubtful* with it: they may still agree, but of two groups that a
  piece agreed with as often, it joins the one it agreed with without doubt (the lid's
  piece goes with the lid's other pieces, not with the older hand);
- a MotionBit born out of the pixels of one MotionBit (a piece its cluster split off) is a
  piece of that body: it disagrees with every MotionBit its parent disagrees with (a
  pushed drawer, kept apart from the gripper since it was born, comes apart into pieces
  as the flow on its flat front changes; each piece stays apart from the gripper);
- of two groups that a piece agreed with as often (and as doubtfully), it joins the one
  whose union motion explained it better on average, per px it moved (a piece of a
  laptop lid agrees at as many frames with the hand pressing on it as with the lid's
  other pieces, but more closely with the lid's; pieces that barely move agree closely
  with anything at rest);
- two MotionBits that agreed before but no longer touch are *apart* at a frame when both
  have a cluster and one moves while the other stands still; at two such frames in a row
  they are different bodies for good (a block set down and the hand that carried it,
  which agreed while they moved as one: round 26,
  docs/reading_the_paper.md, "Bodies set down apart"); from the first such frame on they
  are shown apart where one motion fitted to both explains them clearly worse than their
  own motions do (the block set down and its carrier: not a slow link of an arm and its
  fast one), and together again if the run ends (a block set down at the clip's last
  frame is shown as it stands, not under its carrier's mark: round 52);
- MotionBits that agreed at some frame and never disagreed form one group, shown under the
  group's oldest id. Disagreement is final between the two; between groups it is
  outweighed when the groups agreed across at ``OUTWEIGH`` times as many frames as they
  hold disagreeing pairs (a single pair of small pieces that disagreed, once read wrong
  at two frames, does not split an arm agreed on elsewhere at a dozen frames) -- unless
  it was born out of still pixels or inherited (:meth:`MotionBitGroups.forbid`), which
  no agreement outweighs. A group that loses a member splits again.

Once a body is set down, nothing moves to compare: two marks shown at rest side by side
that together fill their convex hull, of a size with each other, are one body
(:func:`join_convex`: a block's top face and its sides, marked apart; round 43).

State is one small set of id pairs per relation (and a count of frames beyond the margin
per pair); nothing grows with the video's length except the number of ids.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from functools import cache

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from motionbits.boxes import grow_box, label_areas, label_boxes, nonzero_box
from motionbits.evidence import photometric_residual
from motionbits.nodes import NodeGrid
from motionbits.revealed import SHADOW_CHROMA, SHADOW_MIN_SUM
from motionbits.twists import rigid_matrix

__all__ = ["touching_pairs", "fit_affine", "MotionBitGroups", "standing_still", "seen_still",
           "drop_seen_still", "observe_touching", "join_convex", "mostly_moving", "one_colour",
           "apply_joins", "DROP_WIDTH", "MIN_MOVED", "CONVEX_SOLIDITY", "CONVEX_BORDER",
           "CONVEX_AREA_RATIO", "FACES_SOLIDITY", "FACES_RING", "FACES_MIN_PIXELS"]

#: The (2, 3) identity motion: a MotionBit without motion this frame stands still.
STILL = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: Touching MotionBits disagree for good once the union motion is worse by ``disagree``
#: at this many frames, or by ``AT_ONCE x disagree`` at one. On the 40 + 40 robot / hand
#: scenes, single frames between 6 and 9 grey levels mostly split an arm whose thin
#: or flat parts DIS reads wrong at that frame (round 7: mIoU 51.1 / 45.4 -> 52.2 / 46.0).
DISAGREE_FRAMES = 2
AT_ONCE = 2.0
#: px/frame: agreements are ranked by their union excess per px of the union's motion
#: (at least this): two pieces that barely move agree closely whatever they are.
MIN_MOVED = 0.5
#: A new MotionBit was born out of still pixels, as far as an older MotionBit can tell, when
#: more than this share of its nodes came from pixels never in a MotionBit and seen standing
#: still (:func:`seen_still`) since that MotionBit first moved; and out of one MotionBit's
#: pixels when more than this share of its nodes carried that MotionBit's label.
BORN_FRESH = 0.5
#: Two groups join across pairs that disagreed (:meth:`MotionBitGroups.observe`) when the
#: pairs across them agreed at this many times as many frames, summed, as there are such
#: pairs. Seed 0 robot / hand: spurious per scene 0.825 / 0.925 -> 0.775 / 0.875 (round 16).
OUTWEIGH = 3

#: Two marks at rest that touch are one body when their union fills at least this share of
#: its convex hull (:func:`join_convex`): a block's top face and its sides, a cylinder's
#: top and its side, shown as two marks once set down (round 43).
CONVEX_SOLIDITY = 0.9
#: ... and they share at least this share of the shorter of their two outlines (a corner
#: of contact is not one body) ...
CONVEX_BORDER = 0.1
#: ... and the larger is at most this many times the smaller (the faces of one body are
#: of a size: a block beside a large mark spilled over the table is not its face).
CONVEX_AREA_RATIO = 4.0
#: Two such marks that fill only this share of their hull are one body when they have one
#: colour but for the light: median chromaticities within
#: :data:`motionbits.revealed.SHADOW_CHROMA` (a face turned from the light is darker, not
#: of another colour), each unlike the unlabelled surface around them by as much (a
#: shadow on the table has the table's colour). Round 59, the last frames of held25-held28
#: (555 bodies): of the touching pairs of marks away from the agent that fill 80% of their
#: hull or more, those of one colour were 21 pairs of faces of one body and 1 pair of a
#: block and a mark of the table's colour beside it (docs/results.md, round 59).
FACES_SOLIDITY = 0.8
#: px: the ring around the two marks whose colour they must not have.
FACES_RING = 5
#: Fewest pixels bright enough to have a colour (``SHADOW_MIN_SUM``) for each of the
#: three colours (else the pair is not joined by colour).
FACES_MIN_PIXELS = 20

#: px (working resolution): :func:`drop_seen_still` leaves slivers thinner than this. On
#: the planar demo clip a translating quad lost a sliver of its leading edge at every
#: frame, and its reported twist read vy 0.24 for 0.75 px/frame.
DROP_WIDTH = 3


def standing_still(speed: np.ndarray, reliable: np.ndarray, move_threshold: float) -> np.ndarray:
    """(H, W) bool: pixels seen standing still now -- reliable flow (consistent both ways)
    that moves them less than ``move_threshold`` px; ``speed``: (H, W) float32 length of
    the backward flow relative to the camera (``cv2.magnitude``)."""
    return reliable & (speed < move_threshold)


def seen_still(carried: np.ndarray, standing: np.ndarray, frame_index: int) -> np.ndarray:
    """When each pixel, followed by the flow, was last seen standing still: now
    (``standing``, from :func:`standing_still`) or as ``carried`` (the map of the last
    frame carried to this one).

    Args:
        carried: (H, W) int32, 1 + the last frame at which the pixel was seen still
            (0 = never).
        standing: (H, W) bool, seen standing still now.
        frame_index: this frame's index.

    Returns:
        (H, W) int32 map of the same kind, for the next frame.
    """
    return np.where(standing, np.int32(frame_index + 1), carried).astype(np.int32)


def drop_seen_still(labels: np.ndarray, prior: np.ndarray, still_seen: np.ndarray,
                    first_moved: dict[int, int]) -> np.ndarray:
    """Background again for the pixels that join a MotionBit now although they were seen
    standing still at or after the frame that MotionBit first moved.

    The pixel-level twin of ``BORN_FRESH``: a point that stood still while a body moved is
    not on that body. A block that a gripper pushes moves as the gripper does, and the
    motion alone grows the gripper's mask over it; kept out of it, the block's nodes keep a
    label history of their own, and the block is born as a MotionBit of its own. Pixels
    the MotionBit held at the last frame (``prior``) stay: a body that stood still for a
    while keeps its pixels. Only places at least ``DROP_WIDTH`` px wide go: a sliver along
    a body's outline is the error of its mask or of the smeared flow (a leading edge that
    the mask missed at the last frame, which the flow showed standing still), not a body
    of its own.

    Args:
        labels: (H, W) int32 labels of this frame; changed in place.
        prior: (H, W) int32 labels of the last frame, carried to this one.
        still_seen: (H, W) int32, 1 + the last earlier frame at which each pixel was seen
            standing still (:func:`seen_still`, carried), 0 where never.
        first_moved: id -> the frame at which it first moved (``MotionSpans.first``).

    Returns:
        ``labels``.
    """
    top = int(labels.max()) + 1
    if not first_moved or top == 1:
        return labels
    first = np.full(top, np.iinfo(np.int32).max, np.int32)  # never moved: never dropped
    ids = np.fromiter(first_moved.keys(), np.int64, len(first_moved))
    frames = np.fromiter(first_moved.values(), np.int64, len(first_moved))
    first[ids[ids < top]] = frames[ids < top]
    # only where a label is (``first[0]``: never); int32 as ``still_seen``
    places = np.zeros(labels.shape, np.uint8)
    box = nonzero_box(labels)
    lab = labels[box]
    places[box] = (lab != prior[box]) & (still_seen[box] > np.take(first, lab))
    square = np.ones((DROP_WIDTH, DROP_WIDTH), np.uint8)
    labels[cv2.morphologyEx(places, cv2.MORPH_OPEN, square) > 0] = 0
    return labels


def touching_pairs(labels: np.ndarray, reach: int) -> set[tuple[int, int]]:
    """Pairs (a, b), a < b, of non-zero labels whose masks come within ``reach`` px.

    Args:
        labels: (H, W) int label map.
        reach: px (>= 1).
    """
    box = nonzero_box(labels)
    if box[0].start == box[0].stop:
        return set()
    # the labelled box: outside it nothing touches
    lab = labels[box].astype(np.int32)
    # largest and smallest label within reach (``none``: no label); uint16 morphology
    # (faster) where the ids fit, else float32
    dtype, none = ((np.uint16, 0xFFFF) if lab.max() < 0xFFFF
                   else (np.float32, np.iinfo(np.int32).max))
    kernel = np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)
    pairs: set[tuple[int, int]] = set()
    grown_max = cv2.dilate(lab.astype(dtype), kernel)
    grown_min = cv2.erode(np.where(lab > 0, lab, none).astype(dtype), kernel)
    for a_map, b_map in ((lab, grown_max), (lab, grown_min)):
        sel = (a_map > 0) & (b_map > 0) & (b_map != a_map) & (b_map < none)
        if sel.any():
            a = a_map[sel].astype(np.int64)
            b = b_map[sel].astype(np.int64)
            key = np.unique(np.minimum(a, b) * (1 << 31) + np.maximum(a, b))
            pairs.update((int(k >> 31), int(k & ((1 << 31) - 1))) for k in key)
    return pairs


def join_convex(shown: np.ndarray, rgb: np.ndarray, moving: Collection[int],
                groups: MotionBitGroups) -> list[tuple[int, int]]:
    """Pairs of marks at rest that are one body by their shape: they touch along at least
    ``CONVEX_BORDER`` of the shorter outline, the larger is at most ``CONVEX_AREA_RATIO``
    times the smaller, and together they fill ``CONVEX_SOLIDITY`` of their union's convex
    hull -- or ``FACES_SOLIDITY`` of it, with one colour but for the light
    (:func:`one_colour`). Each such pair not known to disagree
    (:meth:`MotionBitGroups.known`) is recorded in ``groups`` as agreeing, so that later
    frames show them as one.

    The faces of a body that its motion or its arrival marked apart (a block's top face
    and its sides, seen from above at an angle) stand still side by side once it is set
    down: no motion tells them apart or together any more. Two bodies at rest side by
    side rarely fill their union's hull (the rigid bodies of the generated tracks are
    blocks, cylinders and balls; a shadow beside a block makes an L).

    Args:
        shown: (H, W) int32 marks shown, under their group labels (0 = none).
        rgb: (H, W, 3) uint8 current frame.
        moving: group labels moving now (not joined).
        groups: the merging state; updated in place.

    Returns:
        (keep, drop) pairs, keep < drop, in the order found; a label may occur in several.
    """
    boxes = label_boxes(shown)
    at_rest = [i + 1 for i, box in enumerate(boxes) if box is not None and i + 1 not in moving]
    if len(at_rest) < 2:  # no pair at rest
        return []
    square = np.ones((3, 3), np.uint8)
    joined = []
    for a, b in sorted(touching_pairs(shown, 1)):
        if a in moving or b in moving or groups.known(a, b):
            continue
        (ra, ca), (rb, cb) = boxes[a - 1], boxes[b - 1]
        pair_box = (slice(min(ra.start, rb.start), max(ra.stop, rb.stop)),
                    slice(min(ca.start, cb.start), max(ca.stop, cb.stop)))
        sub = shown[pair_box]
        mask_a, mask_b = (sub == a).view(np.uint8), (sub == b).view(np.uint8)
        area_a, area_b = np.count_nonzero(mask_a), np.count_nonzero(mask_b)
        if max(area_a, area_b) > CONVEX_AREA_RATIO * min(area_a, area_b):
            continue
        border = np.count_nonzero((cv2.dilate(mask_a, square) > 0) & (mask_b > 0))
        if border < CONVEX_BORDER * min(_outline_length(mask_a), _outline_length(mask_b)):
            continue
        union = mask_a | mask_b
        contours, _ = cv2.findContours(union, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        hull = cv2.contourArea(cv2.convexHull(np.vstack(contours)))
        solidity = (area_a + area_b) / max(hull, 1.0)
        if solidity >= CONVEX_SOLIDITY or (solidity >= FACES_SOLIDITY
                                           and one_colour(shown, rgb, a, b, pair_box)):
            groups.observe(a, b, 0.0)
            joined.append((a, b))
    return joined


def mostly_moving(state: np.ndarray, rep: dict[int, int], moving: Collection[int],
                  marks: Collection[int]) -> set[int]:
    """The shown labels among ``marks`` most of whose pixels in ``state`` ((H, W) int32
    MotionBit ids) belong to MotionBits ``moving`` now (``rep``: id -> the label it is
    shown under). For :func:`join_convex`: a sliver of a body set down that reads a
    neighbour's smeared flow, or the camera model's residual on a tall face (0.65 px a
    frame against the 0.6 px move threshold, held28), does not make the body move."""
    if not marks:
        return set()
    areas = label_areas(state)
    total: dict[int, int] = {}
    stirring: dict[int, int] = {}
    for i, r in rep.items():
        if r in marks and i < areas.size:
            total[r] = total.get(r, 0) + int(areas[i])
            if i in moving:
                stirring[r] = stirring.get(r, 0) + int(areas[i])
    return {r for r in marks if 2 * stirring.get(r, 0) >= total.get(r, 0)}


def apply_joins(shown: np.ndarray, rep: dict[int, int], pairs: list[tuple[int, int]]
                ) -> tuple[np.ndarray, dict[int, int]]:
    """``shown`` (H, W) int32 and ``rep`` (id -> group label) with each pair's labels
    under one, the smallest of those joined to it (``pairs`` from :func:`join_convex`);
    both unchanged (the same objects) when ``pairs`` is empty."""
    if not pairs:
        return shown, rep
    ends = np.array(pairs, np.int64)  # (P, 2)
    _, comp = connected_components(coo_matrix((np.ones(len(ends)), (ends[:, 0], ends[:, 1])),
                                              shape=(ends.max() + 1,) * 2), directed=False)
    smallest = np.full(comp.max() + 1, np.iinfo(np.int64).max)
    np.minimum.at(smallest, comp[ends.ravel()], ends.ravel())
    final = {int(i): int(smallest[comp[i]]) for i in np.unique(ends) if smallest[comp[i]] != i}
    lut = np.arange(int(max(shown.max(initial=0), ends.max())) + 1, dtype=np.int32)
    for label, to in final.items():
        lut[label] = to
    return lut[shown], {i: final.get(r, r) for i, r in rep.items()}


def one_colour(shown: np.ndarray, rgb: np.ndarray, a: int, b: int,
               box: tuple[slice, slice]) -> bool:
    """Whether marks ``a`` and ``b`` of ``shown`` ((H, W) int32; ``box``: the image box
    holding both) have one colour in ``rgb`` ((H, W, 3) uint8) but for the light, and not
    the colour of the unlabelled surface within ``FACES_RING`` px of them: their median
    chromaticities (each channel over the sum of the three, pixels whose sum is at least
    ``SHADOW_MIN_SUM``) lie within ``SHADOW_CHROMA`` of each other and at least that far
    from the surface's. False where any of the three has fewer than ``FACES_MIN_PIXELS``
    such pixels."""
    box = grow_box(box, FACES_RING, shown.shape)
    sub = shown[box]
    pair = ((sub == a) | (sub == b)).view(np.uint8)
    side = 2 * FACES_RING + 1
    ring = (cv2.dilate(pair, np.ones((side, side), np.uint8)) > 0) & (sub == 0)
    colours = [_chromaticity(rgb[box][m]) for m in (sub == a, sub == b, ring)]
    if any(c is None for c in colours):
        return False
    first, second, around = colours
    return bool(np.abs(first - second).max() < SHADOW_CHROMA
                and np.abs(first - around).max() >= SHADOW_CHROMA
                and np.abs(second - around).max() >= SHADOW_CHROMA)


def _chromaticity(pixels: np.ndarray) -> np.ndarray | None:
    """(3,) float32 median chromaticity of the (n, 3) uint8 ``pixels`` bright enough to
    have a colour (sum of the three at least ``SHADOW_MIN_SUM``); None with fewer than
    ``FACES_MIN_PIXELS`` of them."""
    light = pixels.astype(np.float32)
    total = light.sum(axis=1)
    bright = total >= SHADOW_MIN_SUM
    if np.count_nonzero(bright) < FACES_MIN_PIXELS:
        return None
    return np.median(light[bright] / total[bright, None], axis=0)


def _outline_length(mask: np.ndarray) -> float:
    """px: the length of the longest outer outline of the (h, w) uint8 0/1 ``mask``."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    return max(cv2.arcLength(c, True) for c in contours) if contours else 0.0


def fit_affine(points: np.ndarray, back_points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(2, 3) weighted least-squares affine map q ~ A [p; 1] (current -> previous)."""
    x = np.hstack([points, np.ones((len(points), 1))]).astype(np.float64)
    sw = np.sqrt(np.maximum(weights, 1e-6))[:, None]
    sol, *_ = np.linalg.lstsq(x * sw, back_points.astype(np.float64) * sw, rcond=None)
    return sol.T


class MotionBitGroups:
    """Which MotionBit ids show one rigid body (the agree / disagree relations above).

    Args:
        agree: grey levels; a union motion within this of each member's own residual agrees.
        disagree: grey levels; beyond this for either member at ``DISAGREE_FRAMES`` frames
            (or beyond ``AT_ONCE`` times this at one), the two disagree for good.
    """

    def __init__(self, agree: float, disagree: float) -> None:
        self.agree_tol, self.disagree_tol = agree, disagree
        self._agree: dict[tuple[int, int], int] = {}  # frames seen agreeing
        self._excess: dict[tuple[int, int], float] = {}  # their excess per px moved, summed
        self._disagree: set[tuple[int, int]] = set()
        self._strikes: dict[tuple[int, int], int] = {}  # frames seen beyond ``disagree``
        self._doubt: set[tuple[int, int]] = set()  # born still beside the other's motion
        self._forbidden: set[tuple[int, int]] = set()  # disagreements nothing outweighs
        self._apart: dict[tuple[int, int], int] = {}  # frames in a row seen apart (observe_apart)
        self._apart_now: set[tuple[int, int]] = set()  # ... of which seen apart at this frame

    @staticmethod
    def _key(a: int, b: int) -> tuple[int, int]:
        return (a, b) if a < b else (b, a)

    def forbid(self, a: int, others) -> None:
        """``a`` and each of ``others`` are different bodies, for good: no agreement
        between their groups outweighs it."""
        for b in others:
            if b != a:
                key = self._key(int(a), int(b))
                self._forbidden.add(key)
                self._disagree.add(key)
                self._agree.pop(key, None)
                self._excess.pop(key, None)

    def inherit(self, child: int, parent: int) -> None:
        """``child``, a piece of ``parent``, disagrees with each MotionBit ``parent``
        disagrees with."""
        self.forbid(child, [b if a == parent else a for a, b in self._disagree
                            if parent in (a, b)])

    def doubt(self, a: int, b: int) -> None:
        """``a`` was born out of pixels seen standing still while ``b`` moved, where that
        could not be seen: their agreements rank after as many of an undoubted pair."""
        self._doubt.add(self._key(int(a), int(b)))

    def known(self, a: int, b: int) -> bool:
        return self._key(a, b) in self._disagree

    def observe(self, a: int, b: int, excess: float, moved: float = MIN_MOVED) -> None:
        """Record one frame's test: ``excess`` = how much worse (grey levels) the union
        motion explains the worse-explained member than its own motion does; ``moved``
        = px the union motion moved the two (mean over their nodes)."""
        key = self._key(a, b)
        if key in self._disagree:
            return
        if excess > self.disagree_tol:
            self._strikes[key] = self._strikes.get(key, 0) + 1
            if self._strikes[key] >= DISAGREE_FRAMES or excess > AT_ONCE * self.disagree_tol:
                self._disagree.add(key)
                self._agree.pop(key, None)
                self._excess.pop(key, None)
                del self._strikes[key]
        elif excess <= self.agree_tol:
            self._agree[key] = self._agree.get(key, 0) + 1
            self._excess[key] = self._excess.get(key, 0.0) + excess / max(moved, MIN_MOVED)

    def observe_apart(self, touching: set[tuple[int, int]], clustered: set[int],
                      moving: set[int],
                      differ: Callable[[int, int], bool] | None = None) -> None:
        """Record this frame's evidence on the pairs seen agreeing before that no longer
        touch (``touching``: the pairs (a, b), a < b, that do) and both have a cluster now
        (``clustered``): one moving (``moving``) while the other stands still is a frame
        apart, both moving or both still ends the run; at ``DISAGREE_FRAMES`` frames apart
        in a row they are different bodies for good. One twist trajectory is one MotionBit:
        a block set down and the hand that carried it agreed while it carried it (or once,
        where the block's flat faces could not tell), then the hand moves on while the
        block stands. Until the next call, :meth:`representatives` keeps the pairs seen
        apart at this frame for which ``differ(a, b)`` is true (one motion cannot explain
        both now; None: every such pair) in different groups: the block is shown apart
        from the first frame apart on (at a clip's last frame there is no second), the
        slow link of an arm beside its fast one is not."""
        self._apart_now = set()
        for key in list(self._agree):
            a, b = key
            if key in touching or a not in clustered or b not in clustered:
                continue
            if (a in moving) == (b in moving):
                self._apart.pop(key, None)
                continue
            self._apart[key] = self._apart.get(key, 0) + 1
            if self._apart[key] >= DISAGREE_FRAMES:
                del self._apart[key]
                self.forbid(a, [b])  # (which parts them at this frame too)
            elif differ is None or differ(a, b):
                self._apart_now.add(key)

    def representatives(self, ids) -> dict[int, int]:
        """id -> the oldest (smallest) id of its group, for ``ids`` present now. Groups
        join greedily along agreeing pairs, the pairs seen agreeing at the most frames
        first, undoubted pairs (:meth:`doubt`) before doubtful ones, then those whose
        union motion explained both better (the smaller mean excess per px moved): a
        piece that agreed with two MotionBits that disagree joins the one it agreed with
        more often, or without doubt, or more closely. Two groups do not join across a
        forbidden pair (:meth:`forbid`) or a pair seen apart at this frame
        (:meth:`observe_apart`), nor across pairs that disagreed unless the pairs across
        them agreed at ``OUTWEIGH`` times as many frames as there are disagreeing ones."""
        ids = sorted(int(i) for i in ids)
        present = set(ids)
        rep = {i: i for i in ids}
        members: dict[int, set[int]] = {i: {i} for i in ids}
        for a, b in sorted(self._agree, key=lambda key: (
                -self._agree[key], key in self._doubt, self._excess[key] / self._agree[key], key)):
            if a not in present or b not in present:
                continue
            ra, rb = rep[a], rep[b]
            if ra == rb:
                continue
            across = [self._key(x, y) for x in members[ra] for y in members[rb]]
            if any(key in self._forbidden or key in self._apart_now for key in across):
                continue
            split = sum(key in self._disagree for key in across)
            if split and sum(self._agree.get(key, 0) for key in across) < OUTWEIGH * split:
                continue
            keep, drop = (ra, rb) if ra < rb else (rb, ra)
            for x in members[drop]:
                rep[x] = keep
            members[keep] |= members.pop(drop)
        return rep


def union_excess(labels: np.ndarray, a: int, b: int, boxes: list, motion_a: np.ndarray,
                 motion_b: np.ndarray, union: np.ndarray, cur: np.ndarray, prev: np.ndarray
                 ) -> float:
    """Grey levels by which the (2, 3) ``union`` motion explains the worse of MotionBits
    ``a`` and ``b`` (their pixels in ``labels``; ``boxes``: ``label_boxes(labels)``) worse
    than its own (2, 3) motion does."""
    (rows_a, cols_a), (rows_b, cols_b) = boxes[a - 1], boxes[b - 1]
    box = (slice(min(rows_a.start, rows_b.start), max(rows_a.stop, rows_b.stop)),
           slice(min(cols_a.start, cols_b.start), max(cols_a.stop, cols_b.stop)))
    sub = labels[box]
    e_union = photometric_residual(cur, prev, union, box)
    worst = 0.0
    for lab, own in ((a, motion_a), (b, motion_b)):
        m = sub == lab
        e_own = photometric_residual(cur, prev, own, box)
        worst = max(worst, float(e_union[m].mean() - e_own[m].mean()))
    return worst


def stillness_visible(labels: np.ndarray, a: int, box: tuple[slice, slice], motion: np.ndarray,
                      cur: np.ndarray) -> float:
    """Grey levels by which the (2, 3) ``motion`` would change the image on MotionBit
    ``a``'s pixels (in ``labels``, within their bounding ``box``): mean |I - I pulled back
    by the motion|. Large on texture, ~0 on a flat region or for motion along its stripes
    -- where standing still is not observable."""
    return float(photometric_residual(cur, cur, motion, box)[labels[box] == a].mean())


def observe_touching(groups: MotionBitGroups, grid: NodeGrid, labels: np.ndarray,
                     node_ids: np.ndarray, ids: np.ndarray, thetas: np.ndarray,
                     trans: np.ndarray, moving: set[int], first_new: int,
                     still_before: np.ndarray, carried: np.ndarray, back_points: np.ndarray,
                     reliability: np.ndarray, cur: np.ndarray, prev: np.ndarray, *,
                     disagree: float, first_moved: dict[int, int],
                     min_agreeing: float = 0.0) -> None:
    """Record in ``groups`` this frame's evidence on every pair of touching MotionBits,
    and on the pairs seen agreeing before that no longer touch
    (:meth:`MotionBitGroups.observe_apart`; such a pair, one moving and the other still,
    is shown apart at this frame where the affine motion fitted to both explains one of
    them worse than its own motion by more than ``disagree``, :func:`union_excess`).

    A MotionBit born now out of pixels never in a MotionBit and seen standing still while
    a moving older MotionBit moved (``BORN_FRESH`` of its nodes, seen still at or after
    the older one's first moving frame), where the older one's motion would have shown,
    are different bodies for good (the pushed block is not the gripper that pushes it; a
    part of the gripper that the masks missed while it moved is); where the older one's
    motion would not have shown, the pair is doubtful (:meth:`MotionBitGroups.doubt`).
    Stillness seen before the older MotionBit moved tells nothing about the two: an arm's
    upper part, slow near the shoulder, reads as standing still while the whole arm
    starts moving.
    A MotionBit born now of which more than ``BORN_FRESH`` of the nodes carried one older
    MotionBit's label inherits that one's disagreements (:meth:`MotionBitGroups.inherit`).
    Otherwise, where either has a motion this frame, one affine motion is fitted to the
    nodes of both and :func:`union_excess` is observed -- a member without motion stands
    still (``STILL``), which can show that they differ, never that they agree; nor can a
    union motion under ``min_agreeing`` px (mean over the nodes): under a moving camera,
    what stands still relative to the static world's model "moves" by that model's error,
    and two such MotionBits (a body at rest, a mark spilled on the table beside it) agree
    whatever they are.

    Args:
        groups: the relations, updated in place.
        grid: the node grid.
        labels: (H, W) int32 label map of this frame.
        node_ids: (n,) int MotionBit id of each node (0 = none).
        ids: (K,) MotionBit ids with a cluster now, with backward motions ``thetas`` (K,)
            and ``trans`` (K, 2).
        moving: ids whose motion moved their nodes this frame.
        first_new: ids from this one on were born now.
        still_before: (n,) int, 1 + the last earlier frame at which each node was seen
            standing still (:func:`seen_still`), 0 where never or once in a MotionBit.
        carried: (n,) int, the MotionBit id each node carried from the last frame (0: none).
        back_points: (n, 2) each node's backward target relative to the camera.
        reliability: (n,) flow reliability of each node.
        cur, prev: (H, W) float32 grey frames (``prev`` camera-stabilised).
        disagree: grey levels (config ``merge_disagree``).
        first_moved: id -> the frame at which it first moved (``MotionSpans.first``).
        min_agreeing: px; agreement is recorded only where the union motion moves the
            pair's nodes by at least this much (0: always; ``MIN_MOVED`` under a moving
            camera).
    """
    own = {int(i): rigid_matrix(th, t) for i, th, t in zip(ids, thetas, trans)}
    reach = int(np.ceil(max(grid.cell)))
    newborn = {int(i) for i in ids[ids >= first_new]}
    for x in newborn:
        parents = np.bincount(carried[node_ids == x], minlength=1)  # its nodes' last ids
        if parents[1:].sum() and parents[1:].max() > BORN_FRESH * parents.sum():
            groups.inherit(x, int(parents[1:].argmax()) + 1)
    boxes = cache(lambda: label_boxes(labels))  # once, if a pair asks
    touching = touching_pairs(labels, reach=reach)

    def pair_excess(a: int, b: int) -> tuple[float, np.ndarray]:
        """:func:`union_excess` of the affine motion fitted to both, and their nodes."""
        sel = (node_ids == a) | (node_ids == b)
        union = fit_affine(grid.points[sel], back_points[sel], reliability[sel])
        return union_excess(labels, a, b, boxes(), own.get(a, STILL), own.get(b, STILL),
                            union, cur, prev), sel

    def differ(a: int, b: int) -> bool:  # one motion cannot explain both
        if any(x > len(boxes()) or boxes()[x - 1] is None for x in (a, b)):
            return False  # a cluster without pixels: nothing to tell
        return pair_excess(a, b)[0] > disagree

    groups.observe_apart(touching, set(own), moving, differ)
    for a, b in touching:
        if groups.known(a, b):
            continue
        for x, y in ((a, b), (b, a)):
            if (x in newborn and y < first_new and y in own and y in moving
                    and np.mean(still_before > first_moved[y], where=node_ids == x) > BORN_FRESH):
                if stillness_visible(labels, x, boxes()[x - 1], own[y], cur) > disagree:
                    groups.forbid(x, [y])
                else:
                    groups.doubt(x, y)
        if groups.known(a, b) or (a not in own and b not in own):
            continue
        excess, sel = pair_excess(a, b)
        moved = float(np.hypot(*(back_points[sel] - grid.points[sel]).T).mean())
        if (a in own and b in own and moved >= min_agreeing) or excess > disagree:
            groups.observe(a, b, excess, moved)
