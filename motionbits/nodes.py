"""The node grid (paper Sec. 5.1, SampleNodes): positions, neighbours, flow samples."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np
from scipy.spatial import cKDTree

from motionbits.boxes import at_border

__all__ = ["NodeGrid", "binary_fill_holes", "sample_bilinear"]


@dataclass(frozen=True)
class NodeGrid:
    """A ``rows x cols`` grid of nodes over an ``height x width`` image, with k-NN lists.

    Attributes:
        points: (n, 2) float32 (x, y) node positions, row-major, cell centres.
        neighbors: (n, k) int32 indices of each node's k nearest grid nodes (itself
            excluded; ties broken by index, so the lists are deterministic).
        rows, cols, height, width: grid and image sizes.
    """

    points: np.ndarray
    neighbors: np.ndarray
    rows: int
    cols: int
    height: int
    width: int

    @classmethod
    def build(cls, height: int, width: int, side: int, k: int) -> "NodeGrid":
        """A ``side x side`` grid (the paper's sqrt(n) x sqrt(n)) over an image."""
        rows = cols = side
        xs = (np.arange(cols, dtype=np.float32) + 0.5) * (width / cols)
        ys = (np.arange(rows, dtype=np.float32) + 0.5) * (height / rows)
        gx, gy = np.meshgrid(xs, ys)
        points = np.stack([gx.ravel(), gy.ravel()], axis=1).astype(np.float32)
        _, idx = cKDTree(points).query(points, k=k + 1)
        # the query returns each node first (distance 0); drop it
        neighbors = np.ascontiguousarray(idx[:, 1:], dtype=np.int32)
        return cls(points, neighbors, rows, cols, height, width)

    @property
    def n(self) -> int:
        return self.points.shape[0]

    @property
    def cell(self) -> tuple[float, float]:
        """(cell width, cell height) in pixels."""
        return self.width / self.cols, self.height / self.rows

    def nearest_node(self, xy: np.ndarray) -> np.ndarray:
        """(m,) int index of the grid node nearest to each (m, 2) (x, y) position (clamped)."""
        cw, ch = self.cell
        c = np.clip(np.floor(xy[:, 0] / cw), 0, self.cols - 1).astype(np.int64)
        r = np.clip(np.floor(xy[:, 1] / ch), 0, self.rows - 1).astype(np.int64)
        return r * self.cols + c

    @cached_property
    def _slot_table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """Grid row and column of every node, (n,) each; and an (n, (2R+1)^2) int16 table:
        the position of each neighbour in a node's list, indexed by its (row, column)
        offset, -1 where that offset is no neighbour (R: the largest offset)."""
        n, k = self.neighbors.shape
        row, col = np.divmod(np.arange(n), self.cols)
        dr, dc = row[self.neighbors] - row[:, None], col[self.neighbors] - col[:, None]
        reach = int(max(np.abs(dr).max(initial=0), np.abs(dc).max(initial=0)))
        side = 2 * reach + 1
        table = np.full((n, side * side), -1, np.int16)
        table[np.arange(n)[:, None], (dr + reach) * side + dc + reach] = np.arange(k)
        return row, col, table, reach

    def edge_slot(self, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
        """Position of node ``dst`` in the neighbour list of node ``src`` (int arrays of
        one shape), -1 where it is not one of its neighbours."""
        row, col, table, reach = self._slot_table
        dr, dc = row[dst] - row[src], col[dst] - col[src]
        near = (np.abs(dr) <= reach) & (np.abs(dc) <= reach)
        offset = np.where(near, (dr + reach) * (2 * reach + 1) + dc + reach, 0)
        return np.where(near, table[src, offset], -1)

    @cached_property
    def pixel_nodes(self) -> tuple[np.ndarray, np.ndarray]:
        """(height,) grid row of each pixel row and (width,) grid column of each pixel
        column under nearest-node upsampling (:meth:`to_image`)."""
        ys = np.minimum(np.floor(np.arange(self.height) * (self.rows / self.height)), self.rows - 1)
        xs = np.minimum(np.floor(np.arange(self.width) * (self.cols / self.width)), self.cols - 1)
        return ys.astype(np.int64), xs.astype(np.int64)

    def to_image(self, node_values: np.ndarray) -> np.ndarray:
        """Nearest-node upsampling of (n,) values to an (height, width) map."""
        grid = node_values.reshape(self.rows, self.cols)
        return cv2.resize(grid, (self.width, self.height), interpolation=cv2.INTER_NEAREST)


def sample_bilinear(field: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Bilinear samples of an (H, W, C) float32 field at (n, 2) (x, y) points -> (n, C)."""
    h, w = field.shape[:2]
    x = np.clip(points[:, 0].astype(np.float32), 0, w - 1)
    y = np.clip(points[:, 1].astype(np.float32), 0, h - 1)
    x0 = np.minimum(np.floor(x).astype(np.int64), w - 2) if w > 1 else np.zeros(x.shape, np.int64)
    y0 = np.minimum(np.floor(y).astype(np.int64), h - 2) if h > 1 else np.zeros(y.shape, np.int64)
    fx, fy = x - x0, y - y0  # float64 (float32 - int64), and so is the interpolation
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    flat = np.ascontiguousarray(field).reshape(-1)
    c = flat.size // (h * w)

    def at(rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        # (C, n): channels first, so that every operation below runs along the n points
        first = (rows * w + cols) * c
        return np.stack([flat.take(first + k) for k in range(c)]).astype(np.float64)

    top = at(y0, x0) * (1 - fx) + at(y0, x1) * fx
    bottom = at(y1, x0) * (1 - fx) + at(y1, x1) * fx
    return np.ascontiguousarray((top * (1 - fy) + bottom * fy).T, dtype=np.float32)


def binary_fill_holes(mask: np.ndarray) -> np.ndarray:
    """(H, W) bool ``mask`` with its holes filled: the background not 4-connected to the
    image border (``scipy.ndimage.binary_fill_holes``, through OpenCV's faster labelling)."""
    n, lab = cv2.connectedComponents((~mask).astype(np.uint8), connectivity=4)
    outside = at_border(lab)  # (n,): every label 0..n-1 is present
    outside[0] = False  # label 0: the mask itself
    return mask | ~np.take(outside, lab)  # np.take: faster than outside[lab] (int32)
