import pytest

from motionbits import MotionBitsConfig, MotionBitsSegmenter
from motionbits.synth import demo_clip


def best_iou(pred, gt_mask):
    """IoU of a ground-truth mask with the predicted label covering most of it, and that label."""
    import numpy as np

    ids, cnt = np.unique(pred[gt_mask], return_counts=True)
    best = int(ids[np.argmax(cnt)])
    if best == 0:
        return 0.0, 0
    p = pred == best
    return float((p & gt_mask).sum() / (p | gt_mask).sum()), best


@pytest.fixture(scope="session")
def demo_run():
    """The built-in 480x640, 16-frame clip segmented once with the paper's defaults."""
    clip = demo_clip(n_frames=16)
    seg = MotionBitsSegmenter(MotionBitsConfig())
    results = [seg.update(f) for f in clip.frames]
    return clip, results
