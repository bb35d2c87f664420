"""Marks that fall apart: one shown mark, one connected body (ours).

The masks are shown one per group of MotionBits whose motions agree
(:class:`motionbits.merging.MotionBitGroups`). One rigid body seen whole is one connected
region; a mark whose pixels fall apart into pieces well apart from each other shows more
than one thing: two blocks carried side by side and set down together, a body and the
static pieces that a moving camera's model left moving with it, a block and the arm that
let go of it, two hands that moved alike. Each piece large enough to be shown by itself
(``min_area``) and farther than ``gap`` px from the rest is shown as a mark of its own,
under the MotionBit that holds most of it (with the members that lie mostly in it), or,
where that MotionBit is the mark's own (one MotionBit on both pieces), under a label of
its own that reports that MotionBit's twist. The largest piece keeps the mark.

Only the marks shown are split: the groups stay as they are, so a piece that comes
back together with the rest is one mark again. Moving-camera pick-and-place, round 56:
thirteen held-out folders 58.3 -> 59.5 mIoU (each +0.3 to +2.2, at most one scene lower
in any), 0.25-0.6 more spurious marks per scene (the static pieces that were part of a
body's mark are marks of their own); docs/reading_the_paper.md, "One mark, one connected
body".
"""

from __future__ import annotations

import numpy as np

from motionbits.boxes import label_areas, label_pieces

__all__ = ["GAP_CELLS", "split_apart"]

#: grid cells: the pieces of a mark farther apart than this are shown apart (half a cell,
#: 3 px at the default grid on 480x640: the pieces of one body a thin occluder divides, a
#: finger or a cable, stay one mark only if it is thinner).
GAP_CELLS = 0.5


def split_apart(shown: np.ndarray, state: np.ndarray, rep: dict[int, int],
                source: dict[int, int], next_id: int, *, gap: int, min_area: float
                ) -> tuple[np.ndarray, dict[int, int], dict[int, int], int]:
    """Each shown mark split into its pieces more than ``gap`` px apart (module docstring).

    Args:
        shown: (H, W) int32 marks under their group labels (0 = none).
        state: (H, W) int32 MotionBit ids the groups are made of, same size.
        rep: id -> the group label it is shown under (0 = not shown).
        source: group label -> the member whose twist it reports
            (:func:`motionbits.records.twist_sources`).
        next_id: the first id not yet given to any MotionBit or label.
        gap: px; pieces of a mark closer than this are one piece.
        min_area: px; only pieces this large are shown apart (smaller ones stay with
            their mark).

    Returns:
        (shown, rep, fresh, next_id): every piece apart other than each mark's largest
        under the id of the MotionBit that holds most of it (``rep`` maps it and the
        members that lie mostly in it there), or under a fresh label where that
        MotionBit is the mark's own, another mark's, or none: ``fresh`` maps each fresh
        label to the member whose twist its mark reported (``source``), and ``next_id``
        moves past them. ``shown`` and ``rep`` themselves (the same objects) where
        nothing falls apart; the inputs are never written.
    """
    areas = label_areas(shown)
    marks = np.flatnonzero(areas[1:] >= 2 * min_area) + 1
    if not marks.size:
        return shown, rep, {}, next_id
    used = set((np.flatnonzero(areas[1:]) + 1).tolist())  # the labels shown
    out, new_rep, fresh, state_areas = shown, rep, {}, None
    for p in label_pieces(shown, marks.tolist(), gap=gap):
        large = np.flatnonzero(p.areas >= min_area)
        if large.size < 2:
            continue
        if out is shown:
            out, new_rep = shown.copy(), dict(rep)
            state_areas = label_areas(state)
        held = state[p.box]
        for k in large[large != p.largest].tolist():
            piece = p.pieces == k
            ids = held[piece]
            counts = np.bincount(ids[ids > 0], minlength=1)
            owner = int(counts.argmax())
            if owner == 0 or owner in used:  # no MotionBit of its own to show it under
                out[p.box][piece] = next_id
                if p.label in source:
                    fresh[next_id] = source[p.label]
                used.add(next_id)
                next_id += 1
                continue
            out[p.box][piece] = owner
            used.add(owner)
            for i in np.flatnonzero(counts).tolist():
                if new_rep.get(i) == p.label and 2 * counts[i] > state_areas[i]:
                    new_rep[i] = owner
            new_rep[owner] = owner
    return out, new_rep, fresh, next_id
