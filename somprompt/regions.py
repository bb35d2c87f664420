"""Per-object regions of a label map: bounding boxes, areas and cropped masks."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import ndimage

from motionbits.frames import whole_number

from .inputs import check_label_map

__all__ = ["Region", "LabelRegions", "as_regions"]


@dataclass(frozen=True)
class Region:
    """One object of a label map.

    Attributes:
        obj_id: the object's id (> 0).
        bbox: ``(x_min, y_min, x_max, y_max)``, pixel coordinates, max exclusive
            (so width = x_max - x_min).
        area: number of pixels.
        crop: (bbox height, bbox width) bool mask of the object inside ``bbox``.
    """

    obj_id: int
    bbox: tuple[int, int, int, int]
    area: int
    crop: np.ndarray

    @property
    def slices(self) -> tuple[slice, slice]:
        x0, y0, x1, y1 = self.bbox
        return slice(y0, y1), slice(x0, x1)

    def full_mask(self, shape: tuple[int, int]) -> np.ndarray:
        """(H, W) bool mask of the object in an image of ``shape``."""
        out = np.zeros(shape[:2], dtype=bool)
        out[self.slices] = self.crop
        return out


class LabelRegions:
    """A validated (H, W) label map with its per-object regions computed once.

    Annotators accept either a plain label map or a ``LabelRegions``; pass the latter to
    several annotators to do the per-object work only once.

    Args:
        labels: (H, W) integer label map, 0 = background, k > 0 = object k.

    Example:
        >>> import numpy as np
        >>> r = LabelRegions(np.array([[0, 2], [2, 2]]))
        >>> r.ids, r[2].bbox, r[2].area
        ([2], (0, 0, 2, 2), 3)
    """

    def __init__(self, labels: np.ndarray) -> None:
        self.labels = check_label_map(labels)

    @property
    def shape(self) -> tuple[int, int]:
        return self.labels.shape  # type: ignore[return-value]

    @cached_property
    def _by_id(self) -> dict[int, Region]:
        uniq, inverse = np.unique(self.labels, return_inverse=True)
        inverse = inverse.reshape(self.labels.shape)
        # compact labels 1..K (0 stays background only if 0 is present)
        offset = 0 if uniq.size and uniq[0] == 0 else 1
        compact = inverse + offset
        n = int(uniq.size) + offset - 1
        if n <= 0:
            return {}
        areas = np.bincount(compact.ravel(), minlength=n + 1)
        slices = ndimage.find_objects(compact, max_label=n)
        out: dict[int, Region] = {}
        for k, sl in enumerate(slices, start=1):
            if sl is None:
                continue
            obj_id = int(uniq[k - offset])
            if obj_id == 0:
                continue
            ys, xs = sl
            out[obj_id] = Region(
                obj_id=obj_id,
                bbox=(xs.start, ys.start, xs.stop, ys.stop),
                area=int(areas[k]),
                crop=compact[sl] == k,
            )
        return out

    @cached_property
    def areas(self) -> dict[int, int]:
        """Object id -> pixel count, ascending ids (one pass over the map, no per-object work)."""
        uniq, counts = np.unique(self.labels, return_counts=True)
        return {int(i): int(c) for i, c in zip(uniq, counts) if i != 0}

    def largest(self, n: int) -> "tuple[LabelRegions, list[int]]":
        """The ``n`` largest objects (ties: lower id kept) and the ids of the others.

        Returns:
            ``(regions, dropped)``: ``self`` and ``[]`` if there are at most ``n`` objects,
            else new regions on the map with the dropped objects set to background, and
            the dropped ids, smallest object first.
        """
        if whole_number("n", n) < 0:  # else -1 kept all but the smallest, 2.5 and NaN failed in a slice
            raise ValueError(f"n must be >= 0 objects, got {n!r}")
        n = int(n)
        areas = self.areas
        if len(areas) <= n:
            return self, []
        ids = np.fromiter(areas, np.int64, len(areas))
        sizes = np.fromiter(areas.values(), np.int64, len(areas))
        order = np.lexsort((ids, -sizes))  # largest first, then lower id
        keep, drop = ids[order[:n]], ids[order[n:]][::-1]
        labels = np.where(np.isin(self.labels, keep), self.labels, 0)
        return LabelRegions(labels), [int(i) for i in drop]

    @property
    def ids(self) -> list[int]:
        """Object ids present, ascending."""
        return sorted(self._by_id)

    def __getitem__(self, obj_id: int) -> Region:
        try:  # whole numbers only: 3.5 and "3" were read as id 3
            return self._by_id[whole_number("obj_id", obj_id)]
        except KeyError:
            raise KeyError(f"object id {obj_id} is not in this label map (ids: {self.ids[:20]})") from None

    def __contains__(self, obj_id: object) -> bool:
        return obj_id in self._by_id

    def __iter__(self):
        return iter(self._by_id[i] for i in self.ids)

    def __len__(self) -> int:
        return len(self._by_id)

    def mask(self, obj_id: int) -> np.ndarray:
        """(H, W) bool mask of object ``obj_id``."""
        return self[obj_id].full_mask(self.shape)


def as_regions(labels: "np.ndarray | LabelRegions", shape: tuple[int, int] | None = None) -> LabelRegions:
    """Wrap a label map (validated, optionally against a frame ``shape``) as LabelRegions."""
    if isinstance(labels, LabelRegions):
        if shape is not None and tuple(labels.shape) != tuple(shape[:2]):
            check_label_map(labels.labels, shape)  # raises the size-mismatch error
        return labels
    return LabelRegions(check_label_map(labels, shape))
