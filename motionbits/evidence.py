"""Photometric evidence: what the images say about a flow field (ours; the paper trusts its flow).

Flow is smooth across motion boundaries and is interpolated over textureless regions, so
it claims motion where the images show none (a white table next to a moving hand) and
carries labels onto pixels that were hidden a frame ago (the table a hand has just
uncovered). Both are caught by comparing the current frame with the previous frame pulled
back along the flow:

- :func:`appearance_consistent`: a pixel's carried label is kept only where the flow's
  correspondence explains its appearance (a disoccluded pixel has no correspondence, so
  its residual is large and the label it would inherit from the occluder is dropped);
- :func:`motion_gain`: grey levels by which the flow explains a neighbourhood better than
  "nothing moved" (the birth test of a new MotionBit);
- :func:`forgive_misalignment`: a residual less what a small misregistration explains
  (the birth test under a moving camera, whose static-world model is not exact);
- :func:`photometric_residual`: how well one parametric motion explains a box of the image
  (pixel masks, the merging test of touching MotionBits).
"""

from __future__ import annotations

import cv2
import numpy as np

from motionbits.boxes import grow_box
from motionbits.flow import sample_maps

__all__ = ["pull_back", "gradient_magnitude", "appearance_consistent", "motion_gain",
           "forgive_misalignment", "photometric_residual", "static_residual"]

#: Grey levels added before taking logs of intensities (dark pixels have noisy ratios).
LOG_OFFSET = 8.0
#: The brightness gain of :func:`static_residual` is estimated at this fraction of the
#: resolution (it is smooth over several grid cells).
GAIN_SCALE = 4


def pull_back(prev_gray: np.ndarray, flow_back: np.ndarray,
              maps: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """(H, W) float32 previous grey frame sampled where the backward flow points:
    ``out(p) = prev(p + F(p))`` (bilinear, border replicated); ``maps``:
    ``motionbits.flow.sample_maps(flow_back)`` if already computed."""
    map_x, map_y = sample_maps(flow_back) if maps is None else maps
    return cv2.remap(prev_gray, map_x, map_y, interpolation=cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)


def gradient_magnitude(gray: np.ndarray, window: int = 5) -> np.ndarray:
    """(H, W) float32 grey levels per px of image gradient (Sobel), mean over a ``window``
    square: how much a sub-pixel shift changes the image, i.e. where flow is measured
    rather than interpolated."""
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
    return cv2.blur(cv2.magnitude(gx, gy), (window, window))


def appearance_consistent(cur_gray: np.ndarray, pulled: np.ndarray, gradient: np.ndarray, *,
                          tolerance: float, gradient_gain: float, window: int = 5) -> np.ndarray:
    """(H, W) bool: where the flow's correspondence explains the pixel's appearance.

    The residual ``|I_t - pulled|`` (mean over a ``window`` square) is compared with
    ``tolerance + gradient_gain * |grad I_t|`` (grey levels): on texture, a sub-pixel flow
    error alone leaves a residual proportional to the image gradient.

    Args:
        cur_gray: (H, W) float32 current grey frame.
        pulled: (H, W) float32 previous grey frame pulled back by the flow (:func:`pull_back`).
        gradient: (H, W) float32 :func:`gradient_magnitude` of ``cur_gray``.
        tolerance: grey levels allowed on flat regions.
        gradient_gain: px of flow error tolerated on texture.
    """
    resid = cv2.blur(np.abs(cur_gray - pulled), (window, window))
    return resid < tolerance + gradient_gain * gradient


def static_residual(cur_gray: np.ndarray, prev_gray: np.ndarray, sigma: float) -> np.ndarray:
    """(H, W) float32 grey levels by which "nothing moved, only the light changed" misses
    each pixel: the smaller of ``|I_t - I_t-1|`` and ``|I_t - g I_t-1|``, with ``log g``
    the Gaussian (``sigma`` px) mean of the per-pixel log ratio ``log I_t - log I_t-1``.

    A moving shadow, a flicker or an exposure change darkens or brightens the static
    texture under it by a smooth factor, so the second residual stays small there; a
    moving body replaces the texture under it, which no smooth gain explains.

    Args:
        cur_gray, prev_gray: (H, W) float32 grey frames in [0, 255] (``prev_gray``
            camera-stabilised).
        sigma: px, smoothness of the gain field.
    """
    # the gain field is smooth: it is estimated at 1/GAIN_SCALE of the resolution
    h, w = cur_gray.shape
    log_ratio = cv2.log(cur_gray + LOG_OFFSET) - cv2.log(prev_gray + LOG_OFFSET)
    small = cv2.resize(log_ratio, (max(w // GAIN_SCALE, 1), max(h // GAIN_SCALE, 1)),
                       interpolation=cv2.INTER_AREA)
    small = cv2.GaussianBlur(small, (0, 0), max(sigma / GAIN_SCALE, 0.5))
    gain = cv2.exp(cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR))
    relit = cv2.absdiff(cur_gray, cv2.multiply(prev_gray, gain))
    return np.minimum(np.abs(cur_gray - prev_gray), relit)


def motion_gain(still: np.ndarray, cur_gray: np.ndarray, pulled: np.ndarray,
                window: int) -> np.ndarray:
    """(H, W) float32 grey levels by which the flow explains each pixel's ``window``
    neighbourhood better than "nothing moved": mean ``still`` - mean |I_t - pulled|, with
    ``still`` the per-pixel residual of "nothing moved" (:func:`static_residual`).

    Motion is only observable where the image changes: on textureless regions the flow is
    interpolated from nearby edges -- often from a moving body next to them -- and both
    hypotheses explain the pixels equally well, so the gain is ~0. Uniform interiors of
    moving bodies get ~0 too, so a birth test averages it over a whole cluster.
    """
    return cv2.blur(still - np.abs(cur_gray - pulled), (window, window))


def forgive_misalignment(residual: np.ndarray, gradient: np.ndarray, px: float
                         ) -> np.ndarray:
    """(H, W) float32 ``max(residual - px * gradient, 0)``: the grey-level residual of a
    registration less what a misalignment of up to ``px`` pixels explains on an image whose
    gradient is ``gradient`` (grey levels per px, :func:`gradient_magnitude`).

    Under a moving camera "nothing moved" compares the frame with the previous one warped
    by the static world's model (homography + parallax), which is good to a fraction of a
    pixel at best: on texture that alone leaves residuals of tens of grey levels, which a
    slightly wrong flow then "explains" better -- a MotionBit born on the static world.
    """
    return np.maximum(residual - np.float32(px) * gradient, 0.0)


def photometric_residual(cur: np.ndarray, prev: np.ndarray, motion: np.ndarray,
                         box: tuple[slice, slice], window: int = 3) -> np.ndarray:
    """Mean absolute grey-level difference between ``cur`` and ``prev`` pulled back by the
    (2, 3) backward map ``motion`` (``out(p) = prev(motion [p; 1])``), over a ``window``
    square, on the image box ``box``; the box is grown by the window radius (clipped to the
    image) so that the result is the whole-image one, cropped."""
    rows, cols = grow_box(box, window // 2, cur.shape)
    y0, y1, x0, x1 = rows.start, rows.stop, cols.start, cols.stop
    m = motion.astype(np.float64).copy()
    m[:, 2] += m[:, 0] * x0 + m[:, 1] * y0  # output origin moved to (x0, y0)
    warped = cv2.warpAffine(prev, m.astype(np.float32), (x1 - x0, y1 - y0),
                            flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                            borderMode=cv2.BORDER_REPLICATE)
    cost = cv2.blur(np.abs(cur[y0:y1, x0:x1] - warped), (window, window))
    return cost[box[0].start - y0:box[0].stop - y0, box[1].start - x0:box[1].stop - x0]
