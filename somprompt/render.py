"""The convenience composite: all marks of a label map on a frame, in one call."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Iterable, Mapping

import numpy as np

from .anchors import LabelPlacement
from .annotators import BoxAnnotator, ContourAnnotator, MaskAnnotator, NumberAnnotator
from .colors import ColorPalette
from .inputs import ImageLike, as_rgb_array, like_input
from .registry import MarkRegistry, MarkStyle, check_registry
from .regions import LabelRegions, as_regions

__all__ = ["MARK_PARTS", "MAX_MARKS", "parse_mode", "RenderedMarks", "SetOfMarkRenderer",
           "draw_marks"]

MAX_MARKS = 256
"""Default cap on the objects marked in one frame. Beyond it the smallest objects are left
unmarked (reported in :attr:`RenderedMarks.dropped` and by a warning): more marks than this
are unreadable, and placing them would cost quadratic time."""

MARK_PARTS = ("mask", "contour", "box", "number")
"""What a mode can combine, in drawing order (the number is drawn last, on top)."""

_ALIASES = {"mark": "number", "marks": "number", "label": "number", "letter": "number",
            "masks": "mask", "contours": "contour", "boxes": "box", "bbox": "box"}


def parse_mode(mode: "str | Iterable[str]") -> tuple[str, ...]:
    """Normalise a rendering mode to a tuple of parts in drawing order.

    Args:
        mode: ``"mask+contour+number"``, ``"mask,number"``, ``"all"`` or an iterable of
            part names from :data:`MARK_PARTS` (``"mark"`` / ``"label"`` mean
            ``"number"``, ``"bbox"`` means ``"box"``).

    Example:
        >>> parse_mode("number+mask")
        ('mask', 'number')
    """
    if isinstance(mode, str):
        if mode.strip().lower() == "all":
            return MARK_PARTS
        items = mode.replace(",", "+").replace("|", "+").replace(" ", "+").split("+")
    elif isinstance(mode, Iterable):
        items = list(mode)
    else:  # e.g. None: "'NoneType' object is not iterable"
        raise TypeError(f"mode must be a str such as 'mask+contour+number' or an iterable of "
                        f"parts, got {type(mode).__name__}")
    parts = set()
    for item in items:
        if not isinstance(item, str):
            raise TypeError(f"mode parts must be strings, got {item!r}")
        key = item.strip().lower()
        if not key:
            continue
        key = _ALIASES.get(key, key)
        if key not in MARK_PARTS:
            raise ValueError(f"unknown mark part {item!r} in mode {mode!r}; use parts of {MARK_PARTS}")
        parts.add(key)
    if not parts:
        raise ValueError(f"mode {mode!r} names no part; use e.g. 'mask+contour+number'")
    return tuple(p for p in MARK_PARTS if p in parts)


@dataclass(frozen=True)
class RenderedMarks:
    """What :meth:`SetOfMarkRenderer.render` returns.

    Attributes:
        image: the marked frame, same type as the input scene.
        placements: object id -> label placement (empty without the number part).
        regions: the label map's regions (bboxes, areas), without dropped objects.
        dropped: ids left unmarked because there were more than ``max_marks`` objects,
            smallest first.
    """

    image: ImageLike
    placements: dict[int, LabelPlacement]
    regions: LabelRegions
    dropped: tuple[int, ...] = field(default=())


class SetOfMarkRenderer:
    """Draws Set-of-Mark marks (mask fill, contour, bbox, number) for every object of a
    label map. Composes :class:`MaskAnnotator`, :class:`ContourAnnotator`,
    :class:`BoxAnnotator` and :class:`NumberAnnotator`.

    Args:
        mode: which parts to draw (see :func:`parse_mode`), default
            ``"mask+contour+number"`` (SoM's default look).
        palette: colours by mark number, shared by all parts.
        opacity: mask fill opacity in [0, 1].
        thickness: contour and box line width in pixels.
        text_scale: font scale of the numbers; ``None`` = from the image size.
        text_padding: pixels between a number and its box edge.
        max_marks: mark at most this many objects, the largest (default
            :data:`MAX_MARKS`; ``None`` = all, at quadratic cost in the number of objects).

    Example:
        >>> import numpy as np
        >>> frame = np.zeros((64, 64, 3), np.uint8); labels = np.zeros((64, 64), np.int32)
        >>> labels[8:30, 8:30] = 1; labels[34:60, 30:60] = 2
        >>> marked = SetOfMarkRenderer(mode="mask+number").annotate(frame, labels)
        >>> marked.shape, marked.dtype
        ((64, 64, 3), dtype('uint8'))
    """

    def __init__(
        self,
        mode: "str | Iterable[str]" = "mask+contour+number",
        palette: ColorPalette | None = None,
        opacity: float = 0.45,
        thickness: int = 2,
        text_scale: float | None = None,
        text_padding: int = 3,
        max_marks: int | None = MAX_MARKS,
    ) -> None:
        if max_marks is not None and (isinstance(max_marks, bool) or not isinstance(max_marks, int)
                                      or max_marks < 1):
            raise ValueError(f"max_marks must be a positive integer or None, got {max_marks!r}")
        self.max_marks = max_marks
        self.mode = parse_mode(mode)
        self.palette = palette if palette is not None else ColorPalette.default()
        self.mask = MaskAnnotator(self.palette, opacity)
        self.contour = ContourAnnotator(self.palette, thickness)
        self.box = BoxAnnotator(self.palette, thickness)
        self.number = NumberAnnotator(self.palette, text_scale, text_padding=text_padding)

    def render(
        self,
        scene: ImageLike,
        labels: "np.ndarray | LabelRegions",
        registry: MarkRegistry | None = None,
        prefer: Mapping[int, tuple[int, int]] | None = None,
    ) -> RenderedMarks:
        """Draw the marks and return the image with the label placements.

        Args:
            scene: (H, W, 3) uint8 RGB array or PIL image.
            labels: (H, W) integer label map of the same size, or LabelRegions.
            registry: id -> mark number (and colour); reuse one across a video. None:
                the ids of this map are numbered 1, 2, ... ascending.
            prefer: id -> ``(x, y)`` label points to keep if still good (last frame's).

        Returns:
            :class:`RenderedMarks`.
        """
        if registry is not None:
            check_registry(registry)
        img = as_rgb_array(scene)
        regions = as_regions(labels, img.shape[:2])
        dropped: list[int] = []
        if self.max_marks is not None:
            regions, dropped = regions.largest(self.max_marks)
        if dropped:
            warnings.warn(f"{len(dropped)} of {len(dropped) + len(regions.areas)} objects left "
                          f"unmarked: more than max_marks={self.max_marks}, smallest dropped",
                          stacklevel=3)
        if registry is None:
            registry = MarkRegistry()
        registry.register(i for i in regions.ids if i not in registry)
        out = img.copy()
        for part in self.mode:
            if part != "number":
                getattr(self, part)._draw(out, regions, registry)
        placements: dict[int, LabelPlacement] = {}
        if "number" in self.mode:
            placements = self.number.place(regions, registry, prefer)
            self.number.draw(out, placements, registry, source=img)
        return RenderedMarks(like_input(out, scene), placements, regions, tuple(dropped))

    def annotate(
        self,
        scene: ImageLike,
        labels: "np.ndarray | LabelRegions",
        registry: MarkRegistry | None = None,
    ) -> ImageLike:
        """Draw the marks; returns the marked scene (same type as ``scene``)."""
        return self.render(scene, labels, registry).image

    def __repr__(self) -> str:
        return f"SetOfMarkRenderer(mode={'+'.join(self.mode)!r}, opacity={self.mask.opacity})"


def draw_marks(
    frame: ImageLike,
    labels: np.ndarray,
    mode: "str | Iterable[str]" = "mask+contour+number",
    style: MarkStyle = "number",
    registry: MarkRegistry | None = None,
    **renderer_kwargs,
) -> ImageLike:
    """Marks on one frame in one call.

    Args:
        frame: (H, W, 3) uint8 RGB array or PIL image.
        labels: (H, W) integer label map, 0 = background.
        mode: parts to draw, e.g. ``"mask+contour+number"``, ``"number"``, ``"all"``.
        style: ``"number"`` (1, 2, ...) or ``"letter"`` (a, b, ...); ignored when a
            ``registry`` is given (it carries its own style).
        registry: reuse to keep numbers and colours stable across frames.
        **renderer_kwargs: style options of :class:`SetOfMarkRenderer`.

    Returns:
        The marked frame, same type as ``frame``.

    Example:
        >>> import numpy as np
        >>> labels = np.zeros((32, 32), int); labels[4:20, 4:20] = 9
        >>> out = draw_marks(np.zeros((32, 32, 3), np.uint8), labels, mode="number", style="letter")
        >>> out.shape
        (32, 32, 3)
    """
    if registry is None:
        registry = MarkRegistry(style)
    return SetOfMarkRenderer(mode, **renderer_kwargs).annotate(frame, labels, registry)
