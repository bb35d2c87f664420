"""From a VLM's answer to the short noun phrases an open-vocabulary detector is prompted with.

The paper (section 6.1) asks every VLM "What rigid bodies or parts have moved in the video?
Describe each in detail." together with an output-format specification, so that the answer
can be handed to YOLOE. `MOVED_OBJECTS_PROMPT` is that prompt with our format
specification: one object per line, ``- <short noun phrase>: <description>``.

`parse_object_list` reads that format; `extract_noun_phrases` is the fallback for free
text (a heuristic without an NLP model); `phrases_from_answer` tries the first, then the
second. Pure Python: no dependencies.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = [
    "PAPER_QUESTION",
    "OUTPUT_FORMAT",
    "MOVED_OBJECTS_PROMPT",
    "ObjectMention",
    "parse_object_list",
    "extract_noun_phrases",
    "phrases_from_answer",
]

#: The question of the paper's VLM baselines (section 6.1), verbatim.
PAPER_QUESTION = "What rigid bodies or parts have moved in the video? Describe each in detail."

#: The output-format specification that makes the answer machine-readable for YOLOE.
OUTPUT_FORMAT = (
    "Answer with one line per moved rigid body or part, and nothing else, in this format:\n"
    "- <short noun phrase>: <description>\n"
    "The short noun phrase names the object in 1-4 words a detector can find "
    '(for example "red mug", "drawer", "laptop lid"); the description says how it looks and moves. '
    "If nothing moved, answer: - none: nothing moved"
)

#: Paper question + format specification: the default prompt of the VLM -> YOLOE baseline.
MOVED_OBJECTS_PROMPT = PAPER_QUESTION + "\n\n" + OUTPUT_FORMAT

_NONE_NAMES = {"none", "nothing", "no object", "no objects", "n/a", "na", "null"}

# "- name: description", "* name - description", "1. name: description", "**name**: description"
_LINE = re.compile(
    r"""^\s*(?:[-*\u2022\u2013]|\d+[.)])\s+   # bullet or number
        (?P<name>[^:\n]{1,80}?)\s*            # short name
        (?::|\s[-\u2013\u2014]\s)\s*          # ':' or ' - ' separator
        (?P<desc>.*)$""",
    re.VERBOSE,
)
_MARKUP = re.compile(r"[*_`\"'\[\]()]+")
_ARTICLE = re.compile(r"^(?:the|a|an|one|two|three|some|this|that|these|those)\s+", re.IGNORECASE)


@dataclass(frozen=True)
class ObjectMention:
    """One object named in a VLM answer: the detector prompt and the VLM's description."""

    name: str
    description: str = ""


def _clean_name(name: str) -> str:
    name = _MARKUP.sub(" ", name)
    name = re.sub(r"\s+", " ", name).strip(" .,;:-").lower()
    name = _ARTICLE.sub("", name)
    return name


def parse_object_list(text: str) -> list[ObjectMention]:
    """Objects from an answer in the ``- <short noun phrase>: <description>`` format.

    Lines not in the format are ignored; "- none: ..." lines are dropped; names are
    lower-cased, stripped of markdown and leading articles, and de-duplicated in order.

    Returns:
        the mentions in answer order (empty when no line matches the format).
    """
    out: list[ObjectMention] = []
    seen: set[str] = set()
    for line in text.splitlines():
        m = _LINE.match(line)
        if not m:
            continue
        name = _clean_name(m.group("name"))
        if not name or name in _NONE_NAMES or len(name.split()) > 6:
            continue
        if name not in seen:
            seen.add(name)
            out.append(ObjectMention(name, m.group("desc").strip()))
    return out


# --------------------------------------------------------------------------- free text

# Words that end a noun phrase or cannot be part of one (closed classes + frequent verbs).
_STOP = set(
    """
    a an the this that these those it its it's they them their there here what which who whom whose
    is are was were be been being has have had do does did will would can could should may might must
    and or but nor so yet if then than as of in on at to from by with without into onto over under
    above below between through during after before while when where why how not no also very just only
    each every both all any some other another such own same more most less least much many few
    i you he she we me him her us my your our his
    moved moves moving move rotated rotates rotating rotate slid slides sliding slide pushed pushes
    pushing push pulled pulls pulling pull opened opens opening open closed closes closing close
    lifted lifts lifting lift dropped drops dropping fell falls falling turned turns turning shifted
    shifts shifting tilted tilts tilting placed places placing picked picks picking grasped grasps
    grasping stacked stacks stacking appears appear appeared seems seem seemed remains remain remained
    stays stay stayed looks look looked describe described video frame frames scene image part parts
    body bodies object objects rigid static stationary visible slightly clearly left right top bottom
    side towards toward away up down around along across itself while
    first second third last final next together
    """.split()
)
# Generic heads that are not useful detector prompts on their own.
_GENERIC = {"thing", "things", "item", "items", "one", "ones", "way", "time", "motion", "movement", "position"}


def extract_noun_phrases(text: str, max_words: int = 3) -> list[str]:
    """Noun-phrase-like word runs from free text, without an NLP model.

    The heuristic: split into clauses at punctuation; in each clause, a phrase is a run of
    up to `max_words` words that follows an article or determiner ("the", "a", ...),
    stopping at the first function word or common verb. Runs are lower-cased and
    de-duplicated in order. It is meant for answers that ignored the requested format;
    it will miss phrases without a determiner and keep some non-objects.

    Example:
        >>> extract_noun_phrases("The red block slid left and the drawer opened.")
        ['red block', 'drawer']
    """
    phrases: list[str] = []
    seen: set[str] = set()
    for clause in re.split(r"[.,;:!?()\n\[\]]+", text):
        words = re.findall(r"[A-Za-z][A-Za-z'-]*", clause)
        i = 0
        while i < len(words):
            if words[i].lower() in {"the", "a", "an", "one", "two", "three", "its", "their"}:
                run: list[str] = []
                j = i + 1
                while j < len(words) and words[j].lower() not in _STOP and len(run) < max_words:
                    run.append(words[j].lower())
                    j += 1
                phrase = " ".join(run)
                if run and run[-1] not in _GENERIC and phrase not in seen:
                    seen.add(phrase)
                    phrases.append(phrase)
                i = max(j, i + 1)
            else:
                i += 1
    return phrases


def phrases_from_answer(text: str, max_phrases: int | None = 16) -> list[str]:
    """Detector prompts from a VLM answer: the formatted list if present, else free-text phrases.

    Args:
        text: the VLM's answer.
        max_phrases: keep at most this many (None: all).

    Returns:
        short lower-case noun phrases, in answer order, no duplicates. An answer in the
        requested format that lists only "none" gives an empty list (nothing moved).

    Raises:
        TypeError: ``text`` is not a string (e.g. None: the VLM produced no answer).
        ValueError: ``max_phrases`` is not a positive integer or None.
    """
    if not isinstance(text, str):
        raise TypeError(f"the answer must be a str, got {type(text).__name__}"
                        + ("; the VLM produced no answer" if text is None else ""))
    if max_phrases is not None and (isinstance(max_phrases, bool) or not isinstance(max_phrases, int)
                                    or max_phrases < 1):
        raise ValueError(f"max_phrases must be a positive integer or None, got {max_phrases!r}")
    mentions = parse_object_list(text)
    if mentions:
        names = [m.name for m in mentions]
    elif any(_LINE.match(line) and _clean_name(_LINE.match(line).group("name")) in _NONE_NAMES
             for line in text.splitlines()):
        names = []
    else:
        names = extract_noun_phrases(text)
    return names if max_phrases is None else names[:max_phrases]
