"""Only what moved is a MotionBit: uncovered background returns to background, one body is one
MotionBit, pieces that never moved are retired (issue "Only what moved")."""

import cv2
import numpy as np
import pytest

import motionbits.segmenter as segmenter_module
from motionbits import MotionBitsConfig, segment_video
from motionbits.evidence import appearance_consistent, gradient_magnitude, pull_back
from motionbits.masks import hide_small, hide_thin
from motionbits.merging import (OUTWEIGH, MotionBitGroups, apply_joins, drop_seen_still,
                                join_convex, mostly_moving, observe_touching, seen_still,
                                standing_still, touching_pairs)
from motionbits.nodes import NodeGrid
from motionbits.revealed import StaticMemory, grey_change
from motionbits.synth.planar import Body, Polygon, render_planar_clip
from motionbits.twists import rigid_matrix

SIZE = (240, 320)
CONFIG = MotionBitsConfig(n_nodes=2500, max_side=max(SIZE))


@pytest.fixture(scope="module")
def sweep():
    """A glued two-texture body sweeping 5 px/frame across a textured background, and a
    static distractor."""
    square = Polygon.rect(20, 80, 70, 140, texture_seed=3)
    triangle = Polygon(((70, 80), (110, 110), (70, 140)), texture_seed=4)
    bodies = [Body((square, triangle), velocity=(5.0, 0.0)),
              Body((Polygon.regular(250, 50, 25, 5, texture_seed=8),))]
    clip = render_planar_clip(bodies, size=SIZE, n_frames=14, seed=2)
    return clip, [r.labels for r in segment_video(clip.frames, CONFIG)]


def test_swept_background_returns_to_background(sweep):
    clip, labels = sweep
    static = clip.labels[-1] == 0
    false_pos = (labels[-1] > 0) & static
    assert false_pos.sum() <= 0.01 * static.sum(), false_pos.sum()
    # the path it has left, more than 15 px behind its trailing edge (x = 85 at the end),
    # keeps no label at all
    assert (clip.labels[-1][:, :85] == 0).all()
    trail = np.zeros(SIZE, bool)
    trail[80:140, 20:70] = True
    assert not (labels[-1][trail & static] > 0).any()


def test_fast_sweep_leaves_no_trail_of_motionbits():
    """15 px/frame with a slow turn: DIS smears the flow behind the body; no piece of that
    smear, nor of the uncovered background, may become a MotionBit."""
    square = Polygon.rect(10, 80, 60, 140, texture_seed=3)
    triangle = Polygon(((60, 80), (100, 110), (60, 140)), texture_seed=4)
    clip = render_planar_clip([Body((square, triangle), velocity=(15.0, 0.0), omega=0.01)],
                              size=SIZE, n_frames=14, seed=2)
    results = list(segment_video(clip.frames, CONFIG))
    for t in (7, 10, 13):
        assert len(results[t].motionbits) == 1, (t, results[t].ids)
        static = clip.labels[t] == 0
        assert ((results[t].labels > 0) & static).sum() <= 0.03 * static.sum()


def test_glued_body_is_one_motionbit(sweep):
    clip, labels = sweep
    body = clip.labels[-1] == 1
    ids, counts = np.unique(labels[-1][body], return_counts=True)
    main = ids[np.argmax(np.where(ids > 0, counts, 0))]
    assert main > 0 and counts[ids == main][0] >= 0.85 * body.sum()
    assert set(np.unique(labels[-1])) == {0, main}  # no other MotionBit anywhere


def test_carried_label_needs_appearance():
    rng = np.random.default_rng(0)
    prev = rng.uniform(0, 255, (60, 80)).astype(np.float32)
    cur = prev.copy()
    cur[20:40, 30:50] = 40.0  # an occluder has gone: a patch whose look changed
    flow = np.zeros((60, 80, 2), np.float32)  # static flow everywhere
    ok = appearance_consistent(cur, pull_back(prev, flow), gradient_magnitude(cur),
                               tolerance=12.0, gradient_gain=1.0)
    assert ok[5:15, 5:20].all()  # unchanged texture: consistent
    assert not ok[25:35, 35:45].any()  # uncovered pixels: inconsistent


def test_groups_agree_disagree_and_oldest_id():
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    groups.observe(3, 5, 0.4)  # agree
    groups.observe(5, 8, 1.0)  # agree
    groups.forbid(8, [2])
    assert groups.representatives([2, 3, 5, 8]) == {2: 2, 3: 3, 5: 3, 8: 3}
    groups.observe(3, 8, 13.0)  # a disagreement by twice the margin is final ...
    groups.observe(3, 8, 0.1)  # ... and a later agreement does not undo it
    rep = groups.representatives([3, 5, 8])
    assert rep[3] != rep[8]


def test_a_body_set_down_leaves_the_group_of_the_hand_that_carried_it():
    """The hand 2 and the block 5 it carried agreed at four frames; the hand lets go and
    moves on, no longer touching the block, which stands still. After DISAGREE_FRAMES
    such frames in a row they are two groups for good; a frame at which both move (or
    they touch) ends the run; pieces still touching are left to the touching test.
    At a frame apart they are shown apart already (a block set down at the clip's last
    frame has no second), and together again when the run ends."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(4):
        groups.observe(2, 5, 0.3, moved=4.0)
    assert groups.representatives([2, 5]) == {2: 2, 5: 2}
    groups.observe_apart(set(), {2, 5}, {2})  # the hand moves, the block stands
    assert groups.representatives([2, 5]) == {2: 2, 5: 5}  # shown apart this frame
    groups.observe_apart(set(), {2, 5}, {2, 5})  # both moved: the run ends
    assert groups.representatives([2, 5]) == {2: 2, 5: 2}
    groups.observe_apart(set(), {2, 5}, {2})
    assert groups.representatives([2, 5]) == {2: 2, 5: 5}
    groups.observe_apart({(2, 5)}, {2, 5}, {2})  # touching: not this test's
    assert groups.representatives([2, 5]) == {2: 2, 5: 2}
    groups.observe_apart(set(), {2}, {2})  # the block without a cluster: nothing seen
    assert groups.representatives([2, 5]) == {2: 2, 5: 2}
    groups.observe_apart(set(), {2, 5}, {2})  # the second frame in a row apart
    assert groups.representatives([2, 5]) == {2: 2, 5: 5}
    groups.observe(2, 5, 0.1, moved=4.0)  # for good
    groups.observe_apart(set(), {2, 5}, {2, 5})
    assert groups.representatives([2, 5]) == {2: 2, 5: 5}


def test_a_group_is_not_joined_across_a_pair_seen_apart_now():
    """The hand 2 carried the block 5, which agreed with its other face 7; the hand lets
    go: 5 and 7 stay one group, the hand's apart from both (one pair apart is enough,
    as for a forbidden pair)."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for a, b in ((2, 5), (2, 7), (5, 7)):
        groups.observe(a, b, 0.3, moved=4.0)
    assert set(groups.representatives([2, 5, 7]).values()) == {2}
    groups.observe_apart({(5, 7)}, {2, 5, 7}, {2})  # 2 moves on; 5, 7 touch and stand
    assert groups.representatives([2, 5, 7]) == {2: 2, 5: 5, 7: 5}


def test_a_pair_apart_is_shown_apart_only_where_one_motion_cannot_explain_both():
    """Two links of one arm, not touching, the slow one read as standing still: one
    motion explains both (``differ`` false), so they stay one group at that frame; a
    second such frame in a row still parts them for good, as before."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(4):
        groups.observe(2, 5, 0.3, moved=4.0)
    asked = []
    def one_motion(a, b):
        asked.append((a, b))
        return False
    groups.observe_apart(set(), {2, 5}, {2}, one_motion)
    assert asked == [(2, 5)]
    assert groups.representatives([2, 5]) == {2: 2, 5: 2}
    groups.observe_apart(set(), {2, 5}, {2}, one_motion)
    assert groups.representatives([2, 5]) == {2: 2, 5: 5}


def test_a_piece_joins_the_group_it_agreed_with_most_often():
    """MotionBit 4 agreed once with 2 (a hand) and at three frames with 3 (the rest of
    the door the hand pushes); 2 and 3 disagree: 4 goes with 3, not with the older 2."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    groups.observe(2, 4, 0.5)
    for _ in range(3):
        groups.observe(3, 4, 0.5)
    groups.forbid(2, [3])
    assert groups.representatives([2, 3, 4]) == {2: 2, 3: 3, 4: 3}
    groups.observe(2, 4, 0.5)
    groups.observe(2, 4, 0.5)
    groups.observe(2, 4, 0.5)  # now more often with 2
    assert groups.representatives([2, 3, 4]) == {2: 2, 3: 3, 4: 2}


def test_a_piece_joins_the_group_it_agreed_with_without_doubt():
    """MotionBit 4 (a piece of a flat lid) agreed as often with 1 (the hand that pushes
    the lid) as with 3 (the lid's other piece); 1 and 3 disagree. 4 was born out of
    pixels seen standing still while 1 moved, where that could not be seen: it goes with
    3. Without the doubt the tie goes to the older 1."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(3):
        groups.observe(1, 4, 0.5)
        groups.observe(3, 4, 0.5)
    groups.forbid(1, [3])
    assert groups.representatives([1, 3, 4]) == {1: 1, 3: 3, 4: 1}
    groups.doubt(4, 1)
    assert groups.representatives([1, 3, 4]) == {1: 1, 3: 3, 4: 3}
    groups.forbid(3, [4])  # with the lid ruled out, the doubtful pair still joins
    assert groups.representatives([1, 3, 4]) == {1: 1, 3: 3, 4: 1}


def test_a_piece_joins_the_group_it_agreed_with_more_closely():
    """MotionBit 4 agreed at two frames with 2 (a hand) and at two with 3 (the rest of the
    lid the hand presses on); 2 and 3 disagree. The union motion with 3 explained both
    better (mean excess 0.3 against 1.2 grey levels): 4 goes with 3, not with the older
    2."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(2):
        groups.observe(2, 4, 1.2)
        groups.observe(3, 4, 0.3)
    groups.forbid(2, [3])
    assert groups.representatives([2, 3, 4]) == {2: 2, 3: 3, 4: 3}
    groups.observe(2, 4, 1.4)  # one frame more with 2 outranks how closely
    assert groups.representatives([2, 3, 4]) == {2: 2, 3: 3, 4: 2}


def test_closeness_is_per_px_moved():
    """A pushed block's piece 4 agreed at two frames with the gripper 2 as it moved 5 px
    (excess 1.0) and at two with 3, a piece at rest (0.2 px: excess 0.2). Per px moved
    the gripper's union explained it better (0.2 against 0.4): pieces that barely move
    agree closely with anything at rest."""
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(2):
        groups.observe(2, 4, 1.0, moved=5.0)
        groups.observe(3, 4, 0.2, moved=0.2)
    groups.forbid(2, [3])
    assert groups.representatives([2, 3, 4]) == {2: 2, 3: 3, 4: 2}


def test_agreement_across_groups_outweighs_one_disagreeing_pair_not_a_forbidden_one():
    """Two pieces of an arm each (1 + 2, 3 + 4), 1 and 3 agreeing at 4 frames, 2 and 4
    (small pieces read wrong) disagreeing: one group while the agreements across are at
    least OUTWEIGH times the disagreeing pairs; a forbidden pair is never outweighed."""
    def arm(across: int, forbid: bool) -> dict[int, int]:
        groups = MotionBitGroups(agree=1.5, disagree=6.0)
        for _ in range(6):
            groups.observe(1, 2, 0.5)
            groups.observe(3, 4, 0.5)
        for _ in range(across):
            groups.observe(1, 3, 0.5)
        if forbid:
            groups.forbid(2, [4])
        else:
            groups.observe(2, 4, 7.0)
            groups.observe(2, 4, 7.0)
        assert groups.known(2, 4)
        return groups.representatives([1, 2, 3, 4])

    assert OUTWEIGH <= 4
    assert arm(4, forbid=False) == {1: 1, 2: 1, 3: 1, 4: 1}
    assert arm(OUTWEIGH - 1, forbid=False) == {1: 1, 2: 1, 3: 3, 4: 3}
    assert arm(4, forbid=True) == {1: 1, 2: 1, 3: 3, 4: 3}


def test_groups_disagree_at_two_frames_not_one():
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    groups.observe(1, 2, 0.5)  # agree
    groups.observe(1, 2, 9.0)  # one frame beyond the margin (under twice it) ...
    assert groups.representatives([1, 2]) == {1: 1, 2: 1}  # ... still one body
    assert not groups.known(1, 2)
    groups.observe(1, 2, 0.3)
    groups.observe(1, 2, 7.0)  # a second frame beyond it: different bodies for good
    assert groups.known(1, 2)
    assert groups.representatives([1, 2]) == {1: 1, 2: 2}


def test_touching_pairs():
    lab = np.zeros((20, 20), np.int32)
    lab[2:8, 2:8], lab[2:8, 9:15], lab[15:19, 15:19] = 1, 2, 3
    assert touching_pairs(lab, reach=2) == {(1, 2)}  # 2 px apart
    assert touching_pairs(lab, reach=1) == set()



def test_seen_still_remembers_stillness_and_ignores_unreliable_flow():
    flow = np.zeros((10, 12, 2), np.float32)
    flow[:, 6:] = (2.0, 0.0)  # the right half moves 2 px
    reliable = np.ones((10, 12), bool)
    reliable[:3] = False  # no trustworthy flow on the top rows: not seen at all
    carried = np.zeros((10, 12), np.int32)
    carried[5:, 8:] = 3  # last seen still at frame 2
    carried[:2, :2] = 5  # ... and at frame 4
    out = seen_still(carried, standing_still(cv2.magnitude(flow[..., 0], flow[..., 1]), reliable,
                                            move_threshold=0.6), frame_index=7)
    assert out.dtype == np.int32
    assert (out[3:, :6] == 8).all() and not out[2, :6].any()  # seen still now (frame 7)
    assert (out[:2, :2] == 5).all()  # not seen now: the carried frame stays
    assert not out[:5, 6:].any() and (out[5:, 8:] == 3).all() and not out[5:, 6:8].any()


def _random_frames(seed: int, shift: int) -> tuple[np.ndarray, np.ndarray, NodeGrid]:
    """An 80x120 random grey frame, the next one with everything moved ``shift`` px right,
    and a 20-node grid over them."""
    prev = np.random.default_rng(seed).uniform(0, 255, (80, 120)).astype(np.float32)
    return prev, np.roll(prev, shift, axis=1), NodeGrid.build(80, 120, 20, 5)


def _node_ids(grid: NodeGrid, labels: np.ndarray) -> np.ndarray:
    """(n,) int64 the label under each grid node."""
    h, w = labels.shape
    nx = np.clip(np.round(grid.points).astype(int), 0, [w - 1, h - 1])
    return labels[nx[:, 1], nx[:, 0]].astype(np.int64)


@pytest.mark.parametrize("last_still, stood_still", [(6, True), (0, False), (3, False)])
def test_newborn_is_kept_apart_only_if_it_was_seen_standing_still(last_still, stood_still):
    """A MotionBit born next to a moving one with the same motion: a block that stood still
    while the gripper moved (last seen still at frame 5, the gripper moving since frame 4)
    is another body for good; a part of the gripper that moved unlabelled, or that stood
    still only before the gripper first moved (frame 2), is not kept apart (its pair is
    observed and may agree)."""
    prev, cur, grid = _random_frames(1, 3)  # everything moved 3 px right
    labels = np.zeros(prev.shape, np.int32)
    labels[20:60, 20:60], labels[20:60, 60:100] = 1, 2  # 1 = gripper, 2 = newborn
    node_ids = _node_ids(grid, labels)
    back = grid.points - np.array([3.0, 0.0], np.float32)
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    still_before = np.where(node_ids == 2, last_still, 0)  # 1 + last frame seen still
    observe_touching(groups, grid, labels, node_ids, np.array([1, 2]), np.zeros(2),
                     np.array([[-3.0, 0.0], [-3.0, 0.0]]), {1, 2}, 2, still_before,
                     np.zeros(grid.n, np.int64), back, np.ones(grid.n), cur, prev,
                     disagree=6.0, first_moved={1: 4, 2: 8})
    assert groups.known(1, 2) == stood_still
    rep = groups.representatives([1, 2])
    assert (rep[2] == 1) != stood_still


@pytest.mark.parametrize("share, apart", [(0.8, True), (0.3, False)])
def test_a_piece_split_off_a_body_stays_apart_from_what_that_body_is_not(share, apart):
    """MotionBit 3 (the gripper's motion, next to gripper 1) is born where MotionBit 2, a
    drawer that disagrees with the gripper, stood at the last frame: born out of more than
    half 2's pixels, it is a piece of the drawer and stays apart from the gripper however
    well their motions agree; born mostly out of unlabelled pixels, it may join it."""
    prev, cur, grid = _random_frames(2, 3)
    labels = np.zeros(prev.shape, np.int32)
    labels[20:60, 20:60], labels[20:60, 60:100] = 1, 3
    node_ids = _node_ids(grid, labels)
    piece = np.flatnonzero(node_ids == 3)
    carried = np.where(node_ids == 1, 1, 0)
    carried[piece[:int(round(share * len(piece)))]] = 2
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    groups.forbid(2, [1])
    observe_touching(groups, grid, labels, node_ids, np.array([1, 3]), np.zeros(2),
                     np.array([[-3.0, 0.0], [-3.0, 0.0]]), {1, 3}, 3, np.zeros(grid.n, int),
                     carried, grid.points - np.array([3.0, 0.0], np.float32), np.ones(grid.n),
                     cur, prev, disagree=6.0, first_moved={1: 1, 2: 2, 3: 4})
    assert groups.known(1, 3) == apart
    assert (groups.representatives([1, 3])[3] == 1) != apart


@pytest.mark.parametrize("turning, shown_apart", [(False, True), (True, False)])
def test_a_pair_apart_is_shown_apart_where_one_motion_cannot_explain_both(turning,
                                                                         shown_apart):
    """MotionBits 1 and 2 agreed before and no longer touch; now 1 moves and 2 reads as
    standing still. A block set down (2) beside the hand moving on (1): the affine motion
    fitted to both explains neither, and they are shown apart at once. Two links of an
    arm turning about a point inside 2 (so 2 moves under a pixel): one motion explains
    both, and they stay one group at this frame."""
    rng = np.random.default_rng(4)
    h, w = 80, 120
    prev = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (3, 3), 0)
    if turning:  # backward: a turn by -0.05 rad about (85, 40)
        back = rigid_matrix(-0.05, np.zeros(2))
        back[:, 2] = np.array([85.0, 40.0]) - back[:, :2] @ np.array([85.0, 40.0])
    else:  # 1 moved 3 px right, 2 stood still
        back = np.array([[1.0, 0.0, -3.0], [0.0, 1.0, 0.0]])
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    cur = cv2.remap(prev, (back[0, 0] * xs + back[0, 1] * ys + back[0, 2]).astype(np.float32),
                    (back[1, 0] * xs + back[1, 1] * ys + back[1, 2]).astype(np.float32),
                    cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    if not turning:
        cur[:, 50:] = prev[:, 50:]
    grid = NodeGrid.build(h, w, 20, 5)
    labels = np.zeros((h, w), np.int32)
    labels[20:60, 10:40], labels[25:55, 70:100] = 1, 2
    node_ids = _node_ids(grid, labels)
    back_points = np.where((node_ids == 1)[:, None] | turning,
                           grid.points @ back[:, :2].T + back[:, 2], grid.points)
    theta_1 = float(np.arctan2(back[1, 0], back[0, 0]))
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(4):
        groups.observe(1, 2, 0.3, moved=3.0)
    observe_touching(groups, grid, labels, node_ids, np.array([1, 2]),
                     np.array([theta_1, 0.0]), np.array([back[:, 2], [0.0, 0.0]]), {1}, 3,
                     np.zeros(grid.n, int), node_ids, back_points.astype(np.float32),
                     np.ones(grid.n), cur, prev, disagree=6.0, first_moved={1: 1, 2: 1})
    assert not groups.known(1, 2)  # one frame apart: not yet for good
    assert (groups.representatives([1, 2])[2] == 2) == shown_apart


def test_a_pair_apart_whose_member_has_no_pixels_stays_together():
    """A MotionBit with a cluster but no pixels in the label map (its mask taken by
    others) tells nothing: its pair is not shown apart, and nothing fails."""
    prev, cur, grid = _random_frames(5, 3)
    labels = np.zeros(prev.shape, np.int32)
    labels[20:60, 10:40] = 1  # 2 and 3 have no pixels
    node_ids = np.zeros(grid.n, np.int64)
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    for _ in range(4):
        groups.observe(1, 3, 0.3, moved=3.0)
    observe_touching(groups, grid, labels, node_ids, np.array([1, 3]), np.zeros(2),
                     np.array([[-3.0, 0.0], [0.0, 0.0]]), {1}, 4, np.zeros(grid.n, int),
                     node_ids, grid.points.copy(), np.ones(grid.n), cur, prev,
                     disagree=6.0, first_moved={1: 1, 3: 1})
    assert groups.representatives([1, 3]) == {1: 1, 3: 1}


@pytest.mark.parametrize("min_agreeing, joined", [(0.0, True), (0.5, False)])
def test_marks_that_barely_move_agree_only_above_the_motion_floor(min_agreeing, joined):
    """Two touching MotionBits at rest, "moving" by 0.2 px (under a moving camera, the
    static world's model is off by that much): one motion explains both, so they agree --
    unless agreement needs a union motion of ``min_agreeing`` px (a body at rest and a
    mark spilled on the table beside it are not one body for standing still together)."""
    prev, cur, grid = _random_frames(3, 0)
    labels = np.zeros(prev.shape, np.int32)
    labels[20:60, 20:60], labels[20:60, 60:100] = 1, 2
    node_ids = _node_ids(grid, labels)
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    observe_touching(groups, grid, labels, node_ids, np.array([1, 2]), np.zeros(2),
                     np.array([[-0.2, 0.0], [-0.2, 0.0]]), set(), 3, np.zeros(grid.n, int),
                     node_ids, grid.points - np.array([0.2, 0.0], np.float32),
                     np.ones(grid.n), cur, prev, disagree=6.0, first_moved={1: 1, 2: 1},
                     min_agreeing=min_agreeing)
    assert not groups.known(1, 2)  # never apart for good
    assert (groups.representatives([1, 2])[2] == 1) == joined


def test_static_memory_reveals_background_seen_again_after_it_was_covered():
    rng = np.random.default_rng(0)
    table = rng.integers(0, 256, (40, 60, 3), dtype=np.uint8)
    memory = StaticMemory(table.shape[:2], tolerance=10.0, covered=20.0)
    everywhere = np.ones(table.shape[:2], bool)

    def step(cur, prev, standing=everywhere):
        gray = [f.mean(axis=2, dtype=np.float32) for f in (cur, prev)]
        residual = np.abs(gray[0] - gray[1])  # "nothing moved" against the last frame
        revealed = memory.observe(cur, gray[0], residual)
        if revealed is not None:  # lowered to the residual against the memory there
            assert (residual[revealed] < 1e-3).all()
            assert (residual[~revealed] == np.abs(gray[0] - gray[1])[~revealed]).all()
        memory.update(cur, gray[0], grey_change(*gray), standing,
                      np.zeros(standing.shape, np.int32))
        return revealed

    step(table, table)  # seen standing still
    arm = table.copy()
    arm[10:30, 10:50] = 30  # a flat dark arm covers the middle
    moving = everywhere.copy()
    moving[10:30, 10:50] = False  # (its flow moves)
    step(arm, table, moving)
    back = table.copy()
    # the right half uncovers something new: the same grey levels, other colours
    back[10:30, 30:50] = table[10:30, 30:50, ::-1]
    revealed = step(back, arm, moving)
    assert revealed[13:27, 13:27].all()  # left half, away from the window's reach
    assert not revealed[14:26, 34:46].any()  # another look: not the static world
    assert not revealed[:8].any()  # never covered: the plain "nothing moved" holds
    # seen still again, the pixel is remembered anew and is no longer "revealed"
    step(back, back)
    assert not step(back, back).any()
    # switched off, nothing is revealed
    off = StaticMemory(table.shape[:2], tolerance=0.0, covered=20.0)
    assert off.observe(table, table.mean(axis=2), everywhere * 1.0) is None


def test_static_memory_follows_a_moving_camera():
    """The camera pans 3 px to the left while an arm uncovers the table: the table is seen
    again 3 px further right in the image, and revealed there; what just came into view
    is not known."""
    rng = np.random.default_rng(1)
    world = rng.integers(0, 256, (40, 70, 3), dtype=np.uint8)  # the table, wider than the view
    view = [world[:, 5:65], world[:, 2:62]]  # the camera pans: the table moves 3 px right
    memory = StaticMemory(view[0].shape[:2], tolerance=10.0, covered=20.0)
    everywhere = np.ones(view[0].shape[:2], bool)
    ys, xs = np.mgrid[:40, :60].astype(np.float32)
    pan = np.stack([xs - 3.0, ys], -1)  # where each pixel's static world was at the last frame

    def step(cur, prev, standing=everywhere, world=None):
        gray = [f.mean(axis=2, dtype=np.float32) for f in (cur, prev)]
        residual = np.abs(gray[0] - gray[1])
        revealed = memory.observe(cur, gray[0], residual, world)
        memory.update(cur, gray[0], grey_change(*gray), standing,
                      np.zeros(standing.shape, np.int32))
        return revealed

    step(view[0], view[0])  # seen standing still
    arm = view[0].copy()
    arm[10:30, 10:40] = 30  # a flat dark arm covers the middle
    moving = everywhere.copy()
    moving[10:30, 10:40] = False
    step(arm, view[0], moving)
    revealed = step(view[1], arm, moving, world=pan)  # the arm leaves as the camera pans
    assert revealed[13:27, 16:40].all()  # the uncovered table, 3 px to the right
    assert not revealed[:8].any()  # never covered
    assert not memory.known[:, :3].any()  # just came into view
    assert memory.known[:, 3:].all()


def test_hide_small_zeroes_whole_labels_under_the_area():
    labels = np.zeros((20, 30), np.int32)
    labels[2:12, 2:12] = 3  # 100 px
    labels[15:18, 20:23] = 7  # 9 px
    labels[0, 29] = 3  # a detached pixel of label 3 counts towards its area
    out = hide_small(labels, 10)
    assert set(np.unique(out)) == {0, 3} and (out[labels == 3] == 3).all()
    assert hide_small(labels, 9) is labels  # nothing under 9 px: unchanged


def test_hide_thin_zeroes_stripes_and_keeps_bodies():
    """Marks along a wood grain's lines (3 px stripes) are not shown; a solid block, a
    block with a stripe of its own, and a 7 px wide rod pushed across the table are."""
    labels = np.zeros((120, 160), np.int32)
    labels[10:40, 10:40] = 2  # a block
    labels[38:42, 40:90] = 2  # ... and a stripe of the grain beside it
    for y in range(60, 100, 8):
        labels[y:y + 3, 10:70] = 5  # stripes of one mark
    labels[60:67, 90:150] = 6  # a rod, 7 px wide
    out = hide_thin(labels, 7)
    assert set(np.unique(out)) == {0, 2, 6}
    assert (out[labels != 5] == labels[labels != 5]).all()
    solid = np.where(labels == 5, 0, labels)
    assert hide_thin(solid, 7) is solid  # nothing hidden: unchanged
    assert set(np.unique(hide_thin(labels, 8))) == {0, 2}  # the rod is thinner than 8 px


def test_hide_thin_zeroes_the_slivers_apart_from_a_body_s_mark():
    """A block's mark that also took a sliver of a shadow's edge away from the block (3 px
    wide) is shown without the sliver; a compact piece apart from it (a face the sliver
    does not join) stays, and so does a sliver touching the block."""
    labels = np.zeros((120, 160), np.int32)
    labels[10:40, 10:40] = 2  # the block
    labels[80:83, 20:120] = 2  # a shadow's edge, apart
    labels[60:72, 100:112] = 2  # a compact piece, apart
    labels[20:23, 40:70] = 2  # a sliver touching the block
    out = hide_thin(labels, 7)
    assert not out[80:83].any()
    assert (out[labels != 2] == 0).all() and (out[10:40, 10:40] == 2).all()
    assert (out[60:72, 100:112] == 2).all() and (out[20:23, 40:70] == 2).all()


def test_a_motionbit_trimmed_below_the_minimum_is_not_shown(monkeypatch):
    """The minimum area holds for the mask shown, after it is trimmed to the image's
    edges, not for the motion's mask before (a sliver of smeared flow that the edges
    trim to a few pixels is not shown)."""
    clip = render_planar_clip([Body((Polygon.rect(40, 80, 100, 140, texture_seed=3),),
                                    velocity=(4.0, 0.0))], size=SIZE, n_frames=6, seed=2)
    shown = [len(r.motionbits) for r in segment_video(clip.frames, CONFIG)]
    assert shown[-1] == 1  # as it is: one MotionBit

    def trim_to_a_corner(label_map, rgb, band):  # keeps 3 x 3 px of each mask
        out = np.zeros_like(label_map)
        for lab in np.unique(label_map[label_map > 0]):
            ys, xs = np.nonzero(label_map == lab)
            y, x = ys[0], xs[0]
            out[y:y + 3, x:x + 3] = np.where(label_map[y:y + 3, x:x + 3] == lab, lab, 0)
        return out

    monkeypatch.setattr(segmenter_module, "snap_to_edges", trim_to_a_corner)
    assert all(len(r.motionbits) == 0 for r in segment_video(clip.frames, CONFIG))


def _relabel_in_order(labels: np.ndarray) -> np.ndarray:
    """Ids replaced by 1, 2, ... in order of first appearance (raster order)."""
    ids, first = np.unique(labels, return_index=True)
    order = ids[np.argsort(first)]
    order = order[order > 0]
    lut = np.zeros(labels.max() + 1, np.int32)
    lut[order] = np.arange(1, len(order) + 1)
    return lut[labels]


def test_a_cut_starts_a_new_shot():
    """After a cut to another scene the segmenter labels the new shot as it would alone:
    nothing of the old shot is carried over, and ids go on from the old shot's."""
    def shot(x0, vx, seed):
        return render_planar_clip([Body((Polygon.rect(x0, 80, x0 + 60, 140, texture_seed=seed),),
                                        velocity=(vx, 0.0))], size=SIZE, n_frames=6,
                                  seed=seed).frames
    first, second = shot(40, 4.0, 2), shot(200, -3.0, 5)
    joined = list(segment_video(list(first) + list(second), CONFIG))
    alone = list(segment_video(second, CONFIG))
    old_ids = {m.id for r in joined[:6] for m in r.motionbits}
    assert old_ids
    for cut, one in zip(joined[6:], alone):
        assert np.array_equal(_relabel_in_order(cut.labels), _relabel_in_order(one.labels))
        assert all(m.id > max(old_ids) for m in cut.motionbits)
    assert len(alone[-1].motionbits) == 1
    # without the cut test the old shot's MotionBit lives on in the new shot
    carried = list(segment_video(list(first) + list(second), CONFIG.with_(cut_share=0.0)))
    assert any(m.id in old_ids for r in carried[6:] for m in r.motionbits)


def test_a_stopped_body_keeps_its_id_after_another_passes_in_front():
    """A block moves, stops, and a taller bar sweeps across in front of it and on: once
    uncovered, the block looks as it did when it stopped and gets its MotionBit back, under
    the same id (before, its pixels went back to the background)."""
    block = Body((Polygon.rect(60, 100, 100, 140, texture_seed=3),), velocity=(4.0, 0.0),
                 stop=4)
    bar = Body((Polygon.rect(0, 70, 40, 170, texture_seed=6),), velocity=(14.0, 0.0),
               start=7)
    clip = render_planar_clip([block, bar], size=SIZE, n_frames=22, seed=2)
    results = list(segment_video(clip.frames, CONFIG))
    body = clip.labels[5] == 1  # where the block stands from frame 4 on
    ids, counts = np.unique(results[5].labels[body], return_counts=True)
    block_id = ids[np.argmax(counts)]
    assert block_id > 0 and counts.max() > 0.8 * body.sum()
    # covered by the bar in between
    assert max((r.labels[body] != block_id).mean() for r in results[8:18]) > 0.9
    assert not (clip.labels[-1][body] == 2).any()  # the bar has gone on
    assert (results[-1].labels[body] == block_id).mean() > 0.8


def test_static_memory_gives_ids_back_only_to_bodies_that_stand_still():
    """A pixel seen still inside MotionBit 5, covered, then seen again as it was: it is 5's
    again -- unless 5 moves now (it stood elsewhere since; a look-alike may stand there)."""
    rng = np.random.default_rng(1)
    table = rng.integers(0, 256, (40, 60, 3), dtype=np.uint8)
    gray = table.mean(axis=2, dtype=np.float32)
    everywhere = np.ones(table.shape[:2], bool)
    labels = np.zeros(table.shape[:2], np.int32)
    labels[10:30, 10:30] = 5
    memory = StaticMemory(table.shape[:2], tolerance=10.0, covered=20.0)
    memory.observe(table, gray, np.zeros_like(gray))
    memory.update(table, gray, grey_change(gray, gray), everywhere,
                  labels)  # seen still, inside 5
    hand = table.copy()
    hand[5:35, 5:35] = 40  # something passes in front
    hand_gray = hand.mean(axis=2, dtype=np.float32)
    memory.observe(hand, hand_gray, np.abs(hand_gray - gray))
    memory.update(hand, hand_gray, grey_change(hand_gray, gray), ~(labels > 0),
                  np.zeros_like(labels))
    revealed = memory.observe(table, gray, np.abs(gray - hand_gray))
    nothing = np.zeros_like(labels)
    back, given = memory.restore(nothing, revealed, [])
    assert (back[13:27, 13:27] == 5).all() and given[13:27, 13:27].all()
    assert not (back[labels == 0] > 0).any()
    out, given = memory.restore(nothing, revealed, [5])
    assert out is nothing and given is None
    memory.forget(np.array([5]))  # retired
    out, given = memory.restore(nothing, revealed, [])
    assert out is nothing and given is None


def test_a_block_pushed_by_a_bar_is_a_motionbit_of_its_own():
    """A bar moves from the first frame and, overlapping a block's edge, pushes it from
    frame 6 on with its own motion. The block stood still while the bar moved, so none of
    it may join the bar's MotionBit; it gets one of its own (before: up to 0.89 of it under
    the bar's id and none of it in a MotionBit of its own)."""
    v, start, side = 4.0, 6, 42
    x0 = 70 + v * start
    block = Body((Polygon.rect(x0, 95, x0 + side, 95 + side, texture_seed=5),),
                 velocity=(v, 0.0), start=start)
    bar = Body((Polygon.rect(20, 80, 82, 160, texture_seed=6),), velocity=(v, 0.0))
    clip = render_planar_clip([block, bar], size=SIZE, n_frames=16, seed=2)
    results = list(segment_video(clip.frames, CONFIG))
    for t in range(8, 16):
        labels, truth = results[t].labels, clip.labels[t]
        bar_id = np.bincount(labels[truth == 2]).argmax()
        assert bar_id > 0 and (labels[truth == 1] == bar_id).mean() < 0.2, t
    on_block = results[-1].labels[clip.labels[-1] == 1]
    ids, counts = np.unique(on_block[on_block > 0], return_counts=True)
    assert counts.max() > 0.7 * on_block.size and ids[np.argmax(counts)] != bar_id


def test_drop_seen_still_drops_only_places_seen_still_since_the_motionbit_moved():
    """MotionBit 1 (first moved at frame 2) now also holds a 6 px wide place and a 1 px
    sliver along its outline that were seen standing still at frame 4."""
    labels = np.zeros((20, 30), np.int32)
    labels[5:15, 4:12] = 1  # its body
    labels[5:15, 12:18] = 1  # the place that stood still
    labels[4, 4:12] = 1  # a sliver along its outline
    labels[16:19, 20:28] = 2  # a MotionBit not known to have moved: never dropped
    prior = np.where(labels == 1, 0, labels)
    prior[5:15, 4:12] = 1  # held at the last frame: stays, whenever it stood still
    still_seen = np.full(labels.shape, 5, np.int32)  # 1 + the last frame seen still
    out = drop_seen_still(labels.copy(), prior, still_seen, {1: 2})
    expected = labels.copy()
    expected[5:15, 12:18] = 0
    assert (out == expected).all()
    # seen still only before 1 first moved: nothing goes
    assert (drop_seen_still(labels.copy(), prior, still_seen, {1: 5}) == labels).all()


def _faces(shape=(60, 80)):
    """A block seen from above at an angle, as two marks: its top face (2) and, below it,
    its side (5); a third mark (7) far away."""
    shown = np.zeros(shape, np.int32)
    shown[10:22, 20:50] = 2
    shown[22:40, 20:50] = 5
    shown[45:55, 60:75] = 7
    return shown


def _grey(shape=(60, 80)):
    """An (h, w, 3) uint8 frame of one grey: no two marks differ from their surface."""
    return np.full((*shape, 3), 128, np.uint8)


def test_join_convex_joins_the_faces_of_a_body_at_rest_under_the_smaller_label():
    shown = _faces()
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    pairs = join_convex(shown, _grey(), set(), groups)
    assert pairs == [(2, 5)]
    rep = {2: 2, 3: 5, 5: 5, 7: 7}
    joined, new_rep = apply_joins(shown, rep, pairs)
    assert set(np.unique(joined)) == {0, 2, 7}
    assert np.count_nonzero(joined == 2) == np.count_nonzero((shown == 2) | (shown == 5))
    assert new_rep == {2: 2, 3: 2, 5: 2, 7: 7}
    # recorded as an agreement: the next frame's groups show them as one
    assert groups.representatives([2, 5, 7]) == {2: 2, 5: 2, 7: 7}


def test_join_convex_leaves_moving_marks_l_shapes_corners_and_disagreeing_pairs():
    groups = MotionBitGroups(agree=1.5, disagree=6.0)
    shown = _faces()
    grey = _grey()
    assert join_convex(shown, grey, {5}, groups) == []  # one moves: its motion decides
    ell = shown.copy()
    ell[22:40, 20:50] = 0
    ell[10:40, 50:58] = 5  # a shadow beside the block: together an L
    assert join_convex(ell, grey, set(), groups) == []
    corner = np.zeros((60, 80), np.int32)
    corner[10:30, 10:30] = 2
    corner[30:50, 30:50] = 5  # two blocks touching at a corner
    assert join_convex(corner, grey, set(), groups) == []
    spilled = _faces()
    spilled[22:60, 0:80] = 5  # a mark spilled over the table below the block's top
    assert join_convex(spilled, grey, set(), groups) == []
    groups.forbid(2, [5])  # known to be two bodies
    assert join_convex(shown, grey, set(), groups) == []
    rep = {2: 2, 5: 5}
    same_shown, same_rep = apply_joins(shown, rep, [])
    assert same_shown is shown and same_rep is rep


def test_join_convex_joins_faces_that_fill_less_of_their_hull_if_one_colour_but_for_light():
    """A block's top face and its side, a notch out of the side (together 84% of their
    hull): one body if they are one colour, lit and shaded, unlike the table around them;
    not two bodies of two colours, nor two marks of the table's colour (a shadow)."""
    shown = _faces()
    shown[28:40, 27:43] = 0  # a notch in the side's lower edge: 84% of the hull
    table, red, dark_red, blue = (90, 140, 90), (200, 40, 40), (100, 20, 20), (40, 40, 200)
    for top, side, joined in ((red, dark_red, True), (red, blue, False),
                              ((45, 70, 45), (30, 47, 30), False)):  # the table in shadow
        rgb = np.zeros((60, 80, 3), np.uint8)
        rgb[...] = table
        rgb[shown == 2] = top
        rgb[shown == 5] = side
        groups = MotionBitGroups(agree=1.5, disagree=6.0)
        assert join_convex(shown, rgb, set(), groups) == ([(2, 5)] if joined else [])
    # at 80% of the hull or less, colour does not join them (a spill, two bodies)
    shown[26:40, 26:44] = 0  # 77%
    rgb[...] = table
    rgb[shown == 2], rgb[shown == 5] = red, dark_red
    assert join_convex(shown, rgb, set(), MotionBitGroups(agree=1.5, disagree=6.0)) == []


def test_a_mark_moves_for_the_joins_only_where_most_of_it_moves():
    """A block set down (MotionBit 3) shown with a sliver (4) that reads a neighbour's
    smeared flow: the mark does not move; the carrier (5, 6) whose larger part moves
    does."""
    state = np.zeros((40, 40), np.int32)
    state[5:25, 5:25] = 3
    state[25:28, 5:25] = 4  # the sliver, moving
    state[30:38, 5:35] = 5  # the carrier's hand, moving ...
    state[28:30, 25:35] = 6  # ... and a piece of it at rest
    rep = {3: 3, 4: 3, 5: 5, 6: 5}
    assert mostly_moving(state, rep, {4, 5}, {3, 5}) == {5}
    assert mostly_moving(state, rep, {3, 4, 5}, {3, 5}) == {3, 5}
    assert mostly_moving(state, rep, {4, 5}, set()) == set()
