"""From a VLM's answer to the short noun phrases an open-vocabulary detector is prompted with.

The paper (section 6.1) asks every VLM "What rigid bodies or parts have moved in the video?
Describe each in detail." together with an output-format specification, so that the answer
can be handed to YOLOE. `MOVED_OBJECTS_PROMPT` is the toolkit's one prompt for it (the
``moved_rigid_bodies`` template of ``somprompt``): one object per line,
``- <short noun phrase>: <description>``.

`somprompt.parse_named_objects` reads that format (the one parser, shared with the
set-of-mark prompts); `extract_noun_phrases` is the fallback for free text (a heuristic
without an NLP model); `phrases_from_answer` tries the first, then the second.
"""
from __future__ import annotations

import re

from motionbits.frames import whole_number
from somprompt import load_prompt, parse_named_objects, repair_text

__all__ = [
    "PAPER_QUESTION",
    "MOVED_OBJECTS_PROMPT",
    "extract_noun_phrases",
    "phrases_from_answer",
]

#: The question of the paper's VLM baselines (section 6.1), verbatim.
PAPER_QUESTION = "What rigid bodies or parts have moved in the video? Describe each in detail."

#: Paper question + format specification: the default prompt of the VLM -> YOLOE baseline
#: (template ``moved_rigid_bodies``).
MOVED_OBJECTS_PROMPT = load_prompt("moved_rigid_bodies")

# "- none: nothing moved", "None.", "* nothing"
_SAYS_NONE = re.compile(r"^\W*(?:none|nothing)\b", re.IGNORECASE | re.MULTILINE)


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
    if not isinstance(text, str):  # else re's "expected string or bytes-like object"
        raise TypeError(f"text must be a str, got {type(text).__name__}; the VLM produced no answer")
    if whole_number("max_words", max_words) < 1:  # else 0 and -1 found nothing, None a TypeError of '<'
        raise ValueError(f"max_words must be >= 1, got {max_words!r}")
    phrases: list[str] = []
    seen: set[str] = set()
    for clause in re.split(r"[.,;:!?()\n\[\]]+", text):
        words = re.findall(r"[^\W\d_](?:[^\W\d_]|['-])*", clause)  # letters of any script ("café", not "caf")
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
    text = repair_text(text)  # a lone surrogate would reach the detector's text encoder
    names = [obj.name for obj in parse_named_objects(text)]
    if not names and not _SAYS_NONE.search(text):
        names = extract_noun_phrases(text)
    return names if max_phrases is None else names[:max_phrases]
