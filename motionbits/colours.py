"""Mask outlines moved to where the colours of a body and of its surroundings part.

Flow is smooth across motion boundaries (DIS matches patches; a patch that straddles a
moving body's outline takes the body's motion), so a motion mask overhangs its body by a
few pixels on one side and falls short on another. The colours settle it: within a band
around each mask's outline, a pixel goes to the mask if its colour is more frequent on the
mask's inside than in the background just outside (local colour histograms, as GrabCut's
colour models without its graph cut).
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.boxes import grow_box, label_boxes

__all__ = ["snap_to_colours", "colour_codes", "COLOUR_BINS", "COLOUR_SMOOTH",
           "MIN_COLOUR_SAMPLES", "MIN_KEPT"]

#: Bins per RGB channel of the colour histograms (16: 4096 colours).
COLOUR_BINS = 16
#: px: side of the box filter that smooths the colour probability before it decides.
COLOUR_SMOOTH = 5
#: px: a mask whose inside (or background ring) has fewer is left as it is.
MIN_COLOUR_SAMPLES = 20
#: A mask that would keep less than this share of its pixels is left as it is.
MIN_KEPT = 0.5


def colour_codes(rgb: np.ndarray, bins: int = COLOUR_BINS) -> np.ndarray:
    """(H, W, 3) uint8 -> (H, W) int32 histogram bin of each pixel's colour."""
    q = rgb // np.uint8(256 // bins)
    return (q[..., 0].astype(np.int32) * bins + q[..., 1]) * bins + q[..., 2]


def snap_to_colours(label_map: np.ndarray, rgb: np.ndarray, band: int) -> np.ndarray:
    """Move each mask's outline, within ``band`` px of where it is, to where its colours
    end.

    For each mask: the colour histogram of its inside (the mask eroded by ``band``) and
    of the background in the ring from ``band`` to ``2 * band`` px outside it. A pixel
    within ``band`` px of the outline belongs to the mask where its colour's share of the
    inside is larger than its share of the ring (the ratio smoothed over
    ``COLOUR_SMOOTH`` px). A mask gives pixels only to the background and takes them only
    from it: where two masks meet, the motion decides. A mask is left as it is when its
    inside or ring has fewer than ``MIN_COLOUR_SAMPLES`` pixels (thinner than
    ``2 * band``, all of it is outline: its colours could not be told from its overhangs',
    and a speck would grow by the band all round), or when the colours would take more
    than ``1 - MIN_KEPT`` of it (a body with its surroundings' colours).

    Args:
        label_map: (H, W) int32 labels (0 = background).
        rgb: (H, W, 3) uint8 frame at the same size.
        band: px (0 = return ``label_map`` unchanged).

    Returns:
        (H, W) int32 label map.
    """
    if band < 1 or not label_map.any():
        return label_map
    reach = 2 * band + 2
    out = label_map.copy()
    n_bins = COLOUR_BINS ** 3
    for i, box in enumerate(label_boxes(label_map)):
        if box is None:
            continue
        rows, cols = grow_box(box, reach, label_map.shape)
        labels, code = label_map[rows, cols], colour_codes(rgb[rows, cols])
        mask = (labels == i + 1).astype(np.uint8)
        # distances (px) to the mask from outside and to the background from inside: the
        # erosion / dilations by a disk, in time linear in the box's pixels
        inward = cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_5)
        outward = cv2.distanceTransform(1 - mask, cv2.DIST_L2, cv2.DIST_MASK_5)
        inner = inward > band
        outer = outward <= band
        around = (outward > band) & (outward <= 2 * band) & (labels == 0)
        inside, outside = code[inner], code[around]
        if len(outside) < MIN_COLOUR_SAMPLES or len(inside) < MIN_COLOUR_SAMPLES:
            continue
        # each colour's share, then each pixel's (a lookup: bins are fewer than pixels)
        p_in = np.bincount(inside, minlength=n_bins) / np.float32(len(inside))
        p_out = np.bincount(outside, minlength=n_bins) / np.float32(len(outside))
        share = np.take(((p_in + 1e-4) / (p_in + p_out + 2e-4)).astype(np.float32), code)
        mine = cv2.blur(share, (COLOUR_SMOOTH, COLOUR_SMOOTH)) > 0.5
        band_px = outer & ~inner
        lost = band_px & (mask > 0) & ~mine
        if np.count_nonzero(lost) > (1 - MIN_KEPT) * np.count_nonzero(mask):
            continue  # the colours do not tell this body from its surroundings
        sub = out[rows, cols]
        sub[lost] = 0
        sub[band_px & mine & (labels == 0)] = i + 1
    return out
