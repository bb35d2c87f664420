"""The numbers the marks are shown under: a body keeps its number from frame to frame.

The segmenter groups its MotionBits anew at every frame and names each group after its
oldest member (:meth:`motionbits.merging.MotionBitGroups.representatives`). That name
changes while the body stays: the oldest member retires, a piece joins or leaves, the
greedy grouping comes out differently. A vision-language model shown mark "1" that
becomes "273" and back cannot follow the body. So the result shows each group under a
*number* that its members carry from frame to frame:

- each MotionBit remembers the number it was last shown under, for as long as it lives;
- a shown group inherits the numbers of its members, weighed by their pixels now, the
  heaviest first, each number and each group once: when a group splits, the bigger part
  keeps the number; when two join, the larger part's number wins; when the oldest member
  retires, the others keep the number. Numbers shown at the last frame go first; then a
  group still without one takes a free number its members had earlier (a mark hidden
  for some frames -- too small, or held back -- comes back under its number);
- a group that inherits none takes the number of a mark shown at one of the last
  ``RECENT_FRAMES`` frames and gone now whose pixels it covers (``REBORN_IOU``: a
  MotionBit retired and another born on the same body), the latest first, else its
  representative's id if no other mark holds it, else a fresh id from the segmenter's
  counter (never any MotionBit's id, past or future).

Only the output is numbered (:func:`by_number` gives :func:`motionbits.records.build_result`
the numbers instead of the groups' labels); the segmenter's state keeps the
representatives' ids.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from motionbits.boxes import label_areas
from motionbits.records import group_map

__all__ = ["REBORN_IOU", "RECENT_FRAMES", "ShownNumbers", "by_number", "inherited_weights",
           "match_greedy", "mask_ious"]

#: A mark that inherits no number takes that of a mark shown at a recent frame and gone
#: now when their masks overlap by this IoU: the same body marked again (a MotionBit
#: retired and another born on its pixels). 0.5: each mask is then more the other's than
#: anything else's (the usual "same object" match) ...
REBORN_IOU = 0.5
#: ... shown at one of this many last frames (a body whose MotionBit retired is often
#: marked again a few frames later: on ``02_cups.mp4`` most such marks came back within
#: 2-10 frames).
RECENT_FRAMES = 10


def inherited_weights(areas: np.ndarray, rep: dict[int, int], last: dict[int, int]
                      ) -> dict[tuple[int, int], int]:
    """How strongly each shown group claims each number its members had.

    Args:
        areas: (max id + 1,) int px of each MotionBit id now (:func:`label_areas`).
        rep: id -> the label of the group it is shown under (0 = not shown).
        last: id -> a number it was shown under (at the last frame, or earlier).

    Returns:
        (number, group label) -> px now of the group's members that had that number.
    """
    weights: dict[tuple[int, int], int] = {}
    for i, r in rep.items():
        if r and i in last:
            key = (last[i], r)
            weights[key] = weights.get(key, 0) + int(areas[i] if i < areas.size else 0)
    return weights


def match_greedy(weights: dict[tuple[int, int], float]) -> dict[int, int]:
    """Group label -> number: the pairs taken largest weight first, each number and each
    group at most once (ties: the smaller number, then the smaller label, first).

    Args:
        weights: (number, group label) -> weight.
    """
    numbers: dict[int, int] = {}
    taken: set[int] = set()
    for (d, r), _ in sorted(weights.items(), key=lambda kv: (-kv[1], kv[0])):
        if r not in numbers and d not in taken:
            numbers[r] = d
            taken.add(d)
    return numbers


def mask_ious(now: np.ndarray, before: np.ndarray, area_now: np.ndarray,
              area_before: np.ndarray) -> dict[tuple[int, int], float]:
    """IoU of every pair of overlapping labels of two label maps (the evaluation's
    :func:`motionbits.eval.overlap.contingency` counts every pixel and checks its input;
    this runs at every frame and counts only where both maps have a label).

    Args:
        now, before: (H, W) int32 label maps of one size (0 = background).
        area_now, area_before: their :func:`label_areas`.

    Returns:
        (label in ``before``, label in ``now``) -> IoU of their masks, for the pairs that
        share a pixel.
    """
    both = (now > 0) & (before > 0)
    if not both.any():
        return {}
    k = int(now.max()) + 1
    pairs, shared = np.unique(before[both].astype(np.int64) * k + now[both],
                              return_counts=True)
    return {(d, r): n / (area_before[d] + area_now[r] - n)
            for d, r, n in zip(*(x.tolist() for x in np.divmod(pairs, k)), shared.tolist())}


def by_number(rep: dict[int, int], source: dict[int, int], numbers: dict[int, int]
              ) -> tuple[dict[int, int], dict[int, int]]:
    """The groups under their numbers: ``rep`` (id -> group label) as id -> its group's
    number (0 where the group has none: not shown), and ``source`` (group label -> the
    member whose twist it reports) as number -> member.

    Args:
        rep: id -> the label of the group it is shown under (0 = not shown).
        source: group label -> member id (:func:`motionbits.records.twist_sources`).
        numbers: group label -> number (:meth:`ShownNumbers.assign`).
    """
    return ({i: numbers.get(r, 0) for i, r in rep.items()},
            {numbers[r]: m for r, m in source.items() if r in numbers})


class ShownNumbers:
    """The numbers the marks of one shot are shown under (module docstring).

    State: the number each living MotionBit id was last shown under (and whether that
    was at the last frame), and the shown label maps of the last ``RECENT_FRAMES``
    frames, numbered. A new shot starts a new instance.
    """

    def __init__(self) -> None:
        self._last: dict[int, int] = {}  # MotionBit id -> its number at the last frame
        self._earlier: dict[int, int] = {}  # id -> its number, last shown before that
        # the marks shown at the last frames, numbered ((h, w) int32), with their
        # label_areas; the latest last
        self._recent: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=RECENT_FRAMES)

    def assign(self, shown: np.ndarray, state: np.ndarray, rep: dict[int, int],
               next_id: int) -> tuple[dict[int, int], int]:
        """The number of each mark shown at this frame; remembered for the next.

        Args:
            shown: (h, w) int32 the marks shown, under their group labels (0 = none).
            state: (h, w) int32 the MotionBit ids the groups are made of, same size.
            rep: id -> the group label it is shown under (0 = not shown), every id
                present.
            next_id: the first id not yet given to any MotionBit or number.

        Returns:
            group label -> number for each label in ``shown`` (the numbers are distinct
            and > 0), and the next free id (past the fresh numbers given).
        """
        shown_areas = label_areas(shown)
        groups = set((np.flatnonzero(shown_areas[1:]) + 1).tolist())
        areas = label_areas(state)
        numbers: dict[int, int] = {}
        for memory in (self._last, self._earlier):  # the last frame's claims first
            taken = set(numbers.values())
            numbers.update(match_greedy({
                (d, r): w for (d, r), w in inherited_weights(areas, rep, memory).items()
                if r in groups and r not in numbers and d not in taken}))
        for before, before_areas in reversed(self._recent):  # reborn: the latest first
            orphans, taken = groups - numbers.keys(), set(numbers.values())
            if not orphans:
                break
            numbers.update(match_greedy({
                (d, r): iou for (d, r), iou in mask_ious(shown, before, shown_areas,
                                                         before_areas).items()
                if r in orphans and d not in taken and iou >= REBORN_IOU}))
        taken = set(numbers.values())
        for r in sorted(groups - numbers.keys()):
            number = r
            if r in taken:  # another mark holds it: a fresh number
                number, next_id = next_id, next_id + 1
            numbers[r] = number
            taken.add(number)
        self._earlier = {i: self._last.get(i, self._earlier.get(i)) for i in rep
                         if i in self._last or i in self._earlier}  # the living only
        self._last = {i: numbers[r] for i, r in rep.items() if r in numbers}
        for i in self._last:
            self._earlier.pop(i, None)
        # the numbers are one-to-one over the marks: the areas are the marks' own
        numbered_areas = np.zeros(max(numbers.values(), default=0) + 1, shown_areas.dtype)
        numbered_areas[list(numbers.values())] = shown_areas[list(numbers)]
        numbered_areas[0] = shown_areas[0]
        self._recent.append((group_map(shown, numbers), numbered_areas))
        return numbers, next_id
