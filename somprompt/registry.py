"""Stable assignment of object ids to mark numbers (and so to colours) across frames."""

from __future__ import annotations

from typing import Iterable, Literal

import numpy as np

from motionbits.frames import whole_number

from .inputs import check_label_map

__all__ = ["MarkStyle", "MarkRegistry", "mark_text", "parse_mark_text"]

MarkStyle = Literal["number", "letter"]
_STYLES = ("number", "letter")


def mark_text(number: int, style: MarkStyle = "number") -> str:
    """The text drawn for mark ``number`` (1-based): SoM's ``1`` or ``a`` style.

    Letters continue after ``z`` as ``aa, ab, ...`` (bijective base 26).

    Example:
        >>> [mark_text(n, "letter") for n in (1, 26, 27, 28)]
        ['a', 'z', 'aa', 'ab']

    Raises:
        TypeError: ``number`` is not a whole number (1.5 and True were drawn as ``1``).
    """
    number = whole_number("number", number)
    if number < 1:
        raise ValueError(f"mark numbers start at 1, got {number}")
    if style == "number":
        return str(number)
    if style == "letter":
        out = ""
        while number > 0:
            number, rem = divmod(number - 1, 26)
            out = chr(ord("a") + rem) + out
        return out
    raise ValueError(f"unknown mark style {style!r}; use one of {_STYLES}")


#: Largest mark number: an id beyond int64 is in no label map.
_MAX_NUMBER = 2**63 - 1


def parse_mark_text(text: str, style: MarkStyle = "number") -> int | None:
    """Inverse of :func:`mark_text`; ``None`` if ``text`` is not a mark of that style
    (numbers beyond the int64 range, which no label map holds, included).

    Raises:
        TypeError: ``text`` is not a str.
    """
    if not isinstance(text, str):
        raise TypeError(f"mark text must be a str, got {type(text).__name__}")
    text = text.strip()
    if style == "number":
        if not (text.isdigit() and text.isascii()):
            return None
        text = text.lstrip("0")  # the length test spares int() a number of 5000 digits
        return int(text) if text and len(text) <= 19 and int(text) <= _MAX_NUMBER else None
    if style == "letter":
        t = text.lower()
        if not t or not t.isascii() or not t.isalpha():
            return None
        n = 0
        for ch in t:
            n = n * 26 + (ord(ch) - ord("a") + 1)
        return n
    raise ValueError(f"unknown mark style {style!r}; use one of {_STYLES}")


def whole_ids(values: Iterable, name: str, what: str = "object ids") -> list[int]:
    """``values`` as ints, in order (``what`` they are, for the messages).

    Raises:
        TypeError: ``values`` is not an iterable (or is a str), or holds anything but whole
            numbers (ints, numpy's, whole floats such as 3.0; not bools): ``[1.5]`` or
            ``[3.7]`` would otherwise read as 1 or 3.
    """
    if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
        raise TypeError(f"{name} must be an iterable of {what}, got "
                        f"{type(values).__name__} {values!r:.40}")
    ids = []
    for i in values:
        try:
            ids.append(whole_number(name, i))
        except TypeError:
            raise TypeError(f"{name} must hold integer {what} (whole numbers), got "
                            f"{type(i).__name__} {i!r:.40}") from None
    return ids


def check_registry(registry: object, name: str = "registry") -> None:
    """TypeError unless ``registry`` is a :class:`MarkRegistry` (a list of ids failed with
    "'list' object has no attribute 'ids'", an int with "... no attribute 'register'")."""
    if not isinstance(registry, MarkRegistry):
        raise TypeError(f"{name} must be a somprompt.MarkRegistry (register the ids with "
                        f"MarkRegistry().register(ids)), got {type(registry).__name__}")


class MarkRegistry:
    """Remembers which mark number each object id got, so that one object keeps its number
    (and therefore its colour) on every frame of a video.

    New ids get the next free number in the order they are first seen (ascending id
    within one frame). Ids that disappear keep their number; it is never reused.

    Args:
        style: ``"number"`` (marks 1, 2, 3, ...) or ``"letter"`` (a, b, c, ...).

    Example:
        >>> import numpy as np
        >>> reg = MarkRegistry()
        >>> reg.update(np.array([[0, 7], [7, 3]]))
        [3, 7]
        >>> reg.number(3), reg.text(7), reg.id_for_text("2")
        (1, '2', 7)
    """

    def __init__(self, style: MarkStyle = "number") -> None:
        if style not in _STYLES:
            raise ValueError(f"unknown mark style {style!r}; use one of {_STYLES}")
        self.style: MarkStyle = style
        self._number: dict[int, int] = {}
        self._id: dict[int, int] = {}
        self._frames: dict[int, set[int]] = {}

    # -- building --------------------------------------------------------------------
    def register(self, ids: Iterable[int]) -> None:
        """Give each new id in ``ids`` the next free number (in the order given).

        Raises:
            TypeError: ``ids`` is not an iterable of whole numbers (``[1.5]`` would
                otherwise register id 1).
            ValueError: an id <= 0.
        """
        for i in whole_ids(ids, "ids"):
            if i <= 0:
                raise ValueError(f"object ids must be > 0 (0 is background), got {i}")
            if i not in self._number:
                n = len(self._number) + 1
                self._number[i] = n
                self._id[n] = i

    def update(self, labels: np.ndarray, frame_index: int | None = None) -> list[int]:
        """Register the ids present in an (H, W) label map.

        Args:
            labels: (H, W) integer label map, 0 = background.
            frame_index: if given, recorded in :meth:`frames_seen` for each present id.

        Returns:
            The ids present in ``labels``, ascending.
        """
        labels = check_label_map(labels)
        ids = [int(i) for i in np.unique(labels) if i != 0]
        self.register(ids)
        if frame_index is not None:
            for i in ids:
                self._frames.setdefault(i, set()).add(int(frame_index))
        return ids

    @classmethod
    def from_label_maps(
        cls, label_maps: Iterable[np.ndarray], style: MarkStyle = "number"
    ) -> "MarkRegistry":
        """A registry updated with every map in order (frame indices 0, 1, ...)."""
        reg = cls(style)
        for t, lm in enumerate(label_maps):
            reg.update(lm, frame_index=t)
        return reg

    # -- lookups ---------------------------------------------------------------------
    @property
    def ids(self) -> list[int]:
        """All registered ids, in mark-number order."""
        return [self._id[n] for n in sorted(self._id)]

    def __len__(self) -> int:
        return len(self._number)

    def __contains__(self, obj_id: object) -> bool:
        return obj_id in self._number

    def number(self, obj_id: int) -> int:
        """Mark number (1-based) of object ``obj_id`` (a whole number: 3.7 is no id, not 3)."""
        obj_id = whole_number("obj_id", obj_id)
        try:
            return self._number[obj_id]
        except KeyError:
            raise KeyError(
                f"object id {obj_id} is not registered; call registry.update(label_map) first "
                f"(registered: {self.ids[:20]})"
            ) from None

    def text(self, obj_id: int) -> str:
        """The mark as drawn (``'3'`` or ``'c'``)."""
        return mark_text(self.number(obj_id), self.style)

    def id_for_number(self, number: int) -> int | None:
        """Object id that carries mark ``number`` (a whole number: 1.5 is no mark, not 1), or None."""
        return self._id.get(whole_number("number", number))

    def id_for_text(self, text: str) -> int | None:
        """Object id whose mark reads ``text`` (``'3'`` / ``'c'``), or None."""
        n = parse_mark_text(text, self.style)
        return None if n is None else self._id.get(n)

    def frames_seen(self, obj_id: int) -> list[int]:
        """Frame indices passed to :meth:`update` in which ``obj_id`` was present, sorted
        (``obj_id`` a whole number: 3.7 is no id, not 3)."""
        return sorted(self._frames.get(whole_number("obj_id", obj_id), ()))

    def __repr__(self) -> str:
        pairs = ", ".join(f"{i}->{self.text(i)}" for i in self.ids[:8])
        more = ", ..." if len(self) > 8 else ""
        return f"MarkRegistry(style={self.style!r}, {{{pairs}{more}}})"
