"""Revealed background: the static world seen again where a moving body uncovers it (ours).

Optical flow is smooth across motion boundaries, so the table a hand or an arm has just
uncovered gets the hand's flow (the flow "smears" into its wake), and both of the
segmenter's hypotheses fail there: the hand's motion pulls back the hand, "nothing moved"
the hand too -- it covered the pixel a frame ago. The wake then becomes part of the hand's
MotionBit or a new one (a ghost). What explains such a pixel is the static world as it was
*before* the body covered it. :class:`StaticMemory` keeps, for each pixel, its colour
when it was last seen standing still, and whether something with another look has covered
it since; a pixel that looks as remembered again after being covered is *revealed*
background (:meth:`StaticMemory.observe`), which "nothing moved" explains. The price: a
body the hand covers and then lifts by a few pixels looks as it did at rest, and loses
those pixels (docs/reading_the_paper.md, "Background seen again").

Under a moving camera the memory follows the static world: each frame it is warped by
the camera's model of the static world (homography and parallax, ``CameraMotion.world``)
before it is compared, so the table an arm or its passing shadow has just uncovered is
"nothing moved" there too (births on static surfaces whose look changed were the largest
share of the moving camera's static false positives), and the cast-shadow test
(:meth:`StaticMemory.shadowed`) reads the memory so carried (docs/reading_the_paper.md,
"Moving cameras").
A body that stood still at first and moves away reveals what it hid, which the memory
never saw: nothing changes there. A body that comes to rest is remembered as
it is once it is seen still, so a stopped body is never "revealed" away -- and with it
the id of its MotionBit: when a hand (or another body, or a shadow) has passed in front
of it, its pixels seen again as they were take that id back (:meth:`StaticMemory.restore`),
unless that MotionBit moves now or was retired. The MotionBits at rest follow the same
model: under a moving camera their labels are carried with it rather than with the flow
(:func:`carry_at_rest`; docs/reading_the_paper.md, "Moving cameras", round 24).
"""

from __future__ import annotations

from collections.abc import Callable, Collection

import cv2
import numpy as np

from motionbits.boxes import grow_box

__all__ = ["StaticMemory", "light_change", "brightness", "gain_of", "chroma_change",
           "dimmed", "texture_shows", "follow_known", "follow_look", "follow_ids",
           "carry_at_rest"]

#: px, side of the square over which grey-level differences are averaged.
WINDOW = 5
#: Largest change of chromaticity (each channel over the sum of the three) of a static
#: pixel under a cast shadow: a shadow dims the light on a surface, not its colour.
SHADOW_CHROMA = 0.03
#: A cast shadow leaves a pixel at a fraction of its remembered brightness in this range.
SHADOW_GAIN = (0.2, 0.85)
#: px, side of the square over which a shadow's gain is taken as constant.
SHADOW_WINDOW = 9
#: Remembered pixels darker than this sum of the three channels have no reliable colour.
SHADOW_MIN_SUM = 60
#: Under a moving camera a pixel stays known where the bilinear weights of the known
#: pixels its memory is read from exceed this (all four; float rounding aside).
KNOWN_WEIGHT = 0.999


def _color_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(H, W) uint8 ``WINDOW``-mean absolute difference of two (H, W, 3) uint8 images, the
    largest over the channels (a red block on a green table of the same grey level
    differs)."""
    r, g, b_ = cv2.split(cv2.blur(cv2.absdiff(a, b), (WINDOW, WINDOW)))
    return cv2.max(cv2.max(r, g), b_)


def grey_change(cur_gray: np.ndarray, prev_gray: np.ndarray) -> np.ndarray:
    """(H, W) float32 ``WINDOW``-mean absolute change of grey level between two (H, W)
    float32 frames: where it is small, a pixel stands still (:meth:`StaticMemory.update`,
    :meth:`motionbits.arrivals.Arrivals.find`)."""
    return cv2.blur(cv2.absdiff(cur_gray, prev_gray), (WINDOW, WINDOW))


#: (1, 3) float32: :func:`brightness` as OpenCV's per-pixel matrix transform
_CHANNEL_SUM = np.ones((1, 3), np.float32)


def brightness(image: np.ndarray) -> np.ndarray:
    """(...) float32 sum of the three channels of an (..., 3) uint8 (or float32) image
    (an (H, W, 3) uint8 image by OpenCV -- integer sums, exact in float32 in any order --
    else channel by channel: numpy's sums along a last axis of 3 are ~10x slower)."""
    if image.ndim == 3 and image.dtype == np.uint8:
        return cv2.transform(image.astype(np.float32), _CHANNEL_SUM)
    return (image[..., 0].astype(np.float32) + image[..., 1].astype(np.float32)
            + image[..., 2].astype(np.float32))


def light_change(now: np.ndarray, then: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """How the colours ``then`` look as ``now`` -- each (..., 3) uint8 (or float32) --
    differ as a change of light would: ``(chroma, gain, sum_now, sum_then)``, each
    (...) float32, with ``chroma`` the largest change of chromaticity (each channel over
    the sum of the three, +1) and ``gain`` the ratio of brightness (the sums, +8 each, so
    that dark pixels do not explode)."""
    sum_now, sum_then = brightness(now), brightness(then)
    return chroma_change(now, then, sum_now, sum_then), gain_of(sum_now, sum_then), \
        sum_now, sum_then


def gain_of(sum_now: np.ndarray, sum_then: np.ndarray) -> np.ndarray:
    """(...) float32 ratio of brightness of :func:`light_change` from the two
    :func:`brightness` sums."""
    return (sum_now + 8) / (sum_then + 8)


def chroma_change(now: np.ndarray, then: np.ndarray, sum_now: np.ndarray,
                  sum_then: np.ndarray) -> np.ndarray:
    """(...) float32 largest change of chromaticity of :func:`light_change`, given the
    (..., 3) colours and their :func:`brightness` sums."""
    scale_now, scale_then = sum_now + 1, sum_then + 1
    chroma = None
    for c in range(3):
        change = np.abs(now[..., c].astype(np.float32) / scale_now
                        - then[..., c].astype(np.float32) / scale_then)
        chroma = change if chroma is None else np.maximum(chroma, change, out=chroma)
    return chroma


def follow_known(known: np.ndarray, world: np.ndarray) -> np.ndarray:
    """(H, W) bool ``known`` carried to the current frame of a moving camera (``world``:
    (H, W, 2) float32, :func:`motionbits.camera.world_maps`): known only where all four
    pixels it is read from were (``KNOWN_WEIGHT``); what has just come into view is not."""
    return cv2.remap(known.astype(np.float32), world, None, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=0.0) > KNOWN_WEIGHT


def follow_look(image: np.ndarray, world: np.ndarray) -> np.ndarray:
    """An (H, W[, C]) remembered image carried along ``world``, bilinearly."""
    return cv2.remap(image, world, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def follow_ids(ids: np.ndarray, world: np.ndarray) -> np.ndarray:
    """An (H, W) int32 map of ids carried along ``world`` (nearest; 0 off the frame)."""
    return cv2.remap(ids.astype(np.float32), world, None, cv2.INTER_NEAREST,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=0.0).astype(np.int32)


def carry_at_rest(prior: np.ndarray, valid: np.ndarray, labels: np.ndarray,
                  world: np.ndarray, resting: Collection[int],
                  consistent: Callable[[], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Under a moving camera, the MotionBits at rest carried with the static world's model
    instead of the flow (ours).

    A body at rest moves with the static world: the camera's model (homography and
    parallax, smooth) carries its mask where the flow (noisy at its outline, smeared
    where it meets a moving body) frays it a little more each frame.

    Args:
        prior: (H, W) int32 last frame's labels carried by the flow.
        valid: (H, W) bool, where ``prior`` is trustworthy.
        labels: (H, W) int32 last frame's labels.
        world: (H, W, 2) float32, where each pixel's static world was at the last frame.
        resting: ids at rest at the last frame.
        consistent: called once, only if a resting id has pixels: (H, W) bool, where the
            current frame looks like the last one carried by ``world`` (the stabilised
            previous frame).

    Returns:
        ``prior`` and ``valid`` with the resting ids' pixels taken from ``labels`` carried
        by ``world`` (valid where ``consistent``); the same objects if none rests.
    """
    rest = np.fromiter(resting, np.int64)
    if not rest.size:
        return prior, valid
    followed = follow_ids(labels, world)
    new = np.isin(followed, rest)
    old = np.isin(prior, rest)
    if not (new.any() or old.any()):
        return prior, valid
    # the flow's pixels of a resting id give way; a resting id's pixels by the model take
    # what the flow left free or gave to another resting id
    take = new & ((prior == 0) | old)
    prior = np.where(take, followed, np.where(old, 0, prior))
    valid = np.where(take, consistent(), valid)
    return prior, valid


def texture_shows(sum_now: np.ndarray, sum_then: np.ndarray, gain: np.ndarray,
                  tolerance: float) -> np.ndarray:
    """(h, w) bool: where the brightness ``sum_now`` (sum of the three channels, (h, w)
    float32) is the remembered ``sum_then`` times ``gain`` (h, w; the dimming, taken over
    a window around each pixel) within ``tolerance`` grey levels (``WINDOW`` mean, per
    channel): the texture under a shadow is the remembered one, dimmed; another surface
    of the same colour has its own."""
    return cv2.blur(np.abs(sum_now - gain * sum_then), (WINDOW, WINDOW)) < 3 * tolerance


def dimmed(cur: np.ndarray, then: np.ndarray, known: np.ndarray, box: tuple[slice, slice],
           tolerance: float, where: np.ndarray | None = None) -> np.ndarray:
    """(h, w) bool on the image box ``box``: where (H, W, 3) uint8 ``cur`` shows ``then``
    (known where ``known``) under a shadow (:meth:`StaticMemory.shadowed`); only among the
    pixels ``where`` ((h, w) bool; None: all) when given."""
    # grown by the windows' reach, so that the answer is the whole image's, cropped
    grown = grow_box(box, SHADOW_WINDOW // 2 + WINDOW // 2, known.shape)
    y0, x0 = grown[0].start, grown[1].start
    inner = (slice(box[0].start - y0, box[0].stop - y0),
             slice(box[1].start - x0, box[1].stop - x0))
    now, past = cur[grown], then[grown]
    sum_now, sum_then = brightness(now), brightness(past)
    gain = gain_of(sum_now, sum_then)
    local = cv2.blur(gain, (SHADOW_WINDOW, SHADOW_WINDOW))
    shadow = (known[box] & (sum_then[inner] > SHADOW_MIN_SUM) & (gain[inner] > SHADOW_GAIN[0])
              & (gain[inner] < SHADOW_GAIN[1])
              & texture_shows(sum_now, sum_then, local, tolerance)[inner])
    if where is not None:
        shadow &= where
    # the colour last, only where the rest holds (most pixels of a box are lit as before)
    chroma = chroma_change(now[inner][shadow], past[inner][shadow],
                           sum_now[inner][shadow], sum_then[inner][shadow])
    shadow[shadow] = chroma < SHADOW_CHROMA
    return shadow


class StaticMemory:
    """Per-pixel look of the static world where it was last seen still.

    Each frame, :meth:`observe` first (what is revealed), then :meth:`update`.

    Args:
        shape: (H, W) of the working frames.
        tolerance: grey levels (``WINDOW`` mean; 0 = off): a pixel looks as remembered
            within this on every channel; a pixel whose grey level changed less than this
            over a frame, under reliable flow that moves it less than the move threshold,
            is seen standing still.
        covered: grey levels (``WINDOW`` mean, largest channel): a pixel that differs
            from its memory by more than this was covered by something else.
    """

    def __init__(self, shape: tuple[int, int], tolerance: float, covered: float) -> None:
        self.tolerance, self.covered = tolerance, covered
        self.color = np.zeros((*shape, 3), np.uint8)  # remembered RGB
        self.gray = np.zeros(shape, np.float32)  # remembered grey level
        self.known = np.zeros(shape, bool)  # seen standing still at some frame
        self.was_covered = np.zeros(shape, bool)  # looked otherwise since
        self.label = np.zeros(shape, np.int32)  # MotionBit id when last seen still (0: none)
        self._difference: np.ndarray | None = None  # this frame's, from observe()

    def observe(self, cur: np.ndarray, cur_gray: np.ndarray, still: np.ndarray,
                world: np.ndarray | None = None) -> np.ndarray | None:
        """Compare the current frame with the memory; where it is revealed, lower the
        residual of "nothing moved" to the one against the remembered grey level.

        Args:
            cur: (H, W, 3) uint8 current RGB frame.
            cur_gray: (H, W) float32 current grey frame.
            still: (H, W) float32 grey levels by which "nothing moved" misses each pixel,
                lowered in place where revealed.
            world: where the camera moved between the last frame and this one, (H, W, 2)
                float32 where each pixel of the static world was in the last frame
                (``CameraMotion.world``): the memory follows it first (:meth:`follow`);
                None: a still camera.

        Returns:
            (H, W) bool, pixels covered since they were last seen still that look as they
            did then; None when the memory is off.
        """
        self._difference = None
        if self.tolerance <= 0:
            return None
        if world is not None:
            self.follow(world)
        self._difference = _color_difference(cur, self.color)
        revealed = self.known & self.was_covered & (self._difference < self.tolerance)
        # cv2.copyTo writes into ``still`` (np.copyto with ``where`` is ~20x slower)
        cv2.copyTo(np.minimum(still, cv2.absdiff(cur_gray, self.gray)), revealed.view(np.uint8),
                   still)
        return revealed

    def changed(self) -> np.ndarray | None:
        """(H, W) bool: pixels seen standing still before that look otherwise now (by more
        than ``covered``; this frame's :meth:`observe`), or None when the memory is off --
        something other than the static world stands there."""
        if self._difference is None:
            return None
        return self.known & (self._difference > self.covered)

    def follow(self, world: np.ndarray) -> None:
        """Carry the memory to the current frame of a moving camera: each pixel takes
        what was remembered where its static world was in the last frame (``world``,
        (H, W, 2) float32, :func:`motionbits.camera.world_maps`), bilinearly. A pixel is
        known only where all four pixels it is read from are (no colour is mixed with an
        unknown one), was covered where most of them were; what has just come into view
        is unknown."""
        covered = cv2.remap(self.was_covered.astype(np.float32), world, None,
                            cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        self.color = follow_look(self.color, world)
        self.gray = follow_look(self.gray, world)
        self.label = follow_ids(self.label, world)
        self.known = follow_known(self.known, world)
        self.was_covered = covered > 0.5

    def shadowed(self, cur: np.ndarray, box: tuple[slice, slice],
                 labels: np.ndarray | None = None) -> np.ndarray | None:
        """Where the image box ``box`` shows the remembered static world under a shadow:
        darker (``SHADOW_GAIN``), with the same colour (``SHADOW_CHROMA``) and the same
        texture -- the remembered grey levels times the local gain (``SHADOW_WINDOW`` mean)
        match within ``tolerance`` (``WINDOW`` mean) -- and, given this frame's
        ``labels``, not where the memory holds the MotionBit a pixel is labelled with now
        (a body remembered at rest, with its id: a shadow passing over it dims the body;
        round 46).

        Call between :meth:`observe` and :meth:`update`.

        Args:
            cur: (H, W, 3) uint8 current RGB frame.
            box: (rows, cols) slices of the image box.
            labels: (H, W) int label map of this frame, or None (every pixel is tested).

        Returns:
            (h, w) bool on the box; None when the memory does not hold (:meth:`observe`
            returned None).
        """
        if self._difference is None:
            return None
        shadow = dimmed(cur, self.color, self.known, box, self.tolerance)
        if labels is not None:
            now = labels[box]
            shadow &= (self.label[box] != now) | (now == 0)
        return shadow

    def same_colour(self, cur: np.ndarray, box: tuple[slice, slice]) -> np.ndarray:
        """(h, w) bool on the image box ``box``: remembered pixels (over a remembered grey
        sum above ``SHADOW_MIN_SUM``) that show the remembered colour now
        (chromaticity within ``SHADOW_CHROMA``), darker, lighter or as bright -- the
        static world under a change of light, its texture not tested (a shadow's
        penumbra, the table a shadow has just left). All False when the memory does not
        hold (:meth:`observe` returned None)."""
        if self._difference is None:
            return np.zeros(cur[box].shape[:2], bool)
        chroma, _, _, then = light_change(cur[box], self.color[box])
        return self.known[box] & (then > SHADOW_MIN_SUM) & (chroma < SHADOW_CHROMA)

    def dimmed_share(self, cur: np.ndarray, labels: np.ndarray, lab: int,
                     box: tuple[slice, slice]) -> float:
        """Share of MotionBit ``lab``'s pixels (``labels == lab``, inside their bounding
        ``box``) that are remembered and darker now by a shadow's gain (``SHADOW_GAIN``,
        over a remembered grey sum above ``SHADOW_MIN_SUM``): a cheap first look, never
        below the share that :meth:`shadowed` finds. 0 when :meth:`shadowed` would
        return None.

        Args:
            cur: (H, W, 3) uint8 current RGB frame.
            labels: (H, W) int label map.
            lab: the MotionBit's id.
            box: (rows, cols) slices of its bounding box.
        """
        if self._difference is None:
            return 0.0
        mask = labels[box] == lab
        area = np.count_nonzero(mask)
        mask &= self.known[box]
        if not area or not mask.any():
            return 0.0
        _, gain, _, then = light_change(cur[box][mask], self.color[box][mask])
        return float(np.count_nonzero((then > SHADOW_MIN_SUM) & (gain > SHADOW_GAIN[0])
                                      & (gain < SHADOW_GAIN[1]))) / area

    def restore(self, labels: np.ndarray, revealed: np.ndarray | None, moving: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray | None]:
        """Give the revealed pixels that were last seen still inside a MotionBit (a body
        that had stopped, then was covered by another passing in front of it or by its
        shadow) that MotionBit's id again, where nothing else holds them -- unless that
        MotionBit moves now (it is no longer where it stood: another body of its look may
        stand there, as in a shell game).

        Args:
            labels: (H, W) int32 label map of this frame.
            revealed: (H, W) bool from :meth:`observe` (None: the memory is off).
            moving: ids of the MotionBits that move now
                (:func:`motionbits.records.moving_ids`).

        Returns:
            The label map and the (H, W) bool pixels given back (None if none).
        """
        if revealed is None:
            return labels, None
        back = revealed & (labels == 0) & (self.label > 0)
        if back.any() and len(moving):
            back &= ~np.isin(self.label, moving)
        if not back.any():
            return labels, None
        return np.where(back, self.label, labels).astype(np.int32), back

    def forget(self, ids: np.ndarray) -> None:
        """Retired MotionBits (``ids``, (k,) int) are not given back (:meth:`restore`)."""
        if len(ids):
            self.label[np.isin(self.label, ids)] = 0

    def update(self, cur: np.ndarray, cur_gray: np.ndarray, change: np.ndarray,
               standing: np.ndarray, labels: np.ndarray) -> np.ndarray | None:
        """Fold in the current frame (after :meth:`observe`; nothing if that returned
        None).

        Args:
            cur: (H, W, 3) uint8 current RGB frame.
            cur_gray: (H, W) float32 its grey levels.
            change: (H, W) float32 grey change since the last frame (:func:`grey_change`);
                a pixel is seen still only where it is under ``tolerance``.
            standing: (H, W) bool, seen standing still now
                (:func:`motionbits.merging.standing_still`).
            labels: (H, W) int32 this frame's MotionBit ids, remembered with the look of
                the pixels seen still (for :meth:`restore`).

        Returns:
            (H, W) bool, the pixels seen still now (remembered), or None when the memory is
            off.
        """
        if self._difference is None:
            return None
        self.was_covered |= self._difference > self.covered
        calm = standing & (change < self.tolerance)
        # in place; np.copyto with a broadcast ``where`` is ~100x slower
        cv2.copyTo(cur, calm.view(np.uint8), self.color)
        cv2.copyTo(cur_gray, calm.view(np.uint8), self.gray)
        cv2.copyTo(labels, calm.view(np.uint8), self.label)
        self.known |= calm
        self.was_covered &= ~calm
        self._difference = None
        return calm
