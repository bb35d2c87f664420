"""From a VLM's free-text answer back to masks: which marks does it cite?

Recognised citations (case-insensitive keywords; ``n`` = a mark number, ``x`` = a mark
letter in the letter style):

====================  ===============================================================
form                  examples
====================  ===============================================================
square brackets       ``[3]``, ``[3, 5]``, ``[3][5]``, ``[3 and 5]``, ``[mark 3]``,
                      ``[#3]``, nested ``[3, [5]]``; letter style ``[a]``, ``[a, c]``, ``[a][b]``; also the
                      full-width ``［3］`` and the CJK ``【3】``, ``〔3〕``, ``【3、5】``
round brackets        ``(3)``, ``(3, 5)`` (at most 3 digits), full-width ``（3）``;
                      letter style ``(a)``
keyword + mark        ``mark 3``, ``Mark #3``, ``object 3``, ``objects 3, 5 and 7``,
                      ``region 2``, ``label 4``, ``mask 1``, ``segment 2``, ``item 6``,
                      ``body 3``, ``id 3``; letter style ``object A`` (upper case), or
                      ``object a`` followed by punctuation, ``and``/``or`` or the end
hash                  ``#3`` (not inside words, HTML entities or colours like ``#3cb44b``)
====================  ===============================================================

Any string is accepted: lone UTF-16 surrogates (``"\\ud800"``, from a JSON escape or
``surrogateescape`` decoding) become U+FFFD and split surrogate pairs are joined
(:func:`repair_text`), so parsed text always encodes to UTF-8.

Not citations: bare numbers (``3 cups``, ``at 3 o'clock``, ``1. the cup``), decimals
(``3.5``), numbers after a keyword that are followed by a unit (``object 3 cm away``),
and four-digit numbers from 1800 to 2199 that are no known mark (years). Only tokens of
the registry's style count: in the number style ``[a]`` is ignored, in the letter style
``[3]`` is. Known limits: enumerations written ``(1) ... (2) ...`` read as citations;
ranges such as ``[3-5]`` are not expanded.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Iterable, Iterator

import numpy as np

from .inputs import check_label_map
from .registry import MarkRegistry, MarkStyle, parse_mark_text, whole_ids

__all__ = [
    "Citation",
    "ParsedAnswer",
    "find_citations",
    "parse_answer",
    "masks_for_ids",
    "NamedObject",
    "parse_named_objects",
    "repair_text",
]

_SURROGATE = re.compile("[\ud800-\udfff]")

_KW = r"(?i:marks?|markers?|objects?|regions?|labels?|masks?|segments?|items?|ids?|bod(?:y|ies))"
_SEP = r"(?:\s*[,;/&\uff0c\u3001\uff1b]\s*(?:(?i:and|or)\s+)?|\s+(?i:and|or)\s+)"  # also ， 、 ；
# brackets: ASCII, full-width and the CJK lenticular / tortoise-shell ones (Qwen answers in
# Chinese cite marks as 【3】)
_OPEN = r"[\[\uff3b\u3010\u3014]"
_CLOSE = r"[\]\uff3d\u3011\u3015]"
_ROPEN = r"[(\uff08]"
_RCLOSE = r"[)\uff09]"
_UNIT = (
    r"(?i:%|°|mm|cm|m|km|in|inch(?:es)?|ft|feet|px|pixels?|deg(?:rees)?|o'?clock|s|sec(?:onds?)?"
    r"|min(?:utes?)?|h|hours?|times|x|kg|g|fps)(?![A-Za-z])"
)
_NUM = r"\d+(?!\d|\.\d)"  # any length: a cited mark that does not exist is reported
_NUM3 = r"\d{1,3}(?!\d|\.\d)"
_NUM_KW = rf"{_NUM}(?!\s*{_UNIT})"
_LET = r"[A-Za-z]{1,2}(?![A-Za-z0-9])"

# a mark inside a bracketed list may sit in brackets of its own (JSON: ``[3, [5]]``)
_ITEM = rf"(?:{_OPEN}\s*)?(?:{_KW}\s*)?#?{_NUM}(?:\s*{_CLOSE})?"

_PATTERNS: dict[str, list[re.Pattern]] = {
    "number": [
        re.compile(rf"{_OPEN}\s*({_ITEM}(?:{_SEP}{_ITEM})*)\s*{_CLOSE}"),
        re.compile(rf"{_ROPEN}\s*#?({_NUM3}(?:{_SEP}#?{_NUM3})*)\s*{_RCLOSE}"),
        re.compile(rf"\b{_KW}\s*(?:#\s?|(?i:no\.?|nr\.?|number)\s*)?({_NUM_KW}(?:{_SEP}#?{_NUM_KW})*)"),
        re.compile(r"(?<![\w&#/])#\s?(\d{1,4})(?![\d\w]|\.\d)"),
    ],
    "letter": [
        re.compile(rf"{_OPEN}\s*(?:{_KW}\s*)?({_LET}(?:{_SEP}(?:{_KW}\s+)?{_LET})*)\s*{_CLOSE}"),
        re.compile(rf"{_ROPEN}\s*([A-Za-z])\s*{_RCLOSE}"),
        re.compile(rf"\b{_KW}\s+#?([A-Z])(?![A-Za-z0-9'])"),
        re.compile(rf"\b{_KW}\s+#?([a-z])(?=\s*(?:[,.;:!?)\]]|$)|\s+(?i:and|or)\b)"),
    ],
}
# the start of a bracketed list of numbers (pattern 0 of "number" without its closing
# bracket): it never backtracks, so it finds where a run of items ends in linear time
_NUMBER_RUN = re.compile(rf"{_OPEN}\s*{_ITEM}(?:{_SEP}{_ITEM})*")
_TOKEN = {"number": re.compile(r"\d+"), "letter": re.compile(r"[A-Za-z]+")}
_SEP_WORDS = {"and", "or"}
_KW_WORDS = re.compile(rf"^{_KW}$")


@dataclass(frozen=True)
class Citation:
    """One mark cited in an answer.

    Attributes:
        text: the mark as written, normalised (``"3"``, ``"c"``).
        obj_id: the object id it refers to, or None if no such mark exists.
        start, end: character span of the mark in the answer.
    """

    text: str
    obj_id: int | None
    start: int
    end: int


@dataclass
class ParsedAnswer:
    """What an answer cites.

    Attributes:
        answer: the answer text (after :func:`repair_text`: it encodes to UTF-8).
        ids: object ids of the cited marks, in order of first mention, no repeats.
        unknown: cited marks (as text) that do not exist, in order of first mention.
        citations: every citation, in text order.
        masks: object id -> (H, W) bool mask, for each cited id present in the label
            map passed to :func:`parse_answer` (empty without one).
        missing: cited ids that exist but are absent from that label map.
    """

    answer: str
    ids: list[int]
    unknown: list[str]
    citations: list[Citation] = field(default_factory=list)
    masks: dict[int, np.ndarray] = field(default_factory=dict)
    missing: list[int] = field(default_factory=list)
    shape: tuple[int, int] | None = None

    @property
    def label_map(self) -> np.ndarray | None:
        """(H, W) int64 map holding only the cited objects (ids kept), or None without
        a label map."""
        if self.shape is None:
            return None
        out = np.zeros(self.shape, dtype=np.int64)
        for i, m in self.masks.items():
            out[m] = i
        return out

    @property
    def mask(self) -> np.ndarray | None:
        """(H, W) bool union of the cited masks, or None without a label map."""
        lm = self.label_map
        return None if lm is None else lm > 0


def repair_text(text: str) -> str:
    """``text`` as valid Unicode, which encodes to UTF-8: a surrogate pair held as two
    code points becomes its character, a lone surrogate becomes U+FFFD (so one code point
    stays one, and the rest of the text keeps its offsets). Text without surrogates is
    returned as is."""
    if not isinstance(text, str):  # else re's "expected string or bytes-like object"
        raise TypeError(f"text must be a str, got {type(text).__name__}")
    if not _SURROGATE.search(text):
        return text
    return text.encode("utf-16-le", "surrogatepass").decode("utf-16-le", "replace")


def find_citations(answer: str, style: MarkStyle = "number") -> list[tuple[str, int, int]]:
    """Mark tokens cited in ``answer`` (rules in the module doc), as
    ``(text, start, end)`` in text order, one per occurrence.

    Never raises on any string. Raises TypeError for non-strings.
    """
    if not isinstance(answer, str):
        raise TypeError(f"answer must be a str, got {type(answer).__name__}")
    if style not in _PATTERNS:
        raise ValueError(f"unknown mark style {style!r}; use 'number' or 'letter'")
    spans: dict[tuple[int, int], str] = {}
    for pattern in _PATTERNS[style]:
        matches = (_bracket_lists(answer) if pattern is _PATTERNS["number"][0]
                   else pattern.finditer(answer))
        for m in matches:
            g_start = m.start(1)
            for tok in _TOKEN[style].finditer(m.group(1)):
                word = tok.group(0)
                if style == "letter" and (word.lower() in _SEP_WORDS or _KW_WORDS.match(word)):
                    continue
                span = (g_start + tok.start(), g_start + tok.end())
                spans.setdefault(span, word.lower() if style == "letter" else _number_text(word))
    return [(text, s, e) for (s, e), text in sorted(spans.items())]


def _bracket_lists(answer: str) -> Iterator[re.Match]:
    """The matches of the bracketed-list pattern, as its ``finditer`` gives them, in linear
    time: ``finditer`` tried the pattern at every ``[`` of a run of list items and each try
    scanned the rest of the run, so an unclosed ``[3, [3, [3, ...`` (a VLM repeating itself
    until ``max_new_tokens``) took 47 s for 40,000 characters. A try that fails at a run's
    start fails at every ``[`` inside the run (each begins an item, whose continuations
    the first try has already seen), so the search goes on after the run."""
    pattern, pos = _PATTERNS["number"][0], 0
    while (run := _NUMBER_RUN.search(answer, pos)) is not None:
        m = pattern.match(answer, run.start())
        if m is not None:
            yield m
        pos = run.end() if m is None else m.end()


def _number_text(word: str) -> str:
    """A number token in ASCII digits without leading zeros (``"007"`` -> ``"7"``, the
    Arabic-Indic ``"\u0663"`` -> ``"3"``), digit by digit: ``int(word)`` refuses a token of
    more than 4300 digits (Python's limit on converting long digit strings)."""
    return "".join(str(int(c)) for c in word).lstrip("0") or "0"


def _looks_like_year(text: str) -> bool:
    return len(text) == 4 and text.isdigit() and 1800 <= int(text) <= 2199


def parse_answer(
    answer: str,
    marks: MarkRegistry | Iterable[int] | None = None,
    labels: np.ndarray | None = None,
    style: MarkStyle = "number",
) -> ParsedAnswer:
    """Find the marks an answer cites and return their masks.

    Args:
        answer: the VLM's text. Any string is accepted; garbage cites nothing. It is
            read (and kept as ``ParsedAnswer.answer``) after :func:`repair_text`.
        marks: a :class:`MarkRegistry` (mark texts are mapped through it; its style is
            used); or an iterable of object ids shown with number = id; or None: number
            = id, and the ids present in ``labels`` (if given) are the known ones.
        labels: (H, W) integer label map to take the masks from (e.g. the last frame's).
        style: ``"number"`` or ``"letter"``, when ``marks`` is not a registry.

    Returns:
        :class:`ParsedAnswer`.

    Raises:
        TypeError: ``answer`` is not a str (e.g. None), or ``marks`` is not one of the above.

    Example:
        >>> import numpy as np
        >>> labels = np.zeros((4, 4), int); labels[0, 0] = 3; labels[3, 3] = 5
        >>> p = parse_answer("The cup [5] hit [3]; mark 9 and the 3 spoons stayed.", labels=labels)
        >>> p.ids, p.unknown, int(p.masks[5].sum())
        ([5, 3], ['9'], 1)
    """
    if not isinstance(answer, str):
        raise TypeError(
            f"answer must be the VLM's text (str), got {type(answer).__name__}; "
            "if the VLM returned None it produced no answer"
        )
    answer = repair_text(answer)
    lm = None if labels is None else check_label_map(labels)
    present = None if lm is None else {int(i) for i in np.unique(lm) if i != 0}

    if isinstance(marks, MarkRegistry):
        style = marks.style
        lookup = marks.id_for_text
    else:
        if marks is not None:
            known = _known_ids(marks)
        elif present is not None:
            known = present
        else:
            known = None  # anything goes

        def lookup(text: str) -> int | None:
            n = parse_mark_text(text, style)
            return n if n is not None and (known is None or n in known) else None

    citations: list[Citation] = []
    ids: list[int] = []
    unknown: list[str] = []
    for text, start, end in find_citations(answer, style):
        obj_id = lookup(text)
        if obj_id is None:
            if style == "number" and (text == "0" or _looks_like_year(text)):
                continue  # "[0]" is no mark; "(2024)" is a year
            if text not in unknown:
                unknown.append(text)
        elif obj_id not in ids:
            ids.append(obj_id)
        citations.append(Citation(text, obj_id, start, end))

    masks: dict[int, np.ndarray] = {}
    missing: list[int] = []
    if lm is not None:
        masks = masks_for_ids(lm, ids)
        missing = [i for i in ids if i not in masks]
    return ParsedAnswer(answer, ids, unknown, citations, masks, missing,
                        None if lm is None else lm.shape)


def _known_ids(marks: Iterable[int]) -> set[int]:
    """The object ids of ``parse_answer``'s ``marks`` (whole numbers; numpy's too)."""
    if isinstance(marks, (str, bytes)) or not isinstance(marks, Iterable):
        raise TypeError("marks must be a MarkRegistry, an iterable of object ids or None, "
                        f"got {type(marks).__name__} {marks!r:.40}")
    return set(whole_ids(marks, "marks"))


def masks_for_ids(labels: np.ndarray, ids: Iterable[int]) -> dict[int, np.ndarray]:
    """Object id -> (H, W) bool mask, for each of ``ids`` present in ``labels``.

    Raises:
        TypeError: ``ids`` is not an iterable of whole numbers (e.g. None, or 3.7, which
            would otherwise give the mask of 3).
    """
    lm = check_label_map(labels)
    out = {}
    for i in whole_ids(ids, "ids"):
        m = lm == i
        if m.any():
            out[i] = m
    return out


@dataclass(frozen=True)
class NamedObject:
    """One line of a ``- <name>: <description>`` answer (prompt ``moved_rigid_bodies``).

    Attributes:
        name: short noun phrase, lower case, no marks or markup: a detector text class.
        description: the rest of the line.
        marks: mark texts cited on the line (``som_moved_rigid_bodies`` format).
    """

    name: str
    description: str
    marks: tuple[str, ...] = ()


# "- name: description", "* name - description", "1. name: description", "- [1][3] name: ..."
_LINE = re.compile(
    r"""^\s*(?:[-*\u2022\u2013]|\d{1,3}[.)])\s+      # bullet or number
        (?P<head>[^:\n]{1,120}?)\s*                  # marks and name
        (?::|\s[-\u2013\u2014]\s)\s*                  # ':' or ' - ' separator
        (?P<desc>.*?)\s*$""",
    re.VERBOSE,
)
_ARTICLE = re.compile(r"^(?:the|a|an|one|two|three|some|this|that|these|those)\s+", re.I)
_NONE_NAMES = {"none", "nothing", "no object", "no objects", "n/a", "na", "null"}
_MAX_NAME_WORDS = 6
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")  # NUL, ESC, ...: not part of a name (read as spaces)


def parse_named_objects(answer: str, style: MarkStyle = "number") -> list[NamedObject]:
    """Read the list format of the ``moved_rigid_bodies`` prompts: one object per line,
    ``- <name>: <description>`` (also ``*``, ``\u2022`` or ``1.`` bullets, `` - `` instead
    of the colon, ``**bold**`` names and leading marks ``- [1][2] red mug: ...``). This
    is the toolkit's one parser for that answer (the VLM -> YOLOE path of
    ``vlm_adapters`` uses it too).

    The answer is read after :func:`repair_text`. Names are lower-cased and stripped
    of marks, markdown and a leading article; lines
    naming nothing (``- none: ...``), names of more than six words and repeated names
    are skipped; lines out of the format are ignored.

    Returns:
        One :class:`NamedObject` per object line, in order; names suit YOLOE
        ``set_classes``.

    Example:
        >>> [o.name for o in parse_named_objects("- **The Red Mug**: slid left\\n* lid - rotated")]
        ['red mug', 'lid']
    """
    if not isinstance(answer, str):
        raise TypeError(f"answer must be a str, got {type(answer).__name__}")
    answer = repair_text(answer)
    out: list[NamedObject] = []
    seen: set[str] = set()
    for line in answer.splitlines():
        m = _LINE.match(line)
        if not m:
            continue
        head = m.group("head")
        marks = tuple(t for t, _, _ in find_citations(head, style))
        name = re.sub(rf"{_OPEN}[^\]\uff3d\u3011\u3015]*{_CLOSE}|{_ROPEN}[^)\uff09]*{_RCLOSE}"
                      rf"|{_OPEN}|{_CLOSE}|{_ROPEN}|{_RCLOSE}|[*_`\"']", " ", head)
        name = _ARTICLE.sub("", " ".join(_CONTROL.sub(" ", name).split()).strip(" .,;:-").lower())
        if not name or name in _NONE_NAMES or len(name.split()) > _MAX_NAME_WORDS or name in seen:
            continue
        seen.add(name)
        out.append(NamedObject(name, m.group("desc").strip("*").strip(), marks))
    return out
