"""Answers -> cited marks -> masks, on realistic VLM prose and on arbitrary text."""

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from somprompt import MarkRegistry, find_citations, parse_answer, parse_named_objects, repair_text

# marks 1..6 shown; object ids are not the mark numbers (ids 11..16)
REG = MarkRegistry()
REG.register([11, 12, 13, 14, 15, 16])
LETTERS = MarkRegistry("letter")
LETTERS.register([11, 12, 13, 14, 15, 16])

# (answer, cited marks in order of first mention, unknown marks)
NUMBER_TABLE = [
    ("The red cup [2] was slid to the left by the hand, while [5] stayed still.", [2, 5], []),
    ("In the video, the robot gripper [1] grasps the blue block [3] and places it on the tray [4].",
     [1, 3, 4], []),
    ("Objects [3, 5] moved together as one rigid body; [1] moved on its own.", [3, 5, 1], []),
    ("The drawer front [2][4] and its slider [6] moved.", [2, 4, 6], []),
    ("Mark 3 is the kettle. It is lifted at around 3 o'clock position and tilted by 45 degrees.", [3], []),
    ("The kettle (mark #4) was lifted, and the mug (#6) did not move.", [4, 6], []),
    ("Object 1 and object 2 were pushed. There were 3 cups in total, filmed in 2023.", [1, 2], []),
    ("**Answer:** [5]\n\nThe robot should grasp [5] first because it is the largest free object, "
     "unlike [2] which is under [3].", [5, 2, 3], []),
    ("1. The cup [2] moved right.\n2. The lid [7] rotated.\n3. The spoon did not move.", [2], ["7"]),
    ("The hand moved the objects labelled 1, 2 and 3 but I cannot see mark 9.", [], ["9"]),
    ("Regions 1, 4 and 6 moved; region 2 stayed.", [1, 4, 6, 2], []),
    ("I could not identify any moving object in these frames.", [], []),
    ("The box moved 3.5 cm and then 2 cm. Object 3 cm to its left did not move.", [], []),
    ("- [1] robot gripper: closes on the block\n- [3] [5] glued block: red and blue pieces lifted together",
     [1, 3, 5], []),
    ("The answer is [mark 2]. Nothing else (0 objects) moved.", [2], []),
    ("Color #3cb44b marks the cup, see https://example.com/a#3 for details; &#39;cup&#39;", [], []),
    ("The lid (2) and the pot (3) moved (by about 10 cm).", [2, 3], []),
    ("[2][2] and again [2]: the same object", [2], []),
    ("The marked item [12] is not there, but [01] is.", [1], ["12"]),
    # Chinese answers (Qwen): full-width and CJK brackets, ideographic separators
    ("杯子【3】被移动了，盖子［5］没有动。", [3, 5], []),
    ("移动的物体是【2、4】和（6）。", [2, 4, 6], []),
    ("刚体〔1〕与【mark 3，5】一起移动", [1, 3, 5], []),
]


@pytest.mark.parametrize("answer, cited, unknown", NUMBER_TABLE)
def test_realistic_answers_number_marks(answer, cited, unknown):
    p = parse_answer(answer, REG)
    assert p.ids == [10 + n for n in cited]
    assert p.unknown == unknown


LETTER_TABLE = [
    ("The cup [a] moved to the left of the bowl [c].", [1, 3], []),
    ("Marks [a, b] are one rigid body; [d][f] are two parts of the drawer.", [1, 2, 4, 6], []),
    ("Object A was lifted first, then object e.", [1, 5], []),
    ("The robot grasps a block. It marks a turning point for the task.", [], []),
    ("It is labelled [z] but that mark does not exist; [3] is not a letter.", [], ["z"]),
    ("移动的是【a】和（c）", [1, 3], []),
]


@pytest.mark.parametrize("answer, cited, unknown", LETTER_TABLE)
def test_realistic_answers_letter_marks(answer, cited, unknown):
    p = parse_answer(answer, LETTERS)
    assert p.ids == [10 + n for n in cited]
    assert p.unknown == unknown


def test_citation_spans_point_at_the_marks():
    answer = "First [3], then object 12 and #4."
    texts = [(t, answer[s:e]) for t, s, e in find_citations(answer)]
    assert texts == [("3", "3"), ("12", "12"), ("4", "4")]


def test_masks_come_from_the_label_map():
    labels = np.zeros((10, 10), np.int32)
    labels[0:3, 0:3] = 11
    labels[5:10, 5:10] = 13
    p = parse_answer("The block [3] hit the cup [1]; [2] and [9] too.", REG, labels)
    assert p.ids == [13, 11, 12]
    assert p.unknown == ["9"]
    assert sorted(p.masks) == [11, 13]
    assert p.missing == [12]  # a known mark that is not in this frame
    assert p.masks[13].sum() == 25 and p.masks[13].dtype == bool
    combined = p.label_map
    assert set(np.unique(combined)) == {0, 11, 13}
    assert np.array_equal(p.mask, (labels == 11) | (labels == 13))


def test_without_registry_numbers_are_ids():
    labels = np.zeros((6, 6), np.int32)
    labels[0, 0] = 3
    labels[5, 5] = 8
    p = parse_answer("Objects [8] and [3] moved, not [4].", labels=labels)
    assert p.ids == [8, 3] and p.unknown == ["4"]
    assert parse_answer("[4] and [100]", marks=[4, 5]).ids == [4]
    assert parse_answer("[4] and [100]").ids == [4, 100]  # nothing known: anything goes


def test_non_string_answers_fail_clearly():
    with pytest.raises(TypeError, match="str"):
        parse_answer(None, REG)
    with pytest.raises(TypeError, match="str"):
        parse_answer(b"[1]", REG)


def test_bad_label_map_fails_clearly():
    with pytest.raises(TypeError, match="integer"):
        parse_answer("[1]", REG, np.zeros((4, 4), np.float64))


def test_named_objects_for_yoloe():
    answer = """Here is what moved:
- **Red mug**: a glossy red mug, slid 10 cm to the left.
- The drawer front: wooden panel, pulled out.
* robot gripper: the two-finger gripper, closed.
1. blue block: small cube, lifted.
- red mug: mentioned again
This line has a colon: but no bullet.
- none: nothing moved
"""
    objs = parse_named_objects(answer)
    assert [o.name for o in objs] == ["red mug", "drawer front", "robot gripper", "blue block"]
    assert objs[0].description == "a glossy red mug, slid 10 cm to the left."
    som = parse_named_objects("- [1][3] glued block: moved as one\n- [2] lid: rotated")
    assert [(o.name, o.marks) for o in som] == [("glued block", ("1", "3")), ("lid", ("2",))]
    cjk = parse_named_objects("- 【1】【3】 glued block: moved as one\n- （2） lid: rotated")
    assert [(o.name, o.marks) for o in cjk] == [("glued block", ("1", "3")), ("lid", ("2",))]


def test_lone_surrogates_are_replaced_so_the_answer_encodes():
    """A lone UTF-16 surrogate (a JSON "\\ud800" escape, surrogateescape decoding) passed
    through and crashed whoever encoded the answer (UTF-8, json.dumps(ensure_ascii=False))."""
    text = "The cup [1] \ud800moved; object 2 stayed\udcff. Smile \ud83d\ude00 [3]"
    p = parse_answer(text, REG)
    assert p.ids == [11, 12, 13]
    assert p.answer == "The cup [1] \ufffdmoved; object 2 stayed\ufffd. Smile \U0001f600 [3]"
    json.dumps({"answer": p.answer}, ensure_ascii=False).encode("utf-8")
    assert [p.answer[c.start:c.end] for c in p.citations] == ["1", "2", "3"]  # spans in p.answer
    objs = parse_named_objects("- red \ud800mug: slid \udcff left")
    assert [(o.name, o.description) for o in objs] == [("red \ufffdmug", "slid \ufffd left")]
    assert repair_text("no surrogates [1]") == "no surrogates [1]"


@settings(max_examples=200, deadline=None)
@given(st.text(st.one_of(st.characters(min_codepoint=0xD800, max_codepoint=0xDFFF, codec=None,
                                       exclude_categories=()),
                        st.sampled_from("[]#123 abmark object-:\n"), st.characters()), max_size=200))
def test_parsed_text_always_encodes(text):
    p = parse_answer(text, REG)
    p.answer.encode("utf-8")
    for obj in parse_named_objects(text):
        (obj.name + obj.description).encode("utf-8")


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=400))
def test_parser_never_raises_and_results_are_consistent(text):
    for reg in (REG, LETTERS):
        p = parse_answer(text, reg)
        assert len(p.ids) == len(set(p.ids))
        assert all(i in reg for i in p.ids)
        assert all(reg.id_for_text(u) is None for u in p.unknown)
    parse_named_objects(text)


ANSWERISH = st.lists(
    st.one_of(
        st.sampled_from(["[", "]", "(", ")", "#", ",", " and ", "mark", "object", " ", "\n", ".", "&", ":"]),
        st.integers(0, 3000).map(str),
        st.text(alphabet="abcxyzABC ", max_size=5),
    ),
    max_size=40,
).map("".join)


@settings(max_examples=300, deadline=None)
@given(ANSWERISH)
def test_parser_never_raises_on_citation_like_noise(text):
    p = parse_answer(text, REG, np.zeros((4, 4), np.int32))
    assert p.masks == {} and set(p.missing) == set(p.ids)
    parse_answer(text, LETTERS)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=200), st.integers(1, 6), st.text(max_size=200))
def test_an_inserted_bracket_citation_is_always_found(before, n, after):
    p = parse_answer(f"{before} [{n}] {after}", REG)
    assert 10 + n in p.ids
