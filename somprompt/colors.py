"""Mark colours: a palette indexed by mark number, and legible text colours."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from motionbits.frames import whole_number

__all__ = [
    "Color", "ColorPalette", "to_hex", "relative_luminance", "contrast_ratio", "contrasting_color",
]

Color = tuple[int, int, int]
"""An RGB colour, three ints in [0, 255]."""

# Sasha Trubetskoy's "20 simple, distinct colours" (public), grey dropped, reordered so that
# neighbouring mark numbers get very different hues.
_DISTINCT = (
    "#e6194b", "#3cb44b", "#4363d8", "#ffe119", "#f032e6", "#42d4f4", "#f58231", "#911eb4",
    "#bfef45", "#800000", "#469990", "#fabed4", "#000075", "#9a6324", "#dcbeff", "#808000",
    "#aaffc3", "#ffd8b1", "#fffac8",
)


def _hex_to_rgb(value: str) -> Color:
    h = value.lstrip("#")
    if len(h) != 6:
        raise ValueError(f"colour {value!r} is not of the form '#rrggbb'")
    try:
        return (int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16))
    except ValueError as exc:
        raise ValueError(f"colour {value!r} is not of the form '#rrggbb'") from exc


def _to_color(value: "str | Sequence[int]") -> Color:
    if isinstance(value, str):
        return _hex_to_rgb(value)
    c = tuple(int(v) for v in value)
    if len(c) != 3 or not all(0 <= v <= 255 for v in c):
        raise ValueError(f"colour {value!r} must be three ints in [0, 255] (RGB)")
    return c  # type: ignore[return-value]


def to_hex(color: Color) -> str:
    """``(230, 25, 75)`` -> ``'#e6194b'`` (three whole numbers in [0, 255])."""
    c = _rgb(color)  # else (300, 0, 0) gave '#12c0000' and (-1, 0, 0) '#-10000'
    if not all(float(v).is_integer() for v in c):
        raise ValueError(f"colour {color!r:.40} must be three whole numbers in [0, 255] (RGB)")
    return "#{:02x}{:02x}{:02x}".format(*(int(v) for v in c))


def _rgb(color: object) -> np.ndarray:
    """``color`` as three finite floats in [0, 255] (an RGB triple; the mean of pixels may
    be fractional); ValueError otherwise (None gave an IndexError, (300, 0, 0) a
    luminance above 1)."""
    try:
        c = np.asarray(color, dtype=np.float64)
    except (TypeError, ValueError):
        c = np.empty(0)
    if isinstance(color, (str, bool)) or c.shape != (3,) or not np.all(np.isfinite(c)) or c.min() < 0 or c.max() > 255:
        raise ValueError(f"colour {color!r:.40} must be three numbers in [0, 255] (RGB)")
    return c


@dataclass(frozen=True)
class ColorPalette:
    """An ordered list of RGB colours; mark number ``n`` (1-based) gets colour ``n - 1``
    modulo the palette length, so a mark keeps its colour as long as it keeps its number.

    Args:
        colors: RGB tuples or ``'#rrggbb'`` strings.

    Example:
        >>> pal = ColorPalette.from_hex(["#ff0000", "#00ff00"])
        >>> pal.by_number(1), pal.by_number(3)
        ((255, 0, 0), (255, 0, 0))
    """

    colors: tuple[Color, ...]

    def __post_init__(self) -> None:
        if isinstance(self.colors, str):  # else iterated char by char: "colour '#' is not ..."
            raise TypeError(f"colors must be a sequence of colours, got the str {self.colors!r:.40}; "
                            f"for one colour use ColorPalette([{self.colors!r:.40}])")
        bad = "colors must be a sequence of colours ('#rrggbb' strings or RGB triples), got "
        try:
            values = tuple(self.colors)
        except TypeError:  # None, 5: "not iterable"
            raise TypeError(f"{bad}{type(self.colors).__name__} {self.colors!r:.40}") from None
        for i, c in enumerate(values):
            if not isinstance(c, str) and not hasattr(c, "__iter__"):
                raise TypeError(f"{bad}colors[{i}] = {type(c).__name__} {c!r:.40}")
        cols = tuple(_to_color(c) for c in values)
        if not cols:
            raise ValueError("a ColorPalette needs at least one colour")
        object.__setattr__(self, "colors", cols)

    @classmethod
    def default(cls) -> "ColorPalette":
        """19 well-separated colours (Trubetskoy's list)."""
        return cls(_DISTINCT)  # type: ignore[arg-type]

    @classmethod
    def from_hex(cls, values: Sequence[str]) -> "ColorPalette":
        return cls(tuple(values))  # type: ignore[arg-type]

    def __len__(self) -> int:
        return len(self.colors)

    def by_number(self, number: int) -> Color:
        """Colour of mark number ``number`` (1-based, a whole number)."""
        if whole_number("number", number) < 1:  # else NaN failed in int(), 0 gave the last colour, 2.5 mark 2's
            raise ValueError(f"mark numbers start at 1, got {number!r}")
        return self.colors[(int(number) - 1) % len(self.colors)]


def relative_luminance(color: Color) -> float:
    """WCAG 2 relative luminance of an sRGB colour, in [0, 1]."""
    c = _rgb(color) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return float(0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2])


def contrast_ratio(a: Color, b: Color) -> float:
    """WCAG 2 contrast ratio between two colours, in [1, 21]."""
    la, lb = relative_luminance(a), relative_luminance(b)
    hi, lo = max(la, lb), min(la, lb)
    return (hi + 0.05) / (lo + 0.05)


BLACK: Color = (0, 0, 0)
WHITE: Color = (255, 255, 255)


def contrasting_color(background: Color) -> Color:
    """Black or white, whichever has the higher WCAG contrast against ``background``."""
    return BLACK if contrast_ratio(BLACK, background) >= contrast_ratio(WHITE, background) else WHITE
