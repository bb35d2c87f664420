"""Optical flow backends and flow utilities.

A flow backend is any callable ``flow(prev, next) -> (H, W, 2) float32`` taking two
(H, W, 3) uint8 RGB frames and returning, for each pixel of ``prev``, its displacement
(dx, dy) to ``next``. The default is OpenCV's DIS (no weights); RAFT from a local
weights file is built in (``"raft:PATH"``, motionbits/flow_raft.py), and any other model
(MemFlow, ...) plugs in through the same signature.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Protocol

import cv2
import numpy as np

__all__ = [
    "FlowBackend",
    "DISFlow",
    "normalize_contrast",
    "make_flow",
    "warp_nearest",
    "forward_backward_error",
    "sample_maps",
    "nearest_maps",
    "pixel_grid",
    "check_flow",
]


class FlowBackend(Protocol):
    """Dense optical flow between two RGB frames of the same size."""

    def __call__(self, prev: np.ndarray, nxt: np.ndarray) -> np.ndarray:
        """Return the (H, W, 2) float32 flow from ``prev`` to ``nxt`` in pixels."""
        ...


_DIS_PRESETS = {
    "ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
    "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
    "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
}


#: px: Gaussian sigma of the local mean and standard deviation that normalise the frames.
NORMALIZE_SIGMA = 3.0
#: grey levels added to the local standard deviation (keeps flat regions flat, not noise).
NORMALIZE_EPS = 4.0
#: The coarse DIS runs on frames downsampled by this factor.
COARSE_FACTOR = 2
#: Frames with a side under this many px skip the coarse stage.
COARSE_MIN_SIDE = 64


def normalize_contrast(gray: np.ndarray) -> np.ndarray:
    """(H, W) uint8 grey frame -> (H, W) uint8 locally contrast-normalised frame: each
    pixel's grey level minus the local mean, over the local standard deviation (Gaussian
    windows of ``NORMALIZE_SIGMA`` px; ``NORMALIZE_EPS`` added), mapped around 128.

    A shadow or a change of light multiplies the texture under it by a smooth factor: the
    normalised frame does not change, so the flow on it does not follow the shadow.
    """
    g = gray.astype(np.float32)
    mean = cv2.GaussianBlur(g, (0, 0), NORMALIZE_SIGMA)
    var = cv2.GaussianBlur(g * g, (0, 0), NORMALIZE_SIGMA) - mean * mean
    z = (g - mean) / (cv2.sqrt(np.maximum(var, 0)) + NORMALIZE_EPS)
    return np.clip(128 + 40 * z, 0, 255).astype(np.uint8)


class DISFlow:
    """OpenCV Dense Inverse Search flow (Kroeger et al., ECCV 2016), robust to light.

    Two stages: DIS on the grey frames downsampled by ``COARSE_FACTOR`` finds the large
    displacements; DIS on the full-resolution frames after :func:`normalize_contrast`
    refines it from there. DIS on the grey frames alone follows moving cast shadows
    across static texture (7.7% of the static pixels of the pick-and-place track moved
    > 0.6 px, 5.7% now; mean error 1.07 -> 0.62 px); on the normalised frames alone it
    loses displacements above ~15 px (their coarse pyramid levels are nearly flat).

    Args:
        preset: ``"ultrafast"``, ``"fast"`` or ``"medium"``. MEDIUM is the default: the
            faster presets are too noisy for local rotation estimates.
        normalize: False: one DIS on the grey frames (the plain OpenCV flow).
    """

    def __init__(self, preset: str = "medium", normalize: bool = True) -> None:
        if preset not in _DIS_PRESETS:
            raise ValueError(f"unknown DIS preset {preset!r}; choose one of {sorted(_DIS_PRESETS)}")
        self.preset, self.normalize = preset, normalize
        self._dis = cv2.DISOpticalFlow_create(_DIS_PRESETS[preset])
        self._coarse = cv2.DISOpticalFlow_create(_DIS_PRESETS[preset])
        self._inputs: list[tuple[np.ndarray, tuple[np.ndarray, ...]]] = []  # last frames

    def _prepare(self, frame: np.ndarray) -> tuple[np.ndarray, ...]:
        """Grey, normalised and downsampled grey of a frame; the last three frames are
        remembered (a stream passes each frame to several calls)."""
        gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
        for seen, prepared in self._inputs:
            if seen is frame and np.array_equal(prepared[0], gray):  # not changed in place
                return prepared
        h, w = gray.shape
        small = (cv2.resize(gray, (w // COARSE_FACTOR, h // COARSE_FACTOR),
                            interpolation=cv2.INTER_AREA)
                 if min(h, w) >= COARSE_MIN_SIDE else None)
        prepared = (gray if gray is not frame else gray.copy(), normalize_contrast(gray), small)
        self._inputs = [(frame, prepared), *self._inputs[:2]]
        return prepared

    def __call__(self, prev: np.ndarray, nxt: np.ndarray) -> np.ndarray:
        if not self.normalize:
            a = prev if prev.ndim == 2 else cv2.cvtColor(prev, cv2.COLOR_RGB2GRAY)
            b = nxt if nxt.ndim == 2 else cv2.cvtColor(nxt, cv2.COLOR_RGB2GRAY)
            return self._dis.calc(a, b, None)
        (ga, na, sa), (gb, nb, sb) = self._prepare(prev), self._prepare(nxt)
        init = None
        if sa is not None:
            h, w = ga.shape
            init = cv2.resize(self._coarse.calc(sa, sb, None), (w, h),
                              interpolation=cv2.INTER_LINEAR) * COARSE_FACTOR
        return self._dis.calc(na, nb, init)  # a same-size flow is DIS's initial flow

    def __repr__(self) -> str:
        return f"DISFlow(preset={self.preset!r}, normalize={self.normalize})"


def make_flow(spec: str | FlowBackend) -> FlowBackend:
    """Build a flow backend from a name or pass a callable through.

    Names: ``"dis-medium"``, ``"dis-fast"``, ``"dis-ultrafast"`` (OpenCV DIS, no weights);
    ``"raft:PATH"``: torchvision's RAFT from a local weights file
    (:class:`motionbits.flow_raft.RAFTFlow`; needs torch and torchvision, imported only then).
    """
    if callable(spec):
        return spec
    name = str(spec).lower()
    if name.startswith("dis-"):
        return DISFlow(name[4:])
    if name.startswith("raft:"):
        from motionbits.flow_raft import RAFTFlow

        return RAFTFlow.from_spec(str(spec))
    raise ValueError(
        f"unknown flow backend {spec!r}: use 'dis-medium', 'dis-fast', 'dis-ultrafast', "
        "'raft:PATH' (RAFT weights file) or pass a callable flow(prev, next) -> (H, W, 2) array"
    )


def check_flow(flow: object, shape: tuple[int, int], backend: object) -> np.ndarray:
    """Validate what a flow backend returned for two frames of size ``shape`` = (H, W).

    Returns:
        the flow as an (H, W, 2) float32 array.

    Raises:
        TypeError / ValueError: not an array, wrong shape, or NaN / infinite values; the
            message names the backend.
    """
    name = getattr(backend, "__name__", None) or repr(backend)
    if not isinstance(flow, np.ndarray):
        raise TypeError(f"flow backend {name} returned {type(flow).__name__}, expected an "
                        f"(H, W, 2) = {(*shape, 2)} numpy array")
    if flow.shape != (*shape, 2):
        raise ValueError(f"flow backend {name} returned shape {flow.shape} for frames of "
                         f"{shape[1]}x{shape[0]}, expected (H, W, 2) = {(*shape, 2)}")
    if not np.issubdtype(flow.dtype, np.number) or np.issubdtype(flow.dtype, np.complexfloating):
        raise TypeError(f"flow backend {name} returned dtype {flow.dtype}, expected float32")
    flow = np.ascontiguousarray(flow, dtype=np.float32)
    if not np.isfinite(flow).all():
        raise ValueError(f"flow backend {name} returned NaN or infinite values "
                         f"({int((~np.isfinite(flow)).sum())} of {flow.size})")
    return flow


@lru_cache(maxsize=4)
def pixel_grid(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) float32 x and y coordinates of every pixel (cached, read-only)."""
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    xs.flags.writeable = ys.flags.writeable = False
    return xs, ys


def sample_maps(flow: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cv2.remap maps (x + flow_x, y + flow_y) of an (H, W, 2) flow: two (H, W) float32."""
    xs, ys = pixel_grid(*flow.shape[:2])
    return xs + flow[..., 0], ys + flow[..., 1]


def nearest_maps(map_x: np.ndarray, map_y: np.ndarray) -> tuple[np.ndarray, None]:
    """:func:`sample_maps`' (H, W) float32 maps as cv2.remap reads them for the nearest
    pixel: one (H, W, 2) int16 map of rounded (x, y) and None. :func:`warp_nearest` with
    them gives the same result as with the float maps (cv2.remap converts those the same
    way on each call), without converting them again for every map carried."""
    return cv2.convertMaps(map_x, map_y, cv2.CV_16SC2, nninterpolation=True)


def warp_nearest(values: np.ndarray, flow_back: np.ndarray, fill: int = 0,
                 maps: tuple[np.ndarray, np.ndarray | None] | None = None) -> np.ndarray:
    """Carry a per-pixel map from the previous frame to the current one.

    Args:
        values: (H, W) or (H, W, C) map on the previous frame (any integer or float dtype
            that OpenCV remaps: int32, float32, uint8, uint16; C <= 4).
        flow_back: (H, W, 2) float32 flow from the current frame to the previous one.
        fill: value for pixels whose source lies outside the image.
        maps: ``sample_maps(flow_back)`` or :func:`nearest_maps` of it, if already computed.

    Returns:
        map of the same shape on the current frame, ``values[p + flow_back(p)]`` (nearest
        pixel).
    """
    map_x, map_y = sample_maps(flow_back) if maps is None else maps
    return cv2.remap(
        values, map_x, map_y, interpolation=cv2.INTER_NEAREST,
        borderMode=cv2.BORDER_CONSTANT, borderValue=fill,
    )


def forward_backward_error(flow_back: np.ndarray, flow_fwd: np.ndarray,
                           maps: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Forward-backward inconsistency of the current frame's pixels, in pixels.

    For pixel p of the current frame, q = p + flow_back(p) lands in the previous frame and
    flow_fwd(q) should bring it back: the error is |flow_back(p) + flow_fwd(q)|. Large values
    mark occlusions, disocclusions and unreliable flow.

    Args:
        flow_back: (H, W, 2) float32 flow current -> previous.
        flow_fwd: (H, W, 2) float32 flow previous -> current.
        maps: ``sample_maps(flow_back)`` if already computed.

    Returns:
        (H, W) float32 error; pixels whose q leaves the image get +inf.
    """
    map_x, map_y = sample_maps(flow_back) if maps is None else maps
    fwd_at_q = cv2.remap(
        flow_fwd, map_x, map_y, interpolation=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT, borderValue=(np.inf, np.inf),
    )
    d = flow_back + fwd_at_q
    return cv2.magnitude(d[..., 0], d[..., 1])
