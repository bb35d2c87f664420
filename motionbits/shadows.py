"""Marks without cast shadows: the static world, dimmed, is not part of a body (ours).

A body carried or pushed over a table casts a shadow that moves with it, and the flow
moves the shadow's edges as the body's: the clustering gives the shadow the body's
MotionBit, and the mark shown covers the body and the table beside it (a block set down on
wood grain: 2575 px of block, a mark of 5200 px). What lies under a cast shadow is the
static world as :class:`motionbits.revealed.StaticMemory` remembers it, darker, with its
colour and its texture (:meth:`StaticMemory.shadowed`) -- or, where a shadow stood still
long enough for that memory to take it in, the scene as first seen
(:class:`motionbits.completion.FirstLook`), dimmed. The masks shown leave such pixels out:

- only where the remembered world has texture (mean gradient above ``TEXTURE`` grey
  levels per px), each look on its own texture (round 50: the first look's dimmed look
  was judged on the static memory's texture, which may hold the body set down there, its
  edges textured; a grey block's dark face on a plain patch of marble passed for a
  shadow): on a flat table a flat face of a body in the table's hue, darker, passes
  for a shadow, and nothing tells the two apart;
- not where the memory holds the mark's own body, seen at rest (remembered with its id):
  a body that a shadow passes over is still the body;
- only pieces of shadow (an opening by ``OPEN`` px keeps them), so that single pixels of a
  body that happen to match do not fray its mark;
- a mark of which at most ``BODY_SHARE`` is shadow loses those pixels, but not where
  they would leave a hole inside it (a cast shadow lies beside its body; a pale face of a
  body that stood there before it moved looks like the scene first seen there, darker);
  a mark mostly shadow is not shown at all (the agent's shadow, left on the table as a
  mark at rest).

The state keeps the motion's masks; only the masks shown change (docs/results.md,
"Cast shadows", round 27). Completion, before this step, gets the same pixels
(:func:`shadow_map`; :func:`motionbits.completion.complete_masks`): a mark at rest gives
back those through which the texture first seen there shows, however much of it they
are (round 50).
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.boxes import grow_box, label_areas, nonzero_box, run_counts
from motionbits.completion import FirstLook
from motionbits.evidence import gradient_magnitude
from motionbits.masks import drop_labels, fill_holes
from motionbits.revealed import StaticMemory, dimmed

__all__ = ["cast_shadows", "shadow_map", "trim_shadows", "TEXTURE", "TEXTURE_REACH", "OPEN",
           "BODY_SHARE"]

#: Grey levels per px: the remembered world's mean gradient (5x5, then 7x7 mean) above which
#: a dimmed look of it is told from a body's flat face (flat tables read 0.2-0.3, wood grain
#: and marble 2-6 under the shadows of the pick-and-place track).
TEXTURE = 1.0
#: px: how far the texture test's answer at a pixel reads (Sobel 1, then means over 5 and 7).
TEXTURE_REACH = 1 + 5 // 2 + 7 // 2
#: px: pieces of shadow kept by an opening with a square of this side (at the working size).
OPEN = 5
#: A mark loses its shadow pixels when they are at most this share of it; beyond, it is a
#: shadow and is not shown.
BODY_SHARE = 0.5


def cast_shadows(memory: StaticMemory, cur: np.ndarray, labels: np.ndarray,
                 first: FirstLook | None = None
                 ) -> tuple[tuple[slice, slice], np.ndarray] | None:
    """Where the labelled part of the frame shows the remembered static world under a cast
    shadow, on texture (module docstring). Call between the memory's ``observe`` and
    ``update``.

    Args:
        memory: the static world's look where it was last seen still.
        cur: (H, W, 3) uint8 current RGB frame.
        labels: (H, W) int label map of this frame.
        first: the scene's look where first seen still, or None: a shadow that stood
            still for a while is in ``memory``'s look, not in the first one.

    Returns:
        (the box of the labels, (h, w) bool on it), or None when nothing is labelled or
        the memory is off.
    """
    box = nonzero_box(labels)
    if box[0].stop == box[0].start:
        return None
    # a body at rest is remembered as itself (with its id): dimmed, it is still the body
    # (pixels of no MotionBit, where completion may grow a mark, keep the test)
    shadow = memory.shadowed(cur, box, labels)
    if shadow is None:
        return None
    shadow &= _textured(memory.gray[box])
    if first is not None:  # each look on its own texture (tested only around what it finds)
        seen = dimmed(cur, first.look, first.known, box, memory.tolerance)
        if seen.any():
            near = grow_box(nonzero_box(seen), TEXTURE_REACH, seen.shape)
            look = first.look[box][near]
            seen[near] &= _textured(cv2.cvtColor(look, cv2.COLOR_RGB2GRAY))
            shadow |= seen
    return box, shadow


def shadow_map(shadows: tuple[tuple[slice, slice], np.ndarray] | None,
               shape: tuple[int, int]) -> np.ndarray | None:
    """(H, W) bool of ``shape``: the pixels of :func:`cast_shadows`' answer, over the
    whole frame (None: None)."""
    if shadows is None:
        return None
    box, shadow = shadows
    out = np.zeros(shape, bool)
    out[box] = shadow
    return out


def _textured(gray: np.ndarray) -> np.ndarray:
    """(h, w) bool: where the (h, w) grey look has texture (its gradient magnitude's
    7x7 mean above ``TEXTURE``)."""
    return cv2.blur(gradient_magnitude(gray.astype(np.float32, copy=False)), (7, 7)) > TEXTURE


def trim_shadows(shown: np.ndarray, shadows: tuple[tuple[slice, slice], np.ndarray] | None
                 ) -> np.ndarray:
    """``shown`` (H, W) int32 marks without their pieces of cast shadow, and without the
    marks that are mostly shadow (module docstring); ``shadows`` from
    :func:`cast_shadows` (None: ``shown`` itself)."""
    if shadows is None:
        return shown
    box, shadow = shadows
    sub = shown[box]
    on = shadow & (sub > 0)
    if not on.any():
        return shown
    on = cv2.morphologyEx(on.view(np.uint8), cv2.MORPH_OPEN, np.ones((OPEN, OPEN), np.uint8)) > 0
    area = label_areas(shown)  # whole marks (completion may have grown one out of the box)
    dark = run_counts(sub[on], area.size)  # shadow px per mark
    gone = dark > BODY_SHARE * area
    cut = (dark > 0) & ~gone
    cut[0] = gone[0] = False
    if not (cut.any() or gone.any()):
        return shown
    out = shown.copy()
    trimmed = on & cut[sub]
    kept = np.where(trimmed, 0, sub)
    # a hole it would leave inside a mark is not a cast shadow: a face of the body that
    # looks like the scene first seen there, darker (it stood there before it moved)
    filled = fill_holes(kept)
    out[box] = np.where(trimmed & (filled > 0), filled, kept)
    return drop_labels(out, np.flatnonzero(gone))
