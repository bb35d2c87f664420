"""Mark metadata: what each mark stands for, as a dataclass and as JSON."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Mapping

from motionbits.frames import whole_number

from .anchors import LabelPlacement, mask_anchor
from .colors import ColorPalette, to_hex
from .registry import MarkRegistry, check_registry
from .regions import LabelRegions, as_regions

__all__ = ["MarkInfo", "describe_marks", "marks_to_json", "save_marks_json"]


@dataclass
class MarkInfo:
    """One mark, as shown to the VLM.

    Attributes:
        obj_id: object id in the label maps.
        number: mark number (1-based; the letter style shows it as a, b, ...).
        text: the mark as drawn (``"3"`` or ``"c"``).
        color: ``"#rrggbb"``.
        anchor: ``[x, y]`` of the label's point (a pixel of the mask) in ``frame``.
        bbox: ``[x_min, y_min, x_max, y_max]`` in ``frame``, max exclusive.
        area: mask pixels in ``frame``.
        frame: index of the frame the geometry above was measured on (the last one in
            which the object was present).
        frames_seen: indices of all frames in which the object was present.
    """

    obj_id: int
    number: int
    text: str
    color: str
    anchor: list[int]
    bbox: list[int]
    area: int
    frame: int | None = None
    frames_seen: list[int] = field(default_factory=list)

    def to_dict(self) -> dict:
        return asdict(self)


def describe_marks(
    regions: LabelRegions,
    registry: MarkRegistry,
    placements: Mapping[int, LabelPlacement] | None = None,
    palette: ColorPalette | None = None,
    frame_index: int | None = None,
) -> dict[int, MarkInfo]:
    """Metadata of the marks of one frame.

    Args:
        regions: the frame's label map regions (or its (H, W) label map).
        registry: id -> number; ids of ``regions`` not in it are registered.
        placements: label placements of the frame (their points are the anchors); ids
            without one get the distance-transform maximum of their mask.
        palette: the palette the marks were drawn with (default palette if None).
        frame_index: recorded in ``MarkInfo.frame``.

    Returns:
        object id -> :class:`MarkInfo`, in mark-number order.
    """
    regions = as_regions(regions)  # a label map is read as its regions (was: no attribute 'ids')
    check_registry(registry)
    if frame_index is not None and whole_number("frame_index", frame_index) < 0:  # NaN was written to the JSON
        raise ValueError(f"frame_index must be >= 0 or None, got {frame_index!r}")
    frame_index = None if frame_index is None else int(frame_index)
    palette = palette if palette is not None else ColorPalette.default()
    placements = placements or {}
    registry.register(i for i in regions.ids if i not in registry)
    out: dict[int, MarkInfo] = {}
    for reg in sorted(regions, key=lambda r: registry.number(r.obj_id)):
        if reg.obj_id in placements:
            anchor = list(placements[reg.obj_id].point)
        else:
            x, y = mask_anchor(reg.crop)
            anchor = [x + reg.bbox[0], y + reg.bbox[1]]
        n = registry.number(reg.obj_id)
        out[reg.obj_id] = MarkInfo(
            obj_id=reg.obj_id,
            number=n,
            text=registry.text(reg.obj_id),
            color=to_hex(palette.by_number(n)),
            anchor=[int(v) for v in anchor],
            bbox=[int(v) for v in reg.bbox],
            area=reg.area,
            frame=frame_index,
            frames_seen=registry.frames_seen(reg.obj_id),
        )
    return out


def marks_to_json(
    marks: Mapping[int, MarkInfo],
    *,
    style: str | None = None,
    image_size: tuple[int, int] | None = None,
    indent: int | None = 2,
) -> str:
    """Serialise mark metadata.

    Args:
        marks: id -> MarkInfo (e.g. from :func:`describe_marks` or ``MarkedVideo.marks``).
        style: ``"number"`` / ``"letter"``, recorded if given.
        image_size: ``(W, H)`` of the frames the geometry refers to, two whole numbers
            >= 1, recorded if given.
        indent: as in :func:`json.dumps`: a whole number, a str, or None (one line).

    Returns:
        JSON text: ``{"style": ..., "image_size": [W, H], "marks": [{...}, ...]}`` with
        marks in number order, keys as in :class:`MarkInfo`.

    Raises:
        TypeError: ``marks`` is not a mapping of MarkInfo (a list failed with "'list' object
            has no attribute 'values'"), ``style`` not a str, ``image_size`` not two whole
            numbers (NaN failed in int(), 2.5 was written as 2), ``indent`` a NaN or a bool.
        ValueError: an ``image_size`` side < 1.
    """
    if not isinstance(marks, Mapping):
        raise TypeError(f"marks must be a mapping id -> MarkInfo (as describe_marks returns), got "
                        f"{type(marks).__name__} {marks!r:.40}")
    bad = next((m for m in marks.values() if not isinstance(m, MarkInfo)), None)
    if bad is not None:
        raise TypeError(f"marks must map ids to somprompt.MarkInfo, got a {type(bad).__name__} {bad!r:.40}")
    if style is not None and not isinstance(style, str):
        raise TypeError(f"style must be a str (\"number\" / \"letter\") or None, got {type(style).__name__} {style!r:.40}")
    if indent is not None and not isinstance(indent, str):
        indent = whole_number("indent", indent)  # NaN failed in json's "can't multiply sequence by non-int"
    doc: dict = {}
    if style is not None:
        doc["style"] = style
    if image_size is not None:
        doc["image_size"] = _image_size(image_size)
    doc["marks"] = [m.to_dict() for m in sorted(marks.values(), key=lambda m: m.number)]
    return json.dumps(doc, indent=indent)


def _image_size(image_size: object) -> list[int]:
    """``image_size`` as ``[W, H]``, two whole numbers >= 1."""
    try:
        sides = list(image_size) if not isinstance(image_size, (str, bytes)) else None
    except TypeError:  # 20: "'int' object is not subscriptable"
        sides = None
    if sides is None or len(sides) != 2:
        raise TypeError(f"image_size must be (W, H), two whole numbers, got {type(image_size).__name__} "
                        f"{image_size!r:.40}")
    wh = [whole_number(f"image_size[{i}]", v) for i, v in enumerate(sides)]
    if min(wh) < 1:
        raise ValueError(f"image_size must be (W, H) in pixels >= 1, got {image_size!r:.40}")
    return wh


def save_marks_json(path: "str | Path", marks: Mapping[int, MarkInfo], **kwargs) -> Path:
    """Write :func:`marks_to_json` to ``path``; returns the path."""
    path = Path(path)
    text = marks_to_json(marks, **kwargs)  # bad arguments: no folder made, no file written
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + "\n", encoding="utf-8")
    return path
