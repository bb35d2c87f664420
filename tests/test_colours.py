"""Mask outlines moved to where a body's colours end (motionbits.colours)."""

import numpy as np

from motionbits.colours import colour_codes, snap_to_colours


def _speckled(shape, base, spread, rng):
    """(h, w, 3) uint8: ``base`` colour with per-pixel noise of +-``spread`` levels."""
    noise = rng.integers(-spread, spread + 1, shape + (3,))
    return np.clip(np.asarray(base) + noise, 0, 255).astype(np.uint8)


def test_an_overhang_is_given_back_and_a_shortfall_taken():
    """A red speckled body on a green speckled table, its motion mask shifted 5 px to the
    right (a halo on one side, a missing strip on the other): the colours put the outline
    back on the body."""
    rng = np.random.default_rng(0)
    rgb = _speckled((200, 260), (60, 150, 70), 25, rng)
    rgb[60:140, 80:180] = _speckled((80, 100), (190, 50, 40), 25, rng)
    body = np.zeros((200, 260), bool)
    body[60:140, 80:180] = True
    labels = np.zeros((200, 260), np.int32)
    labels[60:140, 85:185] = 1
    out = snap_to_colours(labels, rgb, band=8)
    iou = lambda m: (m & body).sum() / (m | body).sum()  # noqa: E731
    assert iou(labels == 1) < 0.91
    assert iou(out == 1) > 0.98


def test_masks_meet_where_the_motion_says_and_thin_masks_stay():
    """Where two masks meet neither takes the other's pixels, whatever the colours; a mask
    thinner than twice the band (all outline) is left as it is; band 0 is off."""
    rng = np.random.default_rng(1)
    rgb = _speckled((160, 200), (120, 120, 120), 20, rng)
    rgb[40:120, 40:100] = _speckled((80, 60), (200, 200, 40), 20, rng)  # one yellow body...
    rgb[40:120, 100:160] = _speckled((80, 60), (200, 200, 40), 20, rng)  # ...and another
    labels = np.zeros((160, 200), np.int32)
    labels[40:120, 40:110] = 1  # takes 10 px of the second body
    labels[40:120, 110:160] = 2
    labels[5:15, 10:190] = 3  # a 10 px strip: all outline at band 8
    out = snap_to_colours(labels, rgb, band=8)
    assert (out[labels == 2] != 1).all() and (out[labels == 1] != 2).all()
    assert (out[40:120, 100:110] == 1).all()
    assert (out == 3).sum() == (labels == 3).sum() and (out[labels == 3] == 3).all()
    assert snap_to_colours(labels, rgb, band=0) is labels
    nothing = np.zeros_like(labels)
    assert snap_to_colours(nothing, rgb, band=8) is nothing


def test_colour_codes_are_histogram_bins():
    rgb = np.array([[[0, 0, 0], [255, 255, 255], [16, 32, 48]]], np.uint8)
    assert colour_codes(rgb, 16).tolist() == [[0, 16 ** 3 - 1, (1 * 16 + 2) * 16 + 3]]


def test_a_mask_the_colours_would_mostly_remove_is_left_as_it_is():
    """A 30 px mask whose outer 8 px have the colours of the table around it (a white
    sleeve on a white shirt): the colours would keep only its 14 px core, so they are not
    trusted there; a mask that loses less keeps the change."""
    rng = np.random.default_rng(2)
    rgb = _speckled((120, 200), (200, 200, 200), 15, rng)
    rgb[38:52, 38:52] = _speckled((14, 14), (90, 60, 160), 15, rng)  # the core's colours
    rgb[30:60, 130:160] = _speckled((30, 30), (90, 60, 160), 15, rng)  # a whole body
    labels = np.zeros((120, 200), np.int32)
    labels[30:60, 30:60] = 1  # most of it table-coloured: left as it is
    labels[26:64, 126:164] = 2  # a 4 px halo round a body of its own colours: trimmed
    out = snap_to_colours(labels, rgb, band=8)
    assert (out == 1).sum() == (labels == 1).sum() and (out[labels == 1] == 1).all()
    assert (out == 2).sum() < (labels == 2).sum()
    assert (out[30:60, 130:160] == 2).mean() > 0.95
