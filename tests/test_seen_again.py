"""The static world seen again: a shadow's MotionBit is retired, a moving body is kept, and
pixels that look as they did before lose their evidence of motion (issue "Only what moved":
shadows, the wake of a hand)."""

import cv2
import numpy as np
import pytest

from motionbits.retirement import Origin, relit_residual, retire, seen_again

H, W = 120, 160


def _texture(seed: int) -> np.ndarray:
    """(120, 160, 3) float32 colour texture in [40, 220], smooth over 4 px."""
    noise = np.random.default_rng(seed).uniform(0, 1, (H // 4, W // 4, 3)).astype(np.float32)
    return 40 + 180 * cv2.resize(noise, (W, H), interpolation=cv2.INTER_CUBIC).clip(0, 1)


def _gray(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(rgb.astype(np.float32), cv2.COLOR_RGB2GRAY)


def _shift(dx: float) -> np.ndarray:
    """(3, 3) backward motion current -> earlier frame of a body moved by ``dx`` px in x."""
    return np.array([[1.0, 0.0, -dx], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


BOX = (slice(40, 80), slice(60, 110))


def test_relit_residual_explains_a_shadow_not_a_body_of_another_colour():
    base = _texture(0)
    inside = np.ones((40, 50), bool)
    shaded = base.copy()
    shaded[BOX] *= 0.5  # a shadow: every channel darkened by the same factor
    painted = base.copy()
    painted[BOX] = 0.5 * base[BOX][..., [2, 0, 1]]  # as dark, but other colours
    lit = relit_residual(base, np.eye(3), shaded, BOX, inside)
    other = relit_residual(base, np.eye(3), painted, BOX, inside)
    plain = np.abs(_gray(shaded) - _gray(base))[BOX].mean()
    assert plain > 30 and lit < 3, (plain, lit)
    assert other > 10, other
    # no light change at all: no verdict (the plain residual decides)
    assert np.isnan(relit_residual(base, np.eye(3), base, BOX, inside))


@pytest.mark.parametrize("relit, shadow_stays", [(6.0, False), (0.0, True)])
def test_a_shadow_is_retired_and_a_moving_body_is_kept(relit, shadow_stays):
    """MotionBit 1 is a shadow that moved with an arm (its own motion: 10 px), MotionBit 2
    a textured body that moved 10 px. Only the light-change test retires the shadow; the
    body is kept either way."""
    before = _texture(0)
    patch = _texture(1)[20:50, 10:40]
    before[20:50, 110:140] = patch  # the body, before it moved
    now = before.copy()
    now[BOX] *= 0.5  # the shadow now
    now[20:50, 110:140] = _texture(0)[20:50, 110:140]  # the body uncovered the background
    now[20:50, 120:150] = patch  # the body moved 10 px right
    labels = np.zeros((H, W), np.int32)
    labels[BOX] = 1
    labels[20:50, 120:150] = 2
    origins = {i: Origin(_gray(before), _shift(10.0), np.eye(3), before) for i in (1, 2)}
    out, kept = retire(labels, origins, np.zeros(0, int), np.zeros(0), np.zeros((0, 2)), 99,
                       None, _gray(before), _gray(now), 5.0, explained=12.0, relit=relit,
                       prev_rgb=before, cur_rgb=now)
    assert ((out == 1).any()) == shadow_stays
    assert (out == 2).sum() == (labels == 2).sum() and 2 in kept


def test_seen_again_marks_only_pixels_that_look_as_before():
    first = _texture(0)
    now = first.copy()
    now[:, 90:] = np.clip(first[:, 90:] + 60, 0, 255)  # right part: something else is there
    labels = np.zeros((H, W), np.int32)
    labels[30:90, 40:140] = 4
    earned = labels > 0
    earned[30:40] = False
    first_frame = Origin(_gray(first), np.eye(3), np.eye(3))
    seen = seen_again(labels, earned, {}, first_frame, _gray(now), 6.0, {4})
    assert not seen[labels == 0].any()  # only MotionBit pixels ...
    assert not seen[30:40].any()  # ... with evidence of motion
    assert seen[40:90, 40:85].all()  # unchanged part (5x5 mean off the changed edge)
    assert not seen[40:90, 95:140].any()
    # only the MotionBits asked for (those moving)
    assert not seen_again(labels, earned, {}, first_frame, _gray(now), 6.0, {3}).any()
