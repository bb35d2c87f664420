"""Only what moved is a MotionBit: uncovered background returns to background, one body is one
MotionBit, pieces that never moved are retired (issue "Only what moved")."""

import numpy as np
import pytest

from motionbits import MotionBitsConfig, segment_video
from motionbits.evidence import appearance_consistent, gradient_magnitude, pull_back
from motionbits.merging import MotionBitGroups, touching_pairs
from motionbits.synth.planar import Body, Polygon, render_planar_clip

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
    groups.observe(3, 8, 9.0)  # a clear disagreement is final ...
    groups.observe(3, 8, 0.1)  # ... and a later agreement does not undo it
    rep = groups.representatives([3, 5, 8])
    assert rep[3] != rep[8]


def test_touching_pairs():
    lab = np.zeros((20, 20), np.int32)
    lab[2:8, 2:8], lab[2:8, 9:15], lab[15:19, 15:19] = 1, 2, 3
    assert touching_pairs(lab, reach=2) == {(1, 2)}  # 2 px apart
    assert touching_pairs(lab, reach=1) == set()

