"""Marks of bodies at rest held while nothing changes under them (motionbits.resting)."""

import cv2
import numpy as np

from motionbits.evidence import gradient_magnitude
from motionbits.resting import RestingMarks, looks_tested


def _scene(shift: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(240, 320, 3) uint8 textured table with a red block (rows 80:140, cols
    120 + shift:180 + shift) and the block's (240, 320) bool mask; the whole image moves
    ``shift`` px right (a panning camera)."""
    noise = np.random.default_rng(0).uniform(0, 255, (60, 90, 3)).astype(np.float32)
    tex = cv2.resize(noise, (360, 240), interpolation=cv2.INTER_CUBIC)
    rgb = np.clip(tex * (0.25, 0.45, 0.3) + (60, 90, 60), 0, 255).astype(np.uint8)
    rgb[80:140, 140:200] = (200, 40, 40)
    rgb = np.ascontiguousarray(rgb[:, 20 - shift:340 - shift])
    body = np.zeros((240, 320), bool)
    body[80:140, 120 + shift:180 + shift] = True
    return rgb, body


def _remembered(rgb: np.ndarray, body: np.ndarray) -> RestingMarks:
    """A memory that showed the block whole as mark 4 at the last frame."""
    marks = RestingMarks()
    shown = np.where(body, 4, 0).astype(np.int32)
    out, given = marks.hold(shown, rgb, shown, {4})
    assert out is shown and given == []  # nothing remembered yet
    return marks


def test_a_resting_mark_hidden_on_an_unchanged_body_is_shown_as_it_was():
    rgb, body = _scene()
    marks = _remembered(rgb, body)
    state = np.zeros(body.shape, np.int32)
    state[120:140, 120:180] = 4  # the state keeps a frayed part of the block
    hidden = np.zeros(body.shape, np.int32)  # ... that the shown steps hid
    out, given = marks.hold(hidden, rgb, state, {4})
    assert ((out == 4) == body).all() and given == [4]
    # ... and it is remembered so for the next frame
    assert ((marks.hold(hidden, rgb, state, {4})[0] == 4) == body).all()


def test_it_is_not_held_where_the_image_changed_the_body_moved_or_moves_now():
    rgb, body = _scene()
    state = np.zeros(body.shape, np.int32)
    state[120:140, 120:180] = 4
    hidden = np.zeros(body.shape, np.int32)
    covered = rgb.copy()
    covered[70:130, 100:200] = (120, 90, 70)  # a hand in front of most of it
    assert not marks_hold(_remembered(rgb, body), hidden, covered, state, {4}).any()
    elsewhere = np.zeros(body.shape, np.int32)
    elsewhere[150:200, 200:260] = 4  # the state holds it elsewhere now
    assert not marks_hold(_remembered(rgb, body), hidden, rgb, elsewhere, {4}).any()
    assert not marks_hold(_remembered(rgb, body), hidden, rgb, state, set()).any()  # moving
    gone = np.zeros(body.shape, np.int32)  # retired: the state no longer holds it
    assert not marks_hold(_remembered(rgb, body), hidden, rgb, gone, {4}).any()


def test_a_mark_is_held_only_where_it_gets_back_the_smallest_mark_s_area():
    rgb, body = _scene()  # the block: 60 x 60 = 3600 px
    state = np.zeros(body.shape, np.int32)
    state[120:140, 120:180] = 4
    shown = np.zeros(body.shape, np.int32)
    shown[80:135, 120:180] = 9  # another mark took most of its pixels: 300 px are left
    assert (marks_hold(_remembered(rgb, body), shown, rgb, state, {4}, 300)
            == body & ~(shown > 0)).all()
    assert not marks_hold(_remembered(rgb, body), shown, rgb, state, {4}, 301).any()


def test_a_mark_still_shown_is_left_as_the_steps_give_it_even_if_smaller():
    rgb, body = _scene()
    marks = _remembered(rgb, body)
    shown = np.zeros(body.shape, np.int32)
    shown[100:140, 120:180] = 4
    out, given = marks.hold(shown, rgb, shown, {4})
    assert out is shown and given == []


def test_under_a_moving_camera_the_memory_follows_the_static_world():
    rgb, body = _scene()
    marks = _remembered(rgb, body)
    moved, moved_body = _scene(shift=6)
    # the world's model: each pixel now was 6 px to its left at the last frame
    xs, ys = np.meshgrid(np.arange(320, dtype=np.float32), np.arange(240, dtype=np.float32))
    marks.follow(np.dstack([xs - 6, ys]))
    state = np.where(moved_body, 4, 0).astype(np.int32)
    out, _ = marks.hold(np.zeros(body.shape, np.int32), moved, state, {4})
    assert ((out == 4) == moved_body).all()


def test_looks_tested_drops_held_marks_without_an_edge_or_that_are_stripes():
    rgb, body = _scene()
    gradient = gradient_magnitude(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32))
    shown = np.zeros(body.shape, np.int32)
    shown[20:60, 20:60] = 7  # a mark shown as the steps gave it: not tested again
    held = shown.copy()
    held[body] = 4  # the block, given back: its outline is the block's edge
    assert (looks_tested(held, [4], gradient, 7) == held).all()
    flat = np.zeros(body.shape, bool)
    flat[95:125, 135:165] = True  # inside the red block's flat face: no edge
    plain = shown.copy()
    plain[flat] = 4
    assert (looks_tested(plain, [4], gradient, 7) == shown).all()
    stripe = shown.copy()
    stripe[80:140, 120:123] = 4  # 3 px wide along the block's edge
    assert (looks_tested(stripe, [4], gradient, 7) == shown).all()


def marks_hold(marks: RestingMarks, shown: np.ndarray, rgb: np.ndarray, state: np.ndarray,
               resting: set[int], min_area: float = 0.0) -> np.ndarray:
    """(H, W) bool: the pixels shown as mark 4."""
    return marks.hold(shown, rgb, state, resting, min_area)[0] == 4


def test_the_segmenter_holds_a_resting_mark_that_the_stripe_test_hid(monkeypatch):
    """The stripe test (``hide_thin``) turns on the trimmed outline too: a resting body's
    mark trimmed to a sliver and hidden by it is held like one the earlier steps hid
    (round 60: a block whose top the flat-background trim cut to a band)."""
    import motionbits.segmenter as segmenter
    from motionbits import MotionBitsSegmenter
    from motionbits.synth import demo_clip

    clip = demo_clip(n_frames=16)
    seg = MotionBitsSegmenter()
    for frame in clip.frames[:-1]:
        seg.update(frame)
    # the stripe test before the hold hides every mark (what is held is tested again by
    # the real one: ``looks_tested``)
    monkeypatch.setattr(segmenter, "hide_thin", lambda labels, side: np.zeros_like(labels))
    last = seg.update(clip.frames[-1]).labels
    stopped = clip.gt == 6  # GT body 6 moves, then stops: at rest at the last frame
    ids, counts = np.unique(last[stopped], return_counts=True)
    held = int(ids[np.argmax(counts)])
    assert held != 0
    assert ((last == held) & stopped).sum() / ((last == held) | stopped).sum() >= 0.85
    # the bodies still moving at the last frame are not held: every other mark is gone
    assert set(np.unique(last)) <= {0, held}
