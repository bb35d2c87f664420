"""A shown mark whose pixels fall apart is shown as its pieces (motionbits/apart.py)."""

import numpy as np

from motionbits.apart import split_apart


def _two_blocks() -> tuple[np.ndarray, np.ndarray]:
    """One mark (2) over two blocks 10 px apart: the left one held by MotionBit 2, the
    right one by MotionBit 5 (a member of 2's group)."""
    shown = np.zeros((40, 80), np.int32)
    shown[5:30, 5:35] = 2  # 750 px
    shown[10:30, 45:70] = 2  # 500 px
    state = np.where(shown > 0, 2, 0).astype(np.int32)
    state[10:30, 45:70] = 5
    return shown, state


def test_pieces_apart_are_shown_under_the_motionbit_that_holds_them():
    shown, state = _two_blocks()
    rep = {2: 2, 5: 2, 9: 0}
    out, new_rep, fresh, next_id = split_apart(shown, state, rep, {2: 2}, 100, gap=3,
                                               min_area=200)
    assert np.array_equal(out[5:30, 5:35], np.full((25, 30), 2))  # the larger piece keeps it
    assert np.array_equal(out[10:30, 45:70], np.full((20, 25), 5))
    assert new_rep == {2: 2, 5: 5, 9: 0}
    assert fresh == {} and next_id == 100
    assert rep == {2: 2, 5: 2, 9: 0} and np.count_nonzero(shown == 5) == 0  # inputs kept


def test_pieces_within_the_gap_small_pieces_and_single_pieces_stay_one_mark():
    shown, state = _two_blocks()
    rep, source = {2: 2, 5: 2}, {2: 2}
    # 10 px apart, but a gap of 12 px joins them
    out = split_apart(shown, state, rep, source, 100, gap=12, min_area=200)
    assert out[0] is shown and out[1] is rep and out[2] == {} and out[3] == 100
    # the right piece is too small to be shown by itself
    out = split_apart(shown, state, rep, source, 100, gap=3, min_area=600)
    assert out[0] is shown and out[1] is rep
    whole = np.zeros((40, 80), np.int32)
    whole[5:30, 5:70] = 2
    assert split_apart(whole, whole, rep, source, 100, gap=3, min_area=200)[0] is whole


def test_a_motionbit_on_both_pieces_shows_the_smaller_under_a_fresh_label_with_its_twist():
    shown, _ = _two_blocks()
    state = np.where(shown > 0, 2, 0).astype(np.int32)  # MotionBit 2 holds both
    out, new_rep, fresh, next_id = split_apart(shown, state, {2: 2}, {2: 7}, 100, gap=3,
                                               min_area=200)
    assert set(np.unique(out)) == {0, 2, 100}
    assert np.count_nonzero(out == 100) == 500
    assert new_rep == {2: 2} and fresh == {100: 7} and next_id == 101
