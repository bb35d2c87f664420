"""Did a MotionBit really move? Its origin image against its accumulated motion (ours).

A MotionBit can be born where the flow moved and the world did not: in the wake of an arm
sweeping in front of a wall, under smeared flow beside a fast body. Such a MotionBit then
stops, and a stopped MotionBit keeps its mask -- so it would stay for good. The test that
tells it from a body that really moved and stopped: keep the frame before its birth, and the motion accumulated since (current -> that frame) both of
the MotionBit and of the static world (the camera's motion; identity for a static camera).
If the world's motion explains the MotionBit's pixels today clearly better than its own
accumulated motion does, it never moved: it is retired. A moving shadow or a light change
is explained by the static world too, once a local brightness gain is allowed -- the same
gain on every colour channel, so that a body of another colour is not.

The same images tell, pixel by pixel, where the static world is seen again
(:func:`seen_again`): a pixel that looks as it did in the first frame or before its
MotionBit's birth shows no motion, whatever label the flow carried there.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage

from motionbits.twists import rigid_matrix

__all__ = ["Origin", "origin_residuals", "moved_evidence", "retire", "seen_again"]

#: px: below this median distance between where a MotionBit's own and the world's
#: accumulated motions put its pixels, the two cannot be told apart (no verdict).
MIN_SEPARATION = 2.0
#: About this many of a MotionBit's pixels measure that distance.
SEPARATION_SAMPLES = 200
#: px: side of the square over which a local brightness gain is estimated (a shadow's or
#: a light's gain is smooth over it) ...
GAIN_WINDOW = 9
#: ... within [MIN_GAIN, 1 / MIN_GAIN], with this many grey levels added to each channel
#: first (dark pixels have noisy ratios) ...
MIN_GAIN, GAIN_OFFSET = 0.25, 8.0
#: ... and only a gain this far from 1 (log) is a light change: near 1 the plain
#: residual decides.
MIN_LOG_GAIN = 0.14
IDENTITY = np.eye(3)
#: px: side of the square over which :func:`seen_again` averages residuals.
SEEN_WINDOW = 5


@dataclass
class Origin:
    """Where a MotionBit came from.

    Attributes:
        frame: (H, W) float32 grey frame before its birth (shared, never modified).
        body: (3, 3) accumulated backward motion of the MotionBit (current -> birth frame).
        world: (3, 3) accumulated backward motion of the static world.
        colour: (H, W, 3) float32 RGB of ``frame``, or None (then no light-change test).
    """

    frame: np.ndarray
    body: np.ndarray
    world: np.ndarray
    colour: np.ndarray | None = None

    def advance(self, body_step: np.ndarray, world_step: np.ndarray) -> None:
        """Compose one more frame's (3, 3) backward motions (current -> previous)."""
        self.body = self.body @ body_step
        self.world = self.world @ world_step


def _pull(frame: np.ndarray, motion: np.ndarray, box: tuple[slice, slice]) -> np.ndarray:
    """``frame`` (H, W) or (H, W, C) pulled back by the (3, 3) ``motion`` onto the image box
    ``box``: ``out(p) = frame(motion p)``, NaN where that falls outside ``frame``."""
    if np.array_equal(motion, IDENTITY):  # a static camera's world: the box itself
        return frame[box].astype(np.float32)  # (copy) what the bilinear warp gives
    to_frame = motion @ np.array(
        [[1.0, 0.0, box[1].start], [0.0, 1.0, box[0].start], [0.0, 0.0, 1.0]])
    size = (box[1].stop - box[1].start, box[0].stop - box[0].start)
    nan = (np.nan,) * (frame.shape[2] if frame.ndim == 3 else 1)
    return cv2.warpPerspective(frame, to_frame, size,
                               flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                               borderMode=cv2.BORDER_CONSTANT, borderValue=nan)


def _mean_inside(diff: np.ndarray, inside: np.ndarray) -> float:
    """Mean of the finite ``diff`` over ``inside``; NaN if under half of it is finite."""
    d = diff[inside]
    d = d[np.isfinite(d)]
    return float(d.mean()) if d.size > 0.5 * inside.sum() else np.nan


def _residual(frame: np.ndarray, motion: np.ndarray, cur: np.ndarray, box, inside) -> float:
    """Mean |cur - frame pulled back by ``motion``| over ``inside`` of the image box ``box``
    (NaN if less than half of those pixels come from inside ``frame``)."""
    return _mean_inside(np.abs(cur[box] - _pull(frame, motion, box)), inside)


def _darker_or_brighter(origin: Origin, cur_gray: np.ndarray, box, inside) -> bool:
    """Whether the mean grey level over ``inside`` of the image box ``box`` changed by a
    gain at least half ``MIN_LOG_GAIN`` away from 1 since ``origin``'s frame (pulled back by
    the static world's motion): a cheap test before :func:`relit_residual`."""
    ref = _pull(origin.frame, origin.world, box)[inside]
    ok = np.isfinite(ref)
    if ok.sum() <= 0.5 * inside.sum():
        return False
    ratio = (cur_gray[box][inside][ok].mean() + GAIN_OFFSET) / (ref[ok].mean() + GAIN_OFFSET)
    return abs(np.log(ratio)) >= 0.5 * MIN_LOG_GAIN


def relit_residual(colour: np.ndarray, motion: np.ndarray, cur_rgb: np.ndarray, box, inside
                   ) -> float:
    """Mean colour residual (grey levels, mean over channels) over ``inside`` of the image
    box ``box`` of ``cur_rgb`` ((H, W, 3), any dtype) against the (H, W, 3) float32
    ``colour`` frame pulled back by
    ``motion`` and scaled by the local brightness gain (one per pixel, the same on every
    channel: ratio of ``GAIN_WINDOW`` square means of the channel sums).

    NaN where under half of the pixels come from inside the frame, or where the median
    gain is within ``MIN_LOG_GAIN`` of 1 (no light change: the plain residual decides)."""
    ref = _pull(colour, motion, box)
    valid = np.isfinite(ref[..., 0])
    ref = np.where(valid[..., None], ref + GAIN_OFFSET, 0).astype(np.float32)
    cur = cur_rgb[box].astype(np.float32) + GAIN_OFFSET
    k = (GAIN_WINDOW, GAIN_WINDOW)
    num = cv2.blur(np.where(valid, cur.sum(axis=2), 0).astype(np.float32), k)
    gain = np.clip(num / np.maximum(cv2.blur(ref.sum(axis=2), k), 1e-3), MIN_GAIN, 1 / MIN_GAIN)
    sel = inside & valid
    if sel.sum() <= 0.5 * inside.sum() or abs(np.log(np.median(gain[sel]))) < MIN_LOG_GAIN:
        return np.nan
    return float(np.abs(cur - gain[..., None] * ref).mean(axis=2)[sel].mean())


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


def moved_evidence(origin: Origin, cur_gray: np.ndarray, mask: np.ndarray,
                   min_separation: float, corner: tuple[int, int] = (0, 0)) -> float:
    """Grey levels by which the MotionBit's own accumulated motion explains its pixels
    ``mask`` (bool) in ``cur_gray`` better than the static world's motion does
    (negative: it never moved); NaN and ``corner`` as in :func:`origin_residuals`."""
    world, body = origin_residuals(origin, cur_gray, mask, min_separation, corner)
    return world - body


def retire(labels: np.ndarray, origins: dict[int, Origin], ids: np.ndarray,
           thetas: np.ndarray, trans: np.ndarray, first_new: int, cam: np.ndarray | None,
           prev_gray: np.ndarray, cur_gray: np.ndarray, margin: float, *,
           explained: float = np.inf, first: Origin | None = None,
           relit: float = 0.0, prev_rgb: np.ndarray | None = None,
           cur_rgb: np.ndarray | None = None) -> tuple[np.ndarray, dict[int, Origin]]:
    """Advance every MotionBit's origin by this frame's motions and retire those whose
    pixels the static world explains -- within ``explained`` grey levels (mean residual),
    from the frame before the MotionBit's birth or from the stream's first frame
    (``first``) -- and better, by more than ``margin`` grey levels, than their own
    accumulated motion (:func:`origin_residuals`). Where no frame explains them (a body
    carried and set down: the fitted motion of a body lowered in depth drifts, and the
    static world shows what was there before it arrived) the MotionBit stays; the first
    frame still explains background that an arm covered at a MotionBit's birth. A
    MotionBit whose pixels the static world explains within ``relit`` grey levels up to a
    light change (:func:`relit_residual`: a shadow, a reflection, a flicker), and better
    than its own motion by ``margin``, is retired too.

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
        relit: grey levels (config ``relit_tolerance``; 0 = no light-change test).
        prev_rgb, cur_rgb: (H, W, 3) RGB (uint8 or float32) of the previous (not
            stabilised) and current frames (needed for ``relit``).

    Returns:
        ``labels`` without the retired MotionBits, and the origins of those present.
    """
    world = np.eye(3) if cam is None else cam
    own = {int(i): world @ np.vstack([rigid_matrix(th, t), [0.0, 0.0, 1.0]])
           for i, th, t in zip(ids, thetas, trans)}
    boxes = {i + 1: box for i, box in enumerate(ndimage.find_objects(labels)) if box}
    origins = {i: o for i, o in origins.items() if i in boxes}
    out = labels
    if first is not None:
        first.advance(world, world)
    born_rgb = None  # prev_rgb as float32, once
    for i, box in boxes.items():
        if i >= first_new:
            if born_rgb is None and prev_rgb is not None:
                born_rgb = prev_rgb.astype(np.float32)
            origins[i] = Origin(prev_gray, np.eye(3), np.eye(3), born_rgb)
        origin = origins.get(i)
        if origin is None:
            continue
        origin.advance(own.get(i, world), world)
        mask = labels[box] == i
        world_res, body_res = origin_residuals(origin, cur_gray, mask, MIN_SEPARATION,
                                               (box[0].start, box[1].start))
        if not np.isfinite(body_res):
            continue
        frames = (origin,) if first is None else (origin, first)
        if first is not None:
            from_first = _residual(first.frame, first.world, cur_gray, box, mask)
            if np.isnan(world_res) or from_first < world_res:  # NaN: out of view then
                world_res = from_first
        still = world_res < explained and world_res - body_res < -margin
        if not still and relit and cur_rgb is not None and body_res > margin:
            lit = [relit_residual(o.colour, o.world, cur_rgb, box, mask)
                   for o in frames if o.colour is not None and _darker_or_brighter(
                       o, cur_gray, box, mask)]
            still = any(r < relit and r - body_res < -margin for r in lit)
        if still:
            out = np.where(out == i, 0, out)
            del origins[i]
    return out, origins


def seen_again(labels: np.ndarray, earned: np.ndarray, origins: dict[int, Origin],
               first: Origin | None, cur_gray: np.ndarray, tolerance: float, ids
               ) -> np.ndarray:
    """(H, W) bool: ``earned`` pixels of the MotionBits ``ids`` where the static world is
    seen again -- the frame before the MotionBit's birth or the stream's first frame,
    pulled back by the static world's accumulated motion, matches the current frame within
    ``tolerance`` grey levels (mean over a ``SEEN_WINDOW`` square).

    Such a pixel shows no motion now, whatever label the flow carried onto it (the table a
    hand passed over, a shadow's wake): it loses the evidence that lets a carried label
    beat the background on a flat region (``earned``, see
    :func:`motionbits.masks.assign_pixels`). Only moving MotionBits are tested: a body
    that moved a little and stopped looks much as it did before it moved, and keeps its
    mask by that evidence.

    Args:
        labels: (H, W) int32 label map of this frame.
        earned: (H, W) bool evidence of motion of each pixel's label.
        origins: id -> :class:`Origin` of the MotionBits present (as :func:`retire` leaves them).
        first: the stream's first frame (advanced to this frame), or None.
        cur_gray: (H, W) float32 current grey frame.
        tolerance: grey levels (config ``seen_tolerance``).
        ids: the MotionBits to test (those moving now).
    """
    out = np.zeros(labels.shape, bool)
    h, w = labels.shape
    pad = SEEN_WINDOW // 2
    tested = np.where(earned & np.isin(labels, list(ids)), labels, 0)
    for i, box in enumerate(ndimage.find_objects(tested), start=1):
        if box is None:
            continue
        refs = [o for o in (origins.get(i), first) if o is not None]
        if len(refs) == 2 and refs[0].frame is refs[1].frame and np.allclose(
                refs[0].world, refs[1].world):
            refs = refs[:1]  # born at the first frame: one reference
        big = (slice(max(box[0].start - pad, 0), min(box[0].stop + pad, h)),
               slice(max(box[1].start - pad, 0), min(box[1].stop + pad, w)))
        best = None
        for o in refs:
            diff = cv2.blur(np.abs(cur_gray[big] - _pull(o.frame, o.world, big)),
                            (SEEN_WINDOW, SEEN_WINDOW))
            best = diff if best is None else np.fmin(best, diff)
        if best is not None:
            out[big] |= (tested[big] == i) & (best < tolerance)
    return out
