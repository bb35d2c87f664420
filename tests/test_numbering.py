"""The numbers marks are shown under stay with their bodies (motionbits/numbering.py)."""

import numpy as np

from motionbits import MotionBitsSegmenter
from motionbits.boxes import label_areas
from motionbits.numbering import (RECENT_FRAMES, ShownNumbers, by_number, mask_ious,
                                  match_greedy)
from motionbits.records import MotionBitsResult, group_map
from motionbits.synth import demo_clip


def _state(*boxes: tuple[int, slice, slice]) -> np.ndarray:
    """(20, 20) int32 MotionBit ids: each (id, rows, cols) box painted in order."""
    out = np.zeros((20, 20), np.int32)
    for i, rows, cols in boxes:
        out[rows, cols] = i
    return out


def _frame(numbers: ShownNumbers, state: np.ndarray, rep: dict[int, int], next_id: int = 100
           ) -> tuple[dict[int, int], int]:
    """One frame: every present id's group shown whole (the shown map is the state's)."""
    return numbers.assign(group_map(state, rep), state, rep, next_id)


SMALL = (1, slice(0, 4), slice(0, 4))  # id 1, 16 px
BIG = (2, slice(10, 20), slice(0, 10))  # id 2, 100 px


def test_split_the_bigger_part_keeps_the_number():
    numbers = ShownNumbers()
    state = _state(SMALL, BIG)
    assert _frame(numbers, state, {1: 1, 2: 1})[0] == {1: 1}
    # the group splits: its representative (id 1) is the smaller part
    got, next_id = _frame(numbers, state, {1: 1, 2: 2})
    assert got[2] == 1  # the bigger part keeps "1"
    assert got[1] == 100 and next_id == 101  # "1" is held: a fresh number


def test_the_oldest_member_retires_the_number_stays():
    numbers = ShownNumbers()
    assert _frame(numbers, _state(SMALL, BIG), {1: 1, 2: 1})[0] == {1: 1}
    got, next_id = _frame(numbers, _state(BIG), {2: 2})  # id 1 retired
    assert got == {2: 1} and next_id == 100


def test_join_the_larger_parts_number_wins():
    numbers = ShownNumbers()
    state = _state(SMALL, BIG)
    assert _frame(numbers, state, {1: 1, 2: 2})[0] == {1: 1, 2: 2}
    assert _frame(numbers, state, {1: 1, 2: 1})[0] == {1: 2}  # shown under id 1, as "2"


def test_reborn_on_the_same_pixels_keeps_the_number():
    numbers = ShownNumbers()
    _frame(numbers, _state(SMALL, BIG), {1: 1, 2: 1})
    _frame(numbers, _state(BIG), {2: 2})  # "1" on id 2 alone
    # id 2 retired and id 7 born on nearly its pixels in the same frame
    got, _ = _frame(numbers, _state((7, slice(11, 20), slice(0, 10))), {7: 7})
    assert got == {7: 1}
    # elsewhere, a newborn takes its own id
    got, _ = _frame(numbers, _state((7, slice(11, 20), slice(0, 10)),
                                    (9, slice(0, 5), slice(15, 20))), {7: 7, 9: 9})
    assert got == {7: 1, 9: 9}


def test_reborn_after_a_gap_keeps_the_number_within_recent_frames():
    numbers = ShownNumbers()
    _frame(numbers, _state(SMALL, BIG), {1: 1, 2: 1})  # "1" on ids 1 + 2
    _frame(numbers, _state(BIG), {2: 2})  # "1" on id 2 alone
    for _ in range(3):  # id 2 retired; nothing shown
        _frame(numbers, _state(), {})
    got, _ = _frame(numbers, _state((7, slice(11, 20), slice(0, 10))), {7: 7})
    assert got == {7: 1}
    numbers = ShownNumbers()  # past RECENT_FRAMES: a number of its own
    _frame(numbers, _state(SMALL, BIG), {1: 1, 2: 1})
    _frame(numbers, _state(BIG), {2: 2})
    for _ in range(RECENT_FRAMES):
        _frame(numbers, _state(), {})
    got, _ = _frame(numbers, _state((7, slice(11, 20), slice(0, 10))), {7: 7})
    assert got == {7: 7}


def test_a_group_not_shown_passes_no_number_on():
    numbers = ShownNumbers()
    state = _state(SMALL, BIG)
    _frame(numbers, state, {1: 1, 2: 1})
    # shown: only id 1's group (the other mark was hidden)
    shown = group_map(_state(SMALL), {1: 1})
    got, _ = numbers.assign(shown, state, {1: 1, 2: 2}, 100)
    assert got == {1: 1}


def test_a_mark_hidden_for_some_frames_comes_back_under_its_number():
    numbers = ShownNumbers()
    state = _state(SMALL, BIG)
    assert _frame(numbers, state, {1: 1, 2: 1})[0] == {1: 1}
    assert _frame(numbers, state, {1: 1, 2: 2})[0] == {1: 100, 2: 1}  # split: id 2 keeps "1"
    for _ in range(2):  # id 2 hidden (too small to show, say)
        assert _frame(numbers, state, {1: 1, 2: 0}, 101)[0] == {1: 100}
    got, next_id = _frame(numbers, state, {1: 1, 2: 2}, 101)
    assert got == {1: 100, 2: 1} and next_id == 101  # back under "1", not "2"
    # a number held now is not taken back by an earlier claim
    numbers = ShownNumbers()
    _frame(numbers, _state((5, slice(0, 4), slice(0, 4)), BIG), {5: 5, 2: 2})
    _frame(numbers, _state((5, slice(0, 4), slice(0, 4)), BIG), {5: 0, 2: 2})
    got, _ = _frame(numbers, _state((5, slice(0, 4), slice(0, 4)), BIG), {5: 2, 2: 2})
    assert got == {2: 2}  # joined: the last frame's "2" wins over id 5's earlier "5"
    got, _ = _frame(numbers, _state((5, slice(0, 4), slice(0, 4)), BIG), {5: 5, 2: 2})
    assert got == {5: 5, 2: 2}


def test_numbers_are_unique_and_positive_over_a_random_stream():
    rng = np.random.default_rng(3)
    numbers, next_id = ShownNumbers(), 50
    for _ in range(60):
        state = rng.integers(0, 12, (8, 8)).astype(np.int32)
        present = np.unique(state[state > 0]).tolist()
        rep = {}
        for i in present:  # random groups under their smallest member, some not shown
            r = rep.get(int(rng.choice(present)), i)
            rep[i] = min(r, i) if rng.random() > 0.2 else 0
        shown = group_map(state, rep)
        got, after = numbers.assign(shown, state, rep, next_id)
        assert set(got) == set(np.unique(shown[shown > 0]).tolist())
        assert len(set(got.values())) == len(got) and min(got.values(), default=1) > 0
        fresh = [n for n in got.values() if n >= next_id]
        assert sorted(fresh) == list(range(next_id, after))
        next_id = after


def test_match_greedy_heaviest_first_each_once():
    assert match_greedy({(1, 10): 5, (1, 20): 9, (2, 10): 3, (2, 20): 1}) == {20: 1, 10: 2}


def test_mask_ious():
    before = _state((3, slice(0, 10), slice(0, 10)))
    now = _state((5, slice(0, 10), slice(5, 15)))
    empty = np.zeros_like(before)
    areas = label_areas(now), label_areas(before), label_areas(empty)
    assert mask_ious(now, before, areas[0], areas[1]) == {(3, 5): 50 / 150}
    assert mask_ious(now, empty, areas[0], areas[2]) == {}


def test_by_number_gives_members_and_twist_sources_their_groups_numbers():
    rep = {4: 4, 5: 4, 7: 7, 9: 9}  # group 9 is not shown: it has no number
    source = {4: 5, 7: 7, 9: 9}
    members, sources = by_number(rep, source, {4: 12, 7: 2})
    assert members == {4: 12, 5: 12, 7: 2, 9: 0}
    assert sources == {12: 5, 2: 7}


def _run(seg: MotionBitsSegmenter, frames) -> list[MotionBitsResult]:
    return [seg.update(f) for f in frames]


def test_segmenter_results_agree_on_the_numbers_and_reset_forgets_them():
    clip = demo_clip(n_frames=6, size=(120, 160))
    seg = MotionBitsSegmenter()
    first = _run(seg, clip.frames)
    assert any(r.ids for r in first), "the clip must have marks for this to test anything"
    for r in first:
        shown = set(np.unique(r.labels[r.labels > 0]).tolist())
        assert r.ids == sorted(shown)
        assert set(np.unique(r.node_labels[r.node_labels > 0]).tolist()) <= shown
    seg.reset()
    again = _run(seg, clip.frames)
    for a, b in zip(first, again):
        assert a.ids == b.ids and (a.labels == b.labels).all()
