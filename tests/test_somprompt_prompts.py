"""Prompt templates: all render, strict variables, clear errors, override folder."""

from pathlib import Path

import pytest

from somprompt import (
    MarkRegistry,
    PromptError,
    default_prompts_dir,
    list_prompts,
    load_prompt,
    mark_prompt_variables,
    prompt_variables,
)

SAMPLE = {
    "num_marks": "3",
    "mark_list": "[1], [2], [3]",
    "cite_example": "[1]",
    "question": "Which object did the hand touch first?",
    "task": "stack all objects into a tower",
}


def test_prompts_dir_is_the_package_data_and_the_repository_folder():
    d = default_prompts_dir()
    assert d.is_dir() and d.name == "_prompts" and d.parent.name == "somprompt"
    repo = Path(__file__).resolve().parent.parent / "prompts"
    if repo.is_dir():  # source checkout: the package data is the repository's folder
        assert d.resolve() == repo.resolve()


def test_expected_templates_exist():
    names = set(list_prompts())
    assert {"moved_rigid_bodies", "som_vqa", "som_system", "som_grasp_first", "som_move_together",
            "som_interacted", "som_moved_rigid_bodies"} <= names


@pytest.mark.parametrize("name", list_prompts())
def test_every_template_renders(name):
    needed = prompt_variables(name)
    assert set(needed) <= set(SAMPLE), f"{name} uses a variable the test does not know: {needed}"
    text = load_prompt(name, **{k: SAMPLE[k] for k in needed})
    assert "$" not in text and text.strip()
    for k in needed:
        assert SAMPLE[k] in text


def test_paper_prompt_is_verbatim_with_an_output_format():
    text = load_prompt("moved_rigid_bodies")
    assert text.startswith("What rigid bodies or parts have moved in the video? Describe each in detail.")
    assert "- <name>: <description>" in text


def test_som_templates_ask_for_bracket_citations():
    for name in list_prompts():
        if name.startswith("som_"):
            vars_ = {k: SAMPLE[k] for k in prompt_variables(name)}
            assert "[1]" in load_prompt(name, **vars_), name


def test_missing_variable_is_named():
    with pytest.raises(PromptError, match=r"needs variable\(s\) question") as e:
        load_prompt("som_vqa", num_marks=2, mark_list="[1], [2]", cite_example="[1]")
    assert "it uses: num_marks, mark_list, question, cite_example" in str(e.value)


def test_unexpected_variable_is_named():
    with pytest.raises(PromptError, match="does not use variable.*colour"):
        load_prompt("moved_rigid_bodies", colour="red")


def test_unknown_template_lists_the_available_ones():
    with pytest.raises(PromptError, match="unknown prompt template 'nope'.*som_vqa"):
        load_prompt("nope")
    with pytest.raises(PromptError, match="plain file stem"):
        load_prompt("../etc/passwd")


def test_override_directory(tmp_path):
    (tmp_path / "greet.txt").write_text("Hello ${who}, it costs $$5 {not a variable} [1]\n")
    (tmp_path / "broken.txt").write_text("price: $5\n")
    assert list_prompts(tmp_path) == ["broken", "greet"]
    assert load_prompt("greet", prompts_dir=tmp_path, who="robot") == "Hello robot, it costs $5 {not a variable} [1]"
    with pytest.raises(PromptError, match="broken.txt line 1"):
        load_prompt("broken", prompts_dir=tmp_path)
    with pytest.raises(PromptError, match="does not exist"):
        list_prompts(tmp_path / "missing")


def test_mark_prompt_variables():
    reg = MarkRegistry()
    reg.register([10, 4, 7])
    v = mark_prompt_variables(reg, [7, 10])
    assert v == {"num_marks": "2", "mark_list": "[1], [3]", "cite_example": "[1]"}
    letters = MarkRegistry("letter")
    letters.register([5, 6])
    assert mark_prompt_variables(letters)["mark_list"] == "[a], [b]"
    assert mark_prompt_variables(MarkRegistry("letter"))["cite_example"] == "[a]"
