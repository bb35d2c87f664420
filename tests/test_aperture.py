"""Flat links that move along themselves (motionbits/aperture.py): a flat bar entering the
view from the top border, rigidly attached to a textured block, both moving down."""

import cv2
import numpy as np

from motionbits.aperture import (carried_joins, flat_link_candidates, flat_regions,
                                 join_flat_links)

H, W = 160, 160
BAR = (slice(None), slice(70, 86))  # columns of the flat bar
BAR_COLOUR = (150, 40, 60)


def _scene(shift: int, bar_top: int = 0, background_seed: int = 0) -> np.ndarray:
    """(H, W, 3) uint8: static texture with a flat wall in columns 50-109, a nearly flat
    bar from row ``bar_top + shift`` (the top border when 0) down to a textured block at
    rows 70-99 (+ ``shift``)."""
    rng = np.random.default_rng(background_seed)
    frame = cv2.resize(rng.integers(0, 255, (H // 4, W // 4, 3), dtype=np.uint8), (W, H),
                       interpolation=cv2.INTER_NEAREST)
    # a flat wall behind the bar (a smooth gradient): beside a link, textured background
    # that the body's motion would move keeps the link out (the band test)
    wall = np.linspace(60, 110, 60, dtype=np.float32)[None, :, None] * np.ones((H, 1, 3))
    frame[:, 50:110] = (wall + [0, 20, 40]).astype(np.uint8)
    block = np.random.default_rng(7).integers(0, 255, (10, 14, 3), dtype=np.uint8)
    top = 70 + shift
    # a faint smooth texture moves with the bar (the flow sees some of its motion; the
    # colour gradient stays far below FLAT_GRADIENT)
    faint = cv2.GaussianBlur(np.random.default_rng(3).normal(0, 20, (H + 40, 16)), (0, 0), 4)
    bar = np.clip(np.array(BAR_COLOUR) + faint[40 - shift:40 - shift + top, :, None], 0, 255)
    start = bar_top + shift if bar_top else 0
    frame[start:top, BAR[1]] = bar[start:top].astype(np.uint8)
    frame[top:top + 30, 57:99] = cv2.resize(block, (42, 30), interpolation=cv2.INTER_NEAREST)
    return frame


def _gray(frame):
    return cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY).astype(np.float32)


def join_flat_regions(labels, ids, thetas, trans, rgb, cur_gray, prev_gray, still, speed,
                      joined, *, move_threshold, min_area):
    """The segmenter's two steps: the candidate links, then the motions' test on them."""
    links = flat_link_candidates(labels, ids, rgb, speed, joined,
                                 move_threshold=move_threshold, min_area=min_area)
    return join_flat_links(labels, links, ids, thetas, trans, cur_gray, prev_gray, still)


def _join(prev, cur, moving=True, joined=None, bar_top=0):
    labels = np.zeros((H, W), np.int32)
    labels[72:103, 57:99] = 1  # the block's MotionBit (moved 3 px down), its top edge too
    flow = np.zeros((H, W, 2), np.float32)
    if moving:  # the backward flow of the bar and the block (DIS sees some of the bar's)
        flow[bar_top:73, BAR[1], 1] = flow[73:103, 57:99, 1] = -3.0
    still = np.abs(_gray(cur) - _gray(prev))
    return join_flat_regions(
        labels, np.array([1]), np.zeros(1), np.array([[0.0, -3.0 if moving else 0.0]]), cur,
        _gray(cur), _gray(prev), still, cv2.magnitude(flow[..., 0], flow[..., 1]),
        np.zeros((H, W), np.int32) if joined is None else joined,
        move_threshold=0.6, min_area=60)


def test_flat_regions_are_bounded_by_colour_edges():
    flat, regions, stats = flat_regions(_scene(0))
    bar = regions[5:65, 72:84]
    assert flat[5:65, 72:84].all() and len(np.unique(bar)) == 1
    assert stats[bar[0, 0], 2] <= 18  # the bar alone: its edges close it (width 16 px)


def test_a_flat_bar_moving_along_itself_joins_its_body():
    prev, cur = _scene(0), _scene(3)
    out = _join(prev, cur)
    assert (out[0:70, 72:84] == 1).mean() > 0.95
    changed = np.argwhere(out != _join(prev, cur, moving=False))
    assert changed[:, 0].max() < 75 and 67 <= changed[:, 1].min() <= changed[:, 1].max() <= 88
    # a bar the flow does not move stays background
    assert (_join(prev, cur, moving=False)[0:70, 72:84] == 0).all()


def test_the_motions_are_asked_for_only_where_a_link_may_join():
    """The segmenter refines the motions on its second thread and asks for them only
    where :func:`flat_link_candidates` names a (MotionBit, region) pair to test."""
    prev, cur = _scene(0), _scene(3)
    labels = np.zeros((H, W), np.int32)
    labels[72:103, 57:99] = 1

    def candidates(speed):
        return flat_link_candidates(labels, np.array([1]), cur, speed,
                                    np.zeros((H, W), np.int32), move_threshold=0.6,
                                    min_area=60)

    speed = np.zeros((H, W), np.float32)
    assert candidates(speed) is None  # nothing moved along itself: no test
    speed[0:103, BAR[1]] = 3.0
    links = candidates(speed)
    assert links is not None and [(k, kept) for k, _, kept in links.pairs] == [(0, False)]
    assert (links.regions[10:60, 72:84] == links.pairs[0][1]).all()  # the bar


def test_a_flat_region_inside_the_view_does_not_join():
    # the same bar, starting at row 20: its top edge runs across the motion
    prev, cur = _scene(0, bar_top=20), _scene(3, bar_top=20)
    assert (_join(prev, cur, bar_top=20)[25:70, 72:84] == 0).all()


def test_a_joined_region_stays_while_the_body_rests():
    rest = _scene(3)
    joined = np.zeros((H, W), np.int32)
    joined[0:73, 70:86] = 1
    out = _join(rest, rest, moving=False, joined=joined)
    assert (out[0:70, 72:84] == 1).mean() > 0.95
    assert (_join(rest, rest, moving=False)[0:70, 72:84] == 0).all()  # never joined: no


def test_a_join_stays_with_the_group_of_the_piece_that_made_it():
    # a newborn piece (id 5) of the block's body joined the bar, then was merged into the
    # block's group (id 1); at rest the next frame, only the block has a motion
    rest = _scene(3)
    made = np.zeros((H, W), np.int32)
    made[72:103, 57:99] = 1
    made[60:72, 57:99] = 5
    with_links = made.copy()
    with_links[0:60, 70:86] = 5
    joined = carried_joins(with_links, made, {1: 1, 5: 1})
    assert set(np.unique(joined)) == {0, 1} and (joined[0:60, 70:86] == 1).all()
    assert (_join(rest, rest, moving=False, joined=joined)[0:70, 72:84] == 1).mean() > 0.95
    # under the piece's own id, the join is lost once the piece is gone
    alone = carried_joins(with_links, made, {})
    assert (_join(rest, rest, moving=False, joined=alone)[0:70, 72:84] == 0).all()


def _wide_scene(shift: int) -> np.ndarray:
    """(H, W, 3) uint8: the textured block at rows 70-99 (+ ``shift``) below a plain,
    nearly flat surface over the whole width from the top border (a white table or wall,
    45% of the image) whose faint texture moves with the block (smeared flow)."""
    frame = _scene(shift)
    faint = cv2.GaussianBlur(np.random.default_rng(5).normal(0, 20, (H + 40, W)), (0, 0), 4)
    top = 70 + shift
    frame[:top] = np.clip(np.array((200, 200, 190)) + faint[40 - shift:40 - shift + top, :, None],
                          0, 255).astype(np.uint8)
    return frame


def test_the_ground_or_a_wall_never_joins(monkeypatch):
    """A flat region reaching the border over GROUND_SHARE of the image is the ground or
    a wall, not a link, even where the smeared flow moves it with a body (02_cups.mp4: the
    white table joined to the person's mark, 28% of the frame; round 44)."""
    import motionbits.aperture as aperture

    prev, cur = _wide_scene(0), _wide_scene(3)
    flow = np.zeros((H, W, 2), np.float32)
    flow[0:103, :, 1] = -3.0
    labels = np.zeros((H, W), np.int32)
    labels[72:103, 57:99] = 1

    def join():
        return join_flat_regions(
            labels, np.array([1]), np.zeros(1), np.array([[0.0, -3.0]]), cur, _gray(cur),
            _gray(prev), np.abs(_gray(cur) - _gray(prev)),
            cv2.magnitude(flow[..., 0], flow[..., 1]), np.zeros((H, W), np.int32),
            move_threshold=0.6, min_area=60)

    surface = np.s_[0:65, :]
    assert flat_regions(cur)[0][surface].mean() > 0.95
    assert (join()[surface] == 0).all()
    # the motion explains it as it does the bar: only its size keeps it out
    monkeypatch.setattr(aperture, "GROUND_SHARE", 1.0)
    assert (join()[surface] == 1).mean() > 0.9
