"""The segmenter's temporal state over the whole video and over a sliding window."""

from __future__ import annotations

import numpy as np
import pytest

from motionbits import MotionBitsConfig, MotionBitsSegmenter
from motionbits.synth import demo_clip
from motionbits.temporal import TemporalState

H, W = 20, 40
STILL = np.zeros((H, W, 2), np.float32)  # no motion: maps are carried unchanged


def labels_apart() -> np.ndarray:
    lab = np.zeros((H, W), np.int32)
    lab[5:15, 5:20], lab[5:15, 20:35] = 1, 2
    return lab


def labels_together() -> np.ndarray:
    lab = np.zeros((H, W), np.int32)
    lab[5:15, 5:35] = 1
    return lab


def run(state: TemporalState, n_apart: int, n_together: int, raw_apart=5.0, raw_together=1.0):
    """Fold ``n_apart`` maps with the two halves separated, then ``n_together`` with them
    joined; returns, per fold, (history class of the left half, of the right half, past
    max of edge 0, frames the read copy covers)."""
    out = []
    prev = np.zeros((H, W), np.int32)
    for t in range(n_apart + n_together):
        lab, raw = (labels_apart(), raw_apart) if t < n_apart else (labels_together(), raw_together)
        (carried,), hist = state.carry([prev], STILL)
        assert np.array_equal(carried, prev)  # no motion: carried unchanged
        past = state.project(lambda pm: pm)
        out.append((hist[10, 10], hist[10, 30], past[0, 0], state.covered[state.oldest]))
        state.fold(np.full((4, 2), raw), lab, margin=1)
        prev = lab
    return out


def test_whole_video_keeps_a_split_forever():
    trace = run(TemporalState((H, W), (4, 2)), n_apart=3, n_together=30)
    left, right, past, covered = trace[-1]
    assert left != right and left > 0 and right > 0  # separated once: separated for good
    assert past == 5.0  # the largest weight ever seen
    assert covered == 32


@pytest.mark.parametrize("window", [2, 5, 8, 13])
def test_window_forgets_after_n_frames(window):
    state = TemporalState((H, W), (4, 2), window=window)
    trace = run(state, n_apart=3, n_together=3 * window)
    parts = len(state.offsets)
    for t, (left, right, past, covered) in enumerate(trace):
        assert covered <= window
        if t >= window:  # the read copy covers more than N - ceil(N / P) > 3N/4 of the last N
            assert covered > window - -(-window // parts) and covered > 0.75 * window
    # the copy read at the end covers only joined frames: the halves are one class again
    left, right, past, _ = trace[-1]
    assert left == right and left > 0
    assert past == 1.0
    # while the split is inside the window, it holds
    left, right, past, _ = trace[3]
    assert left != right and past == 5.0


def test_window_is_validated():
    with pytest.raises(ValueError, match="window=1"):
        MotionBitsConfig(window=1)
    with pytest.raises(ValueError, match="window must be >= 2"):
        TemporalState((H, W), (4, 2), window=0)


def test_segmenter_with_a_window():
    clip = demo_clip(n_frames=8, size=(240, 320))
    config = MotionBitsConfig(n_nodes=900, max_side=320)
    whole, windowed = MotionBitsSegmenter(config), MotionBitsSegmenter(config.with_(window=3))
    for frame in clip.frames:
        a, b = whole.update(frame), windowed.update(frame)
    assert whole._temporal.covered.tolist() == [7]
    assert windowed._temporal.covered.max() <= 3 and windowed._temporal.histories.shape[0] == 3
    # every body found without the window is found with it (on 8 frames, a window of 3
    # changes little: the bodies move rigidly throughout)
    gt = clip.gt
    found = 0
    for g in np.unique(gt[gt > 0]):
        m = gt == g
        if (a.labels[m] > 0).mean() > 0.5:
            found += 1
            assert (b.labels[m] > 0).mean() > 0.5
    assert found >= 4
    assert (a.labels > 0).sum() == pytest.approx((b.labels > 0).sum(), rel=0.2)
