"""The segmenter on generated planar scenes with exact ground truth."""

import numpy as np
import pytest
from conftest import best_iou

from motionbits import MotionBitsConfig, MotionBitsSegmenter, segment_video
from motionbits.synth import Body, Polygon, render_planar_clip

CASES = {
    1: "rotation about a far pivot",
    2: "pure translation",
    3: "two glued shapes moving as one",
    4: "touching body A (translation)",
    5: "touching body B (rotation)",
    6: "moves, then stops",
}


def test_demo_is_480x640_with_enough_frames(demo_run):
    clip, results = demo_run
    assert clip.frames.shape[1:3] == (480, 640) and len(clip.frames) >= 12
    assert all(r.labels.shape == (480, 640) and r.labels.dtype == np.int32 for r in results)


@pytest.mark.parametrize("gt_id", sorted(CASES), ids=list(CASES.values()))
def test_each_moving_body_is_segmented(demo_run, gt_id):
    clip, results = demo_run
    iou, _ = best_iou(results[-1].labels, clip.gt == gt_id)
    assert iou >= 0.85, f"{CASES[gt_id]}: IoU {iou:.3f}"


def test_bodies_get_distinct_ids(demo_run):
    clip, results = demo_run
    ids = [best_iou(results[-1].labels, clip.gt == g)[1] for g in CASES]
    assert len(set(ids)) == len(ids), f"bodies share ids: {ids}"


def test_background_precision_and_static_body(demo_run):
    clip, results = demo_run
    pred = results[-1].labels
    bg = pred == 0
    assert (bg & (clip.gt == 0)).sum() / bg.sum() >= 0.95
    # the static distractor (last body) never moved: background
    static = clip.labels[-1] == 0
    distractor = np.zeros_like(static)
    import cv2

    pts = np.round(np.asarray(clip.bodies[-1].polygons[0].points)).astype(np.int32)
    cv2.fillPoly(distractor.view(np.uint8), [pts], 1)
    assert (pred[distractor > 0] == 0).mean() > 0.98


def test_first_frame_is_background(demo_run):
    _, results = demo_run
    assert not results[0].labels.any() and results[0].motionbits == []


def test_body_that_stops_keeps_id_and_mask(demo_run):
    clip, results = demo_run
    stop = clip.bodies[5].stop  # GT id 6 stops after this frame
    _, id_at_stop = best_iou(results[stop].labels, clip.labels[stop] == 6)
    iou_end, id_end = best_iou(results[-1].labels, clip.gt == 6)
    assert id_at_stop == id_end != 0
    assert iou_end >= 0.85
    rec = {mb.id: mb for mb in results[-1].motionbits}[id_end]
    assert not rec.moving and rec.last_moved <= stop + 1 and rec.first_moved == 1


def test_records_match_label_map(demo_run):
    _, results = demo_run
    res = results[-1]
    for mb in res.motionbits:
        ys, xs = np.nonzero(res.labels == mb.id)
        assert mb.area == len(xs)
        assert mb.bbox == (xs.min(), ys.min(), xs.max() + 1, ys.max() + 1)
        assert mb.centroid == pytest.approx((xs.mean(), ys.mean()))
    moving = [mb for mb in res.motionbits if mb.moving]
    assert moving and all(np.any(np.asarray(mb.twist) != 0) for mb in moving)


def _small_scene(n_frames=6):
    bodies = [
        Body((Polygon.rect(30, 30, 90, 80, 1),), velocity=(2.0, 1.0)),
        Body((Polygon.regular(220, 120, 35, 5, texture_seed=2),), omega=0.03, pivot=(200, 60)),
    ]
    return render_planar_clip(bodies, size=(240, 320), n_frames=n_frames, seed=3)


SMALL = MotionBitsConfig(n_nodes=2500)  # 240x320 input, processed at the default 640 side


def test_same_input_same_output():
    clip = _small_scene()
    a = [r.labels for r in segment_video(clip.frames, SMALL)]
    b = [r.labels for r in segment_video(clip.frames, SMALL)]
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    for g in (1, 2):
        assert best_iou(a[-1], clip.gt == g)[0] >= 0.85


def test_input_size_is_preserved_at_other_resolutions():
    clip = _small_scene(4)
    big = np.repeat(np.repeat(clip.frames, 2, axis=1), 2, axis=2)  # 480x640 input
    res = list(segment_video(big, SMALL))
    assert res[-1].labels.shape == (480, 640)
    gt_big = np.repeat(np.repeat(clip.gt, 2, axis=0), 2, axis=1)
    assert best_iou(res[-1].labels, gt_big == 1)[0] >= 0.85


def test_memory_state_does_not_grow():
    clip = _small_scene(8)
    seg = MotionBitsSegmenter(SMALL)
    sizes = []
    for f in clip.frames:
        seg.update(f)
        sizes.append(sum(v.nbytes for v in vars(seg).values() if isinstance(v, np.ndarray)))
    assert sizes[2] == sizes[-1]
