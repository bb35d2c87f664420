"""One small class per way of drawing a mark, after roboflow supervision's annotators.

Every annotator has ``annotate(scene, labels, registry=None) -> scene``:

* ``scene``: (H, W, 3) uint8 RGB numpy array or a PIL image; the result has the same
  type (numpy input is not modified, a new array is returned).
* ``labels``: (H, W) integer label map (0 = background, k > 0 = object k), or a
  :class:`~somprompt.regions.LabelRegions` built from one to share the per-object work
  between several annotators.
* ``registry``: a :class:`~somprompt.registry.MarkRegistry` that fixes each id's mark
  number and colour (pass the same one for every frame of a video). ``None`` numbers
  the ids of this map 1, 2, ... in ascending order.

The constructor arguments are the style (palette, opacity, thickness, text scale).
"""

from __future__ import annotations

from typing import Mapping

import cv2
import numpy as np

from motionbits.frames import whole_number

from .anchors import LabelPlacement, place_labels
from .colors import Color, ColorPalette, contrasting_color
from .inputs import ImageLike, as_rgb_array, like_input
from .registry import MarkRegistry, check_registry
from .regions import LabelRegions, as_regions

__all__ = [
    "MaskAnnotator",
    "ContourAnnotator",
    "BoxAnnotator",
    "NumberAnnotator",
    "auto_text_scale",
]

_FONT = cv2.FONT_HERSHEY_SIMPLEX


def _prepare(
    scene: ImageLike, labels: "np.ndarray | LabelRegions", registry: MarkRegistry | None
) -> tuple[np.ndarray, LabelRegions, MarkRegistry]:
    img = as_rgb_array(scene)
    regions = as_regions(labels, img.shape[:2])
    if registry is None:
        registry = MarkRegistry()
        registry.register(regions.ids)
    else:
        check_registry(registry)  # else "argument of type 'int' is not iterable"
        missing = [i for i in regions.ids if i not in registry]
        if missing:
            registry.register(missing)
    return img, regions, registry


#: OpenCV's largest line width (``MAX_THICKNESS`` in drawing.cpp); beyond it cv2 asserts.
MAX_THICKNESS = 32767


def _check_thickness(thickness: int, name: str = "thickness", low: int = 1) -> int:
    """``thickness`` as an int in [low, MAX_THICKNESS] (2.7 would otherwise draw 2 px, 10**9
    fail in OpenCV's "thickness <= MAX_THICKNESS" assertion, inf overflow); ``name`` for
    the messages (also checks ``text_padding``, in [0, MAX_THICKNESS])."""
    thickness = whole_number(name, thickness)
    if not low <= thickness <= MAX_THICKNESS:
        raise ValueError(f"{name} must be in [{low}, {MAX_THICKNESS}] pixels, got {thickness!r:.40}")
    return thickness


#: Largest font scale: the automatic stroke width, ``round(2 * scale)``, must stay a line
#: width OpenCV can draw (MAX_THICKNESS); inf overflowed.
MAX_TEXT_SCALE = MAX_THICKNESS / 2


def auto_text_scale(shape: tuple[int, int]) -> float:
    """OpenCV font scale for an image of ``shape`` (H, W): 0.8 at 480x640, in [0.35, 3].

    Raises:
        TypeError: ``shape`` is not (H, W) or (H, W, C) of whole numbers (NaN gave a NaN
            scale, a str failed in "unsupported operand type(s) for /").
        ValueError: a negative side.
    """
    try:
        hw = list(shape)[:2] if not isinstance(shape, (str, bytes)) else []
    except TypeError:  # an int: "'int' object is not subscriptable"
        hw = []
    if len(hw) != 2:
        raise TypeError(f"shape must be (H, W) or (H, W, C), got {type(shape).__name__} {shape!r:.40}")
    h, w = (whole_number(f"shape[{i}]", v) for i, v in enumerate(hw))
    if min(h, w) < 0:
        raise ValueError(f"shape must be (H, W) in pixels >= 0, got {shape!r:.40}")
    return float(np.clip(min(h, w) / 600.0, 0.35, 3.0))


class _Annotator:
    def __init__(self, palette: ColorPalette | None = None) -> None:
        if palette is not None and not isinstance(palette, ColorPalette):  # else AttributeError 'by_number' when drawing
            raise TypeError(f"palette must be a somprompt.ColorPalette or None (ColorPalette(['#rrggbb', ...])), "
                            f"got {type(palette).__name__} {palette!r:.40}")
        self.palette = palette if palette is not None else ColorPalette.default()

    def color(self, registry: MarkRegistry, obj_id: int) -> Color:
        """Colour of object ``obj_id``: the palette entry of its mark number."""
        return self.palette.by_number(registry.number(obj_id))

    def annotate(
        self,
        scene: ImageLike,
        labels: "np.ndarray | LabelRegions",
        registry: MarkRegistry | None = None,
    ) -> ImageLike:
        img, regions, registry = _prepare(scene, labels, registry)
        out = img.copy()
        self._draw(out, regions, registry)
        return like_input(out, scene)

    def _draw(self, img: np.ndarray, regions: LabelRegions, registry: MarkRegistry) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        fields = ", ".join(f"{k}={v!r}" for k, v in vars(self).items() if k != "palette")
        return f"{type(self).__name__}({fields})"


class MaskAnnotator(_Annotator):
    """Fills each mask with its colour, translucently. Pixels outside every mask are
    left exactly as they were.

    Args:
        palette: colours by mark number (default: :meth:`ColorPalette.default`).
        opacity: weight of the colour, in [0, 1] (0 = invisible, 1 = opaque).

    Returns (``annotate``):
        The scene with masks filled, same type as the input.

    Example:
        >>> import numpy as np
        >>> frame = np.zeros((4, 4, 3), np.uint8); labels = np.zeros((4, 4), int)
        >>> labels[1:3, 1:3] = 1
        >>> out = MaskAnnotator(opacity=1.0).annotate(frame, labels)
        >>> out[1, 1].tolist(), out[0, 0].tolist()
        ([230, 25, 75], [0, 0, 0])
    """

    def __init__(self, palette: ColorPalette | None = None, opacity: float = 0.45) -> None:
        super().__init__(palette)
        if not 0.0 <= float(opacity) <= 1.0:
            raise ValueError(f"opacity must be in [0, 1], got {opacity}")
        self.opacity = float(opacity)

    def _draw(self, img: np.ndarray, regions: LabelRegions, registry: MarkRegistry) -> None:
        a = self.opacity
        for reg in regions:
            view = img[reg.slices]
            color = np.asarray(self.color(registry, reg.obj_id), dtype=np.float32)
            px = view[reg.crop].astype(np.float32)
            view[reg.crop] = np.clip((1 - a) * px + a * color + 0.5, 0, 255).astype(np.uint8)


class ContourAnnotator(_Annotator):
    """Draws each mask's outline (outer boundary and the boundaries of its holes).

    Args:
        palette: colours by mark number.
        thickness: line width in pixels (the line is centred on the mask's boundary
            pixels, so it reaches ``thickness // 2`` pixels outside the mask).

    Example:
        >>> import numpy as np
        >>> frame = np.zeros((9, 9, 3), np.uint8); labels = np.zeros((9, 9), int)
        >>> labels[2:7, 2:7] = 1
        >>> out = ContourAnnotator(thickness=1).annotate(frame, labels)
        >>> bool(out[2, 2].any()), bool(out[4, 4].any())
        (True, False)
    """

    def __init__(self, palette: ColorPalette | None = None, thickness: int = 2) -> None:
        super().__init__(palette)
        self.thickness = _check_thickness(thickness)

    def _draw(self, img: np.ndarray, regions: LabelRegions, registry: MarkRegistry) -> None:
        for reg in regions:
            crop = np.pad(reg.crop.astype(np.uint8), 1)
            contours, _ = cv2.findContours(crop, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
            x0, y0 = reg.bbox[0] - 1, reg.bbox[1] - 1
            shifted = [c + np.array([[[x0, y0]]], dtype=c.dtype) for c in contours]
            cv2.drawContours(img, shifted, -1, self.color(registry, reg.obj_id), self.thickness)


class BoxAnnotator(_Annotator):
    """Draws each mask's bounding box.

    Args:
        palette: colours by mark number.
        thickness: line width in pixels (drawn on the box's outermost pixels, inwards).

    Example:
        >>> import numpy as np
        >>> frame = np.zeros((9, 9, 3), np.uint8); labels = np.zeros((9, 9), int)
        >>> labels[2:7, 3:5] = 1
        >>> out = BoxAnnotator(thickness=1).annotate(frame, labels)
        >>> bool(out[2, 3].any()), bool(out[1, 3].any())
        (True, False)
    """

    def __init__(self, palette: ColorPalette | None = None, thickness: int = 2) -> None:
        super().__init__(palette)
        self.thickness = _check_thickness(thickness)

    def _draw(self, img: np.ndarray, regions: LabelRegions, registry: MarkRegistry) -> None:
        for reg in regions:
            x0, y0, x1, y1 = reg.bbox
            color = self.color(registry, reg.obj_id)
            t = min(self.thickness, (x1 - x0 + 1) // 2, (y1 - y0 + 1) // 2)
            t = max(t, 1)
            # draw the frame as four filled strips so it stays inside the bbox
            img[y0:y0 + t, x0:x1] = color
            img[y1 - t:y1, x0:x1] = color
            img[y0:y1, x0:x0 + t] = color
            img[y0:y1, x1 - t:x1] = color


class NumberAnnotator(_Annotator):
    """Writes each mark's number (or letter) in a filled label box inside its mask.

    The box is centred on the mask's distance-transform maximum, never the centroid;
    boxes of different marks never overlap (see :func:`somprompt.anchors.place_labels`
    for the rule when small masks crowd). The box is filled with the mark's colour, the
    text is black or white, whichever contrasts more with that fill, and a 1-px border
    in black or white, chosen against the pixels under the box, sets it off from the
    scene. A mask of one pixel still gets a full-size box.

    Args:
        palette: colours by mark number.
        text_scale: OpenCV font scale, in (0, 16383.5]; ``None`` picks one from the image
            size (:func:`auto_text_scale`).
        text_thickness: stroke width, a whole number in [1, 32767]; ``None`` follows the scale.
        text_padding: pixels between text and box edge, a whole number in [0, 32767].
        gap: minimum pixels between two label boxes.

    Example:
        >>> import numpy as np
        >>> frame = np.full((60, 60, 3), 128, np.uint8); labels = np.zeros((60, 60), int)
        >>> labels[10:50, 10:50] = 4
        >>> ann = NumberAnnotator(text_scale=0.5)
        >>> out = ann.annotate(frame, labels)
        >>> placements = ann.place(labels)
        >>> placements[4].point
        (29, 29)
    """

    def __init__(
        self,
        palette: ColorPalette | None = None,
        text_scale: float | None = None,
        text_thickness: int | None = None,
        text_padding: int = 3,
        gap: int = 1,
    ) -> None:
        super().__init__(palette)
        if text_scale is not None and not 0 < float(text_scale) <= MAX_TEXT_SCALE:  # inf overflowed in round(2 * scale)
            raise ValueError(f"text_scale must be > 0 and <= {MAX_TEXT_SCALE:g}, got {text_scale}")
        self.text_scale = None if text_scale is None else float(text_scale)
        # 0 was silently drawn as 1, 2.5 as 2, inf overflowed in int()
        self.text_thickness = None if text_thickness is None else _check_thickness(text_thickness, "text_thickness")
        self.text_padding = _check_thickness(text_padding, "text_padding", low=0)  # inf overflowed in int()
        if whole_number("gap", gap) < 0:  # else NaN failed in int(), -1 was read as 0
            raise ValueError(f"gap must be >= 0 pixels, got {gap!r}")
        self.gap = int(gap)

    def _font(self, shape: tuple[int, int]) -> tuple[float, int]:
        scale = self.text_scale if self.text_scale is not None else auto_text_scale(shape)
        thick = self.text_thickness if self.text_thickness is not None else max(1, round(scale * 2))
        return scale, thick

    def box_size(self, text: str, shape: tuple[int, int]) -> tuple[int, int]:
        """``(w, h)`` of the label box for ``text`` on an image of ``shape`` (H, W)."""
        scale, thick = self._font(shape)
        (tw, th), base = cv2.getTextSize(text, _FONT, scale, thick)
        p = self.text_padding
        return tw + 2 * p, th + base + 2 * p

    def place(
        self,
        labels: "np.ndarray | LabelRegions",
        registry: MarkRegistry | None = None,
        prefer: Mapping[int, tuple[int, int]] | None = None,
    ) -> dict[int, LabelPlacement]:
        """Where each label goes, without drawing.

        Args:
            labels: (H, W) label map or LabelRegions.
            registry: mark numbers (None: ids ascending -> 1, 2, ...).
            prefer: id -> ``(x, y)`` to keep when still good (last frame's points).

        Returns:
            object id -> :class:`~somprompt.anchors.LabelPlacement`.
        """
        regions = as_regions(labels)
        if registry is None:
            registry = MarkRegistry()
        registry.register(i for i in regions.ids if i not in registry)
        sizes = {i: self.box_size(registry.text(i), regions.shape) for i in regions.ids}
        return place_labels(regions, sizes, prefer=prefer, gap=self.gap)

    def annotate(
        self,
        scene: ImageLike,
        labels: "np.ndarray | LabelRegions",
        registry: MarkRegistry | None = None,
        prefer: Mapping[int, tuple[int, int]] | None = None,
        placements: Mapping[int, LabelPlacement] | None = None,
    ) -> ImageLike:
        """Draw the labels. ``prefer`` as in :meth:`place`; ``placements`` (from
        :meth:`place`) skips the placement step."""
        img, regions, registry = _prepare(scene, labels, registry)
        if placements is None:
            placements = self.place(regions, registry, prefer)
        out = img.copy()
        self.draw(out, placements, registry, source=img)
        return like_input(out, scene)

    def draw(
        self,
        img: np.ndarray,
        placements: Mapping[int, LabelPlacement],
        registry: MarkRegistry,
        source: np.ndarray | None = None,
    ) -> None:
        """Draw placed labels onto ``img`` ((H, W, 3) uint8, in place). Border colours
        are chosen against ``source`` (default: ``img`` before drawing)."""
        src = img.copy() if source is None else source
        scale, thick = self._font(img.shape[:2])
        for obj_id, pl in placements.items():
            color = self.color(registry, obj_id)
            x0, y0, x1, y1 = pl.box
            if pl.leader:
                cx = int(np.clip(pl.point[0], x0, x1 - 1))
                cy = int(np.clip(pl.point[1], y0, y1 - 1))
                cv2.line(img, (cx, cy), pl.point, color, 1, cv2.LINE_AA)
                cv2.circle(img, pl.point, 1, color, -1)
            under = src[max(y0 - 1, 0):y1 + 1, max(x0 - 1, 0):x1 + 1].reshape(-1, 3)
            mean_under = tuple(int(v) for v in under.mean(axis=0)) if under.size else color
            img[y0:y1, x0:x1] = color
            cv2.rectangle(img, (x0, y0), (x1 - 1, y1 - 1), contrasting_color(mean_under), 1)
            text = registry.text(obj_id)
            (tw, th), base = cv2.getTextSize(text, _FONT, scale, thick)
            org = (x0 + (x1 - x0 - tw) // 2, y0 + (y1 - y0 + th - base) // 2)
            cv2.putText(img, text, org, _FONT, scale, contrasting_color(color), thick, cv2.LINE_AA)
