"""Optical flow backends and flow utilities.

A flow backend is any callable ``flow(prev, next) -> (H, W, 2) float32`` taking two
(H, W, 3) uint8 RGB frames and returning, for each pixel of ``prev``, its displacement
(dx, dy) to ``next``. The default is OpenCV's DIS (no weights); any other model (RAFT,
MemFlow, ...) plugs in through the same signature.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Protocol

import cv2
import numpy as np

__all__ = [
    "FlowBackend",
    "DISFlow",
    "make_flow",
    "warp_nearest",
    "forward_backward_error",
    "sample_maps",
    "pixel_grid",
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


class DISFlow:
    """OpenCV Dense Inverse Search flow (Kroeger et al., ECCV 2016) on grayscale frames.

    Args:
        preset: ``"ultrafast"``, ``"fast"`` or ``"medium"``. MEDIUM is the default: the
            faster presets are too noisy for local rotation estimates.
    """

    def __init__(self, preset: str = "medium") -> None:
        if preset not in _DIS_PRESETS:
            raise ValueError(f"unknown DIS preset {preset!r}; choose one of {sorted(_DIS_PRESETS)}")
        self.preset = preset
        self._dis = cv2.DISOpticalFlow_create(_DIS_PRESETS[preset])

    def __call__(self, prev: np.ndarray, nxt: np.ndarray) -> np.ndarray:
        a = prev if prev.ndim == 2 else cv2.cvtColor(prev, cv2.COLOR_RGB2GRAY)
        b = nxt if nxt.ndim == 2 else cv2.cvtColor(nxt, cv2.COLOR_RGB2GRAY)
        return self._dis.calc(a, b, None)

    def __repr__(self) -> str:
        return f"DISFlow(preset={self.preset!r})"


def make_flow(spec: str | FlowBackend) -> FlowBackend:
    """Build a flow backend from a name (``"dis-medium"``, ``"dis-fast"``, ...) or pass one through."""
    if callable(spec):
        return spec
    name = str(spec).lower()
    if name.startswith("dis-"):
        return DISFlow(name[4:])
    raise ValueError(
        f"unknown flow backend {spec!r}: use 'dis-medium', 'dis-fast', 'dis-ultrafast' "
        "or pass a callable flow(prev, next) -> (H, W, 2) array"
    )


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


def warp_nearest(values: np.ndarray, flow_back: np.ndarray, fill: int = 0) -> np.ndarray:
    """Carry a per-pixel map from the previous frame to the current one.

    Args:
        values: (H, W) or (H, W, C) map on the previous frame (any integer or float dtype
            that OpenCV remaps: int32, float32, uint8, uint16; C <= 4).
        flow_back: (H, W, 2) float32 flow from the current frame to the previous one.
        fill: value for pixels whose source lies outside the image.

    Returns:
        map of the same shape on the current frame, ``values[p + flow_back(p)]`` (nearest
        pixel).
    """
    map_x, map_y = sample_maps(flow_back)
    return cv2.remap(
        values, map_x, map_y, interpolation=cv2.INTER_NEAREST,
        borderMode=cv2.BORDER_CONSTANT, borderValue=fill,
    )


def forward_backward_error(flow_back: np.ndarray, flow_fwd: np.ndarray) -> np.ndarray:
    """Forward-backward inconsistency of the current frame's pixels, in pixels.

    For pixel p of the current frame, q = p + flow_back(p) lands in the previous frame and
    flow_fwd(q) should bring it back: the error is |flow_back(p) + flow_fwd(q)|. Large values
    mark occlusions, disocclusions and unreliable flow.

    Args:
        flow_back: (H, W, 2) float32 flow current -> previous.
        flow_fwd: (H, W, 2) float32 flow previous -> current.

    Returns:
        (H, W) float32 error; pixels whose q leaves the image get +inf.
    """
    map_x, map_y = sample_maps(flow_back)
    fwd_at_q = cv2.remap(
        flow_fwd, map_x, map_y, interpolation=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT, borderValue=(np.inf, np.inf),
    )
    d = flow_back + fwd_at_q
    return cv2.magnitude(d[..., 0], d[..., 1])
