"""Annotators and the composite renderer: types, locality of changes, colours, errors."""

import cv2
import numpy as np
import pytest
from PIL import Image

from somprompt import (
    BoxAnnotator,
    ColorPalette,
    ContourAnnotator,
    MarkRegistry,
    MaskAnnotator,
    NumberAnnotator,
    SetOfMarkRenderer,
    contrast_ratio,
    contrasting_color,
    draw_marks,
    mark_text,
    parse_mode,
)

RNG = np.random.default_rng(0)


@pytest.fixture
def scene():
    return RNG.integers(0, 256, (120, 160, 3), dtype=np.uint8)


@pytest.fixture
def labels():
    lm = np.zeros((120, 160), np.int32)
    lm[10:60, 10:70] = 4
    yy, xx = np.mgrid[:120, :160]
    d = np.hypot(yy - 75, xx - 115)
    lm[(d < 35) & (d > 22)] = 9
    lm[100:115, 20:60] = 2
    return lm


def dilate(mask, r):
    if r <= 0:
        return mask
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    return cv2.dilate(mask.astype(np.uint8), k) > 0


ANNOTATORS = [
    MaskAnnotator(), ContourAnnotator(), BoxAnnotator(), NumberAnnotator(), SetOfMarkRenderer(mode="all"),
]


@pytest.mark.parametrize("ann", ANNOTATORS, ids=lambda a: type(a).__name__)
def test_numpy_in_numpy_out_pil_in_pil_out(ann, scene, labels):
    before = scene.copy()
    out = ann.annotate(scene, labels)
    assert isinstance(out, np.ndarray) and out.shape == scene.shape and out.dtype == np.uint8
    assert np.array_equal(scene, before), "the input array must not be modified"
    assert not np.array_equal(out, scene), "something must be drawn"
    pil = ann.annotate(Image.fromarray(scene), labels)
    assert isinstance(pil, Image.Image) and pil.size == (160, 120) and pil.mode == "RGB"
    assert np.array_equal(np.asarray(pil), out)


def test_mask_mode_changes_only_mask_pixels(scene, labels):
    out = draw_marks(scene, labels, mode="mask")
    outside = labels == 0
    assert np.array_equal(out[outside], scene[outside])
    assert (out[~outside] != scene[~outside]).any(axis=1).mean() > 0.9


@pytest.mark.parametrize("thickness", [1, 2, 3])
def test_contour_stays_within_thickness_of_masks(scene, labels, thickness):
    out = draw_marks(scene, labels, mode="mask+contour", thickness=thickness)
    near = dilate(labels > 0, thickness // 2 + 1)
    assert np.array_equal(out[~near], scene[~near])


def test_all_modes_change_only_masks_and_label_boxes(scene, labels):
    renderer = SetOfMarkRenderer(mode="all", thickness=2)
    rendered = renderer.render(scene, labels)
    assert not any(p.leader for p in rendered.placements.values())
    allowed = dilate(labels > 0, 2)
    for p in rendered.placements.values():
        x0, y0, x1, y1 = p.box
        allowed[y0:y1, x0:x1] = True
    for reg in rendered.regions:  # the bounding-box frames
        x0, y0, x1, y1 = reg.bbox
        allowed[y0:y1, x0:x1] = True
    assert np.array_equal(rendered.image[~allowed], scene[~allowed])
    # and without the box part, the masks' neighbourhood and label boxes suffice
    rendered = SetOfMarkRenderer(mode="mask+contour+number", thickness=2).render(scene, labels)
    allowed = dilate(labels > 0, 2)
    for p in rendered.placements.values():
        x0, y0, x1, y1 = p.box
        allowed[y0:y1, x0:x1] = True
    assert np.array_equal(rendered.image[~allowed], scene[~allowed])


@pytest.mark.parametrize(
    "mode, expected",
    [
        ("mask", ("mask",)),
        ("number+contour", ("contour", "number")),
        ("mask, box,mark", ("mask", "box", "number")),
        (["label", "bbox"], ("box", "number")),
        ("all", ("mask", "contour", "box", "number")),
    ],
)
def test_parse_mode(mode, expected):
    assert parse_mode(mode) == expected


@pytest.mark.parametrize("bad", ["", "mask+glow", ["mask", 3]])
def test_parse_mode_rejects_bad_modes(bad):
    with pytest.raises((ValueError, TypeError), match="mode|part"):
        parse_mode(bad)


def test_every_mode_combination_renders(scene, labels):
    parts = ["mask", "contour", "box", "number"]
    outs = set()
    for k in range(1, 16):
        mode = [p for j, p in enumerate(parts) if k >> j & 1]
        out = draw_marks(scene, labels, mode=mode)
        outs.add(out.tobytes())
    assert len(outs) == 15  # every combination draws something different


def test_number_is_drawn_inside_mask_on_ring(scene):
    lm = np.zeros((120, 160), np.int32)
    yy, xx = np.mgrid[:120, :160]
    d = np.hypot(yy - 60, xx - 80)
    lm[(d < 50) & (d > 30)] = 1
    ann = NumberAnnotator(text_scale=0.4)
    pl = ann.place(lm)[1]
    out = ann.annotate(scene, lm)
    x0, y0, x1, y1 = pl.box
    changed = np.nonzero((out != scene).any(axis=2))
    assert changed[0].min() >= y0 and changed[0].max() < y1  # only the box was drawn
    cy, cx = (y0 + y1) // 2, (x0 + x1) // 2
    assert lm[cy, cx] == 1  # the box centre (where the text is) is on the ring


def test_one_pixel_mask_gets_a_visible_mark(scene):
    lm = np.zeros((120, 160), np.int32)
    lm[50, 70] = 1
    out = draw_marks(scene, lm, mode="mask+contour+number")
    changed = (out != scene).any(axis=2)
    assert changed.sum() >= 100  # a whole label box, not one pixel
    ys, xs = np.nonzero(changed)
    assert ys.min() <= 50 <= ys.max() and xs.min() <= 70 <= xs.max()


def test_colours_follow_registry_numbers_not_ids():
    frame = np.zeros((40, 40, 3), np.uint8)
    reg = MarkRegistry()
    a = np.zeros((40, 40), np.int32)
    a[5:15, 5:15] = 50
    b = a.copy()
    b[25:35, 25:35] = 2  # a smaller id appears later: it must not steal colour 1
    mask = MaskAnnotator(opacity=1.0)
    out_a = mask.annotate(frame, a, reg)
    out_b = mask.annotate(frame, b, reg)
    pal = ColorPalette.default()
    assert tuple(out_a[10, 10]) == tuple(out_b[10, 10]) == pal.by_number(1)
    assert tuple(out_b[30, 30]) == pal.by_number(2)
    assert reg.number(50) == 1 and reg.number(2) == 2


def test_label_text_contrasts_with_label_fill():
    pal = ColorPalette.default()
    for n in range(1, len(pal) + 1):
        c = pal.by_number(n)
        best = max(contrast_ratio((0, 0, 0), c), contrast_ratio((255, 255, 255), c))
        assert contrast_ratio(contrasting_color(c), c) == best
        assert best >= 4.5  # WCAG AA for every palette colour
    assert contrasting_color((255, 225, 25)) == (0, 0, 0)  # yellow -> black text
    assert contrasting_color((0, 0, 117)) == (255, 255, 255)  # navy -> white text


@pytest.mark.parametrize("fill, text", [((255, 255, 0), (0, 0, 0)), ((0, 0, 128), (255, 255, 255))])
def test_rendered_text_pixels_use_contrasting_colour(fill, text):
    frame = np.full((80, 80, 3), 128, np.uint8)
    lm = np.zeros((80, 80), np.int32)
    lm[10:70, 10:70] = 1
    ann = NumberAnnotator(palette=ColorPalette((fill,)), text_scale=0.8)
    out = ann.annotate(frame, lm)
    x0, y0, x1, y1 = ann.place(lm)[1].box
    box = out[y0 + 1:y1 - 1, x0 + 1:x1 - 1].reshape(-1, 3).astype(int)
    # the pixels farthest from the fill are (close to) the text colour
    far = box[np.argmax(np.abs(box - fill).sum(1))]
    assert np.abs(far - text).max() < 40


def test_label_border_contrasts_with_the_scene_under_it():
    lm = np.zeros((80, 80), np.int32)
    lm[10:70, 10:70] = 1
    ann = NumberAnnotator(text_scale=0.6)
    x0, y0, x1, y1 = ann.place(lm)[1].box
    dark = ann.annotate(np.zeros((80, 80, 3), np.uint8), lm)
    light = ann.annotate(np.full((80, 80, 3), 255, np.uint8), lm)
    assert tuple(dark[y0, x0 + 3]) == (255, 255, 255)
    assert tuple(light[y0, x0 + 3]) == (0, 0, 0)


def test_letter_style_draws_letters():
    lm = np.zeros((60, 60), np.int32)
    lm[5:55, 5:55] = 3
    reg = MarkRegistry("letter")
    reg.update(lm)
    assert reg.text(3) == "a"
    a = draw_marks(np.zeros((60, 60, 3), np.uint8), lm, mode="number", registry=reg)
    one = draw_marks(np.zeros((60, 60, 3), np.uint8), lm, mode="number", style="number")
    assert not np.array_equal(a, one)
    assert [mark_text(n, "letter") for n in (1, 2, 26, 27, 52, 53, 702, 703)] == [
        "a", "b", "z", "aa", "az", "ba", "zz", "aaa"]


def test_empty_label_map_draws_nothing(scene):
    out = draw_marks(scene, np.zeros((120, 160), np.int32), mode="all")
    assert np.array_equal(out, scene)


def test_greyscale_and_rgba_frames_are_read_as_everywhere_else(scene, labels):
    """One frame policy for the three packages (motionbits.as_rgb_array)."""
    grey = scene[..., 1]
    assert np.array_equal(draw_marks(grey, labels), draw_marks(np.repeat(grey[..., None], 3, 2), labels))
    rgba = np.concatenate([scene, np.full(scene.shape[:2] + (1,), 7, np.uint8)], axis=2)
    assert np.array_equal(draw_marks(rgba, labels), draw_marks(scene, labels))


def test_uint16_and_bool_label_maps_are_accepted(scene, labels):
    a = draw_marks(scene, labels.astype(np.uint16))
    b = draw_marks(scene, labels)
    assert np.array_equal(a, b)
    draw_marks(scene, labels > 0)


@pytest.mark.parametrize(
    "frame, lm, exc, words",
    [
        (np.zeros((20, 20, 3), np.float32), np.zeros((20, 20), int), TypeError, "uint8"),
        (np.zeros((20, 20, 2), np.uint8), np.zeros((20, 20), int), ValueError, "RGBA"),
        ("frame.png", np.zeros((20, 20), int), TypeError, "PIL"),
        (np.zeros((20, 20, 3), np.uint8), np.zeros((20, 20), np.float32), TypeError, "integer"),
        (np.zeros((20, 20, 3), np.uint8), np.zeros((20, 20, 2), int), ValueError, "label map"),
        (np.zeros((20, 20, 3), np.uint8), -np.ones((20, 20), int), ValueError, "negative"),
        (np.zeros((20, 20, 3), np.uint8), np.zeros((10, 20), int), ValueError, "nearest"),
        (np.zeros((20, 20, 3), np.uint8), [[0, 1]], TypeError, "numpy"),
    ],
)
def test_bad_inputs_fail_clearly(frame, lm, exc, words):
    for ann in (SetOfMarkRenderer(mode="all"), MaskAnnotator(), NumberAnnotator()):
        with pytest.raises(exc, match=words):
            ann.annotate(frame, lm)


@pytest.mark.parametrize("kwargs", [{"opacity": 1.5}, {"thickness": 0}, {"text_scale": 0}])
def test_bad_style_arguments_fail_clearly(kwargs):
    with pytest.raises(ValueError):
        SetOfMarkRenderer(**kwargs)
