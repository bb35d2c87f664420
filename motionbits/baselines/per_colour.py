"""Per-colour segmentation: what an appearance-only segmenter does to glued objects.

A stand-in for the semantic / promptless segmenters of the paper's Table 3 (SAM splits a
glued composite into its differently coloured parts): the last frame is smoothed,
neighbouring pixels of similar colour are joined, and every connected region that does
not touch the image border (table, floor, walls) and is neither tiny nor huge is one
object. Motion is ignored: only the last frame is used.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["PerColourSegmenter"]


class PerColourSegmenter:
    """Connected regions of similar colour in the last frame.

    Args:
        max_delta: largest colour difference between 4-neighbours of one region, in CIE
            Lab units with lightness weighted by ``lightness_weight`` (so the lit top and
            the shaded side of one block stay together).
        lightness_weight: weight of L* in the colour difference.
        smooth: ``(spatial radius, colour radius)`` of OpenCV's mean-shift filtering,
            which flattens texture before the regions are grown.
        min_area: regions with fewer pixels are dropped.
        max_area_fraction: regions larger than this fraction of the image are dropped
            (background).
    """

    def __init__(self, max_delta: float = 6.0, lightness_weight: float = 0.35,
                 smooth: tuple[int, int] = (6, 16), min_area: int = 60,
                 max_area_fraction: float = 0.15) -> None:
        if max_delta <= 0 or min_area < 1 or not 0 < max_area_fraction <= 1:
            raise ValueError("max_delta must be > 0, min_area >= 1, 0 < max_area_fraction <= 1")
        self.max_delta, self.lightness_weight = float(max_delta), float(lightness_weight)
        self.smooth, self.min_area, self.max_area_fraction = smooth, int(min_area), float(max_area_fraction)

    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        """(H, W) int32 labels of the last of ``frames`` ((H, W, 3) uint8 RGB each)."""
        if not len(frames):
            raise ValueError("per-colour segmentation needs at least one frame")
        rgb = np.ascontiguousarray(frames[-1][..., :3], dtype=np.uint8)
        h, w = rgb.shape[:2]
        flat = cv2.pyrMeanShiftFiltering(rgb, self.smooth[0], self.smooth[1])
        lab = cv2.cvtColor(flat.astype(np.float32) / 255.0, cv2.COLOR_RGB2LAB)
        lab[..., 0] *= self.lightness_weight
        idx = np.arange(h * w).reshape(h, w)
        rows, cols = [], []
        for a, b, da, db in ((idx[:, :-1], idx[:, 1:], lab[:, :-1], lab[:, 1:]),
                             (idx[:-1], idx[1:], lab[:-1], lab[1:])):
            ok = np.linalg.norm(da - db, axis=-1) < self.max_delta
            rows.append(a[ok])
            cols.append(b[ok])
        r, c = np.concatenate(rows), np.concatenate(cols)
        graph = coo_matrix((np.ones(r.size, np.int8), (r, c)), shape=(h * w, h * w))
        _, comp = connected_components(graph, directed=False)
        comp = comp.reshape(h, w)
        border = np.unique(np.concatenate([comp[0], comp[-1], comp[:, 0], comp[:, -1]]))
        ids, counts = np.unique(comp, return_counts=True)
        keep = (counts >= self.min_area) & (counts <= self.max_area_fraction * h * w)
        keep &= ~np.isin(ids, border)
        lut = np.zeros(ids.max() + 1, np.int32)
        lut[ids[keep]] = np.arange(1, int(keep.sum()) + 1, dtype=np.int32)
        return lut[comp]
