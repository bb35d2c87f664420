"""Marks on videos: stable numbers/colours, outputs, sampling, metadata JSON."""

import json

import cv2
import numpy as np
import pytest
from PIL import Image

from somprompt import (
    ColorPalette,
    MarkRegistry,
    SetOfMarkRenderer,
    frames_for_vlm,
    mark_video,
    resize_max_side,
    sample_for_vlm,
    sample_frame_indices,
    write_gif,
    write_mp4,
)


def moving_scene(T=6, h=96, w=128):
    """Two squares moving right; a third object (id 1) appears at frame 3."""
    rng = np.random.default_rng(1)
    frames, maps = [], []
    for t in range(T):
        frames.append(rng.integers(0, 256, (h, w, 3), dtype=np.uint8))
        lm = np.zeros((h, w), np.uint16)
        lm[10:40, 5 + 6 * t:35 + 6 * t] = 40
        lm[55:85, 60 + 4 * t:90 + 4 * t] = 7
        if t >= 3:
            lm[5:20, 100:120] = 1
        maps.append(lm)
    return frames, maps


def test_ids_keep_numbers_and_colours_on_every_frame():
    frames, maps = moving_scene()
    video = mark_video(frames, maps, SetOfMarkRenderer(mode="mask", opacity=1.0))
    reg = video.registry
    # first seen in frame 0 ascending: 7 -> 1, 40 -> 2; id 1 only appears later -> 3
    assert (reg.number(7), reg.number(40), reg.number(1)) == (1, 2, 3)
    pal = ColorPalette.default()
    for t, (out, lm) in enumerate(zip(video.frames, maps)):
        for obj_id in np.unique(lm[lm > 0]):
            colours = np.unique(out[lm == obj_id], axis=0)
            assert colours.tolist() == [list(pal.by_number(reg.number(int(obj_id))))], (t, obj_id)


def test_labels_follow_their_masks():
    frames, maps = moving_scene()
    video = mark_video(frames, maps)
    for pl, lm in zip(video.placements, maps):
        for obj_id, p in pl.items():
            assert lm[p.point[1], p.point[0]] == obj_id


def test_metadata_and_json():
    frames, maps = moving_scene()
    video = mark_video(frames, maps, frame_indices=[10, 11, 12, 13, 14, 15])
    doc = json.loads(video.to_json())
    assert doc["style"] == "number" and doc["image_size"] == [128, 96]
    by_id = {m["obj_id"]: m for m in doc["marks"]}
    assert [m["number"] for m in doc["marks"]] == [1, 2, 3]
    assert by_id[1]["frames_seen"] == [13, 14, 15]
    assert by_id[7]["frames_seen"] == list(range(10, 16))
    last = maps[-1]
    ys, xs = np.nonzero(last == 40)
    assert by_id[40]["bbox"] == [xs.min(), ys.min(), xs.max() + 1, ys.max() + 1]
    assert by_id[40]["area"] == int((last == 40).sum())
    assert by_id[40]["frame"] == 15
    ax, ay = by_id[40]["anchor"]
    assert last[ay, ax] == 40
    assert by_id[7]["color"] == "#e6194b" and by_id[7]["text"] == "1"


def test_letter_style_video():
    frames, maps = moving_scene(T=2)
    video = mark_video(frames, maps, style="letter")
    assert [video.marks[i].text for i in (7, 40)] == ["a", "b"]


def test_mp4_and_gif_round_trip(tmp_path):
    frames, maps = moving_scene(T=5)
    video = mark_video(frames, maps)
    mp4 = video.to_mp4(tmp_path / "out" / "marks.mp4", fps=5)
    cap = cv2.VideoCapture(str(mp4))
    n = 0
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        assert bgr.shape == (96, 128, 3)
        n += 1
    cap.release()
    assert n == 5
    gif = video.to_gif(tmp_path / "marks.gif", fps=5)
    with Image.open(gif) as im:
        assert im.n_frames == 5 and im.size == (128, 96)
        im.seek(0)
        first = np.asarray(im.convert("RGB")).astype(int)
    # GIF palettes quantise colours; the picture is still the marked frame
    assert np.abs(first - video.frames[0].astype(int)).mean() < 20


def test_writers_reject_bad_frames(tmp_path):
    with pytest.raises(ValueError, match="no frames"):
        write_mp4([], tmp_path / "a.mp4")
    with pytest.raises(ValueError, match="shape"):
        write_gif([np.zeros((8, 8, 3), np.uint8), np.zeros((9, 8, 3), np.uint8)], tmp_path / "a.gif")
    with pytest.raises(ValueError, match="fps"):
        write_mp4([np.zeros((8, 8, 3), np.uint8)], tmp_path / "a.mp4", fps=0)


@pytest.mark.parametrize(
    "total, n, expected",
    [(10, 4, [0, 3, 6, 9]), (5, None, [0, 1, 2, 3, 4]), (5, 9, [0, 1, 2, 3, 4]), (7, 1, [6]), (2, 2, [0, 1])],
)
def test_sample_frame_indices(total, n, expected):
    assert sample_frame_indices(total, n) == expected


def test_sample_frame_indices_errors():
    with pytest.raises(ValueError):
        sample_frame_indices(0, 3)
    with pytest.raises(ValueError):
        sample_frame_indices(5, 0)


def test_frames_for_vlm_sizes_and_types():
    frames, _ = moving_scene(T=9)
    out = frames_for_vlm(frames, max_side=64, num_frames=3)
    assert len(out) == 3 and all(f.shape == (48, 64, 3) for f in out)
    pil = frames_for_vlm([Image.fromarray(f) for f in frames], max_side=32, num_frames=2)
    assert all(isinstance(p, Image.Image) and p.size == (32, 24) for p in pil)
    assert frames_for_vlm(frames, max_side=1000, num_frames=None)[0].shape == (96, 128, 3)  # never enlarged


def test_sample_for_vlm_resizes_label_maps_with_nearest():
    frames, maps = moving_scene(T=6)
    f, l, idx = sample_for_vlm(frames, maps, max_side=64, num_frames=3)
    assert idx == [0, 2, 5] or idx == [0, 3, 5]
    assert f[0].shape == (48, 64, 3) and l[0].shape == (48, 64)
    assert set(np.unique(l[-1])) <= set(np.unique(maps[idx[-1]]))  # no blended ids
    assert resize_max_side(maps[0], 64).dtype == np.uint16


def test_mark_video_errors():
    frames, maps = moving_scene(T=3)
    with pytest.raises(ValueError, match="3 frames but 2 label maps"):
        mark_video(frames, maps[:2])
    with pytest.raises(ValueError, match="frame"):
        mark_video(frames, [m[:50] for m in maps])
    with pytest.raises(ValueError, match="no frames"):
        mark_video([], [])


def test_registry_reused_across_calls_keeps_numbers():
    frames, maps = moving_scene(T=4)
    reg = MarkRegistry()
    mark_video(frames[:2], maps[:2], registry=reg)
    second = mark_video(frames[2:], maps[2:], registry=reg)
    assert second.registry is reg and reg.number(7) == 1 and reg.number(1) == 3
