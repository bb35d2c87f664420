"""Prompt templates: the repository's ``prompts/`` folder, installed as package data.

Templates are plain ``.txt`` files using :class:`string.Template` syntax (``${name}``,
``$$`` for a literal dollar). The repository's top-level ``prompts/`` folder is their
source; ``somprompt/_prompts`` links to it and wheels carry it as package data, read with
:mod:`importlib.resources`. Every function takes a ``prompts_dir`` to use another folder.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path
from string import Template
from typing import Iterable

from .registry import MarkRegistry, check_registry, whole_ids

__all__ = [
    "PromptError",
    "default_prompts_dir",
    "list_prompts",
    "prompt_variables",
    "load_prompt",
    "format_mark_list",
    "mark_prompt_variables",
]


class PromptError(ValueError):
    """A template is unknown, unreadable, malformed, or got the wrong variables."""


def default_prompts_dir() -> Path:
    """The templates installed with ``somprompt`` (package data ``somprompt/_prompts``; in
    a source checkout, a link to ``<repo>/prompts``)."""
    return Path(str(resources.files(__package__).joinpath("_prompts")))


def _dir(prompts_dir: "str | os.PathLike | None") -> Path:
    if prompts_dir is not None and not isinstance(prompts_dir, (str, os.PathLike)):
        # else pathlib's "expected str, bytes or os.PathLike object, not int"
        raise TypeError(f"prompts_dir must be a folder path (str or pathlib.Path) or None, got "
                        f"{type(prompts_dir).__name__} {prompts_dir!r:.40}")
    if prompts_dir is not None and not os.fspath(prompts_dir).strip():  # Path("") is "."
        raise PromptError(f"prompts_dir is empty ({os.fspath(prompts_dir)!r}); pass a folder of "
                          ".txt templates or None for the installed ones")
    d = Path(prompts_dir) if prompts_dir is not None else default_prompts_dir()
    if not d.is_dir():
        what = "is a file, not a folder" if d.exists() else "does not exist"
        raise PromptError(
            f"prompt folder {d} {what}; pass prompts_dir=<folder of .txt templates> "
            "(the default is the templates installed with somprompt)"
        )
    return d


def list_prompts(prompts_dir: "str | os.PathLike | None" = None) -> list[str]:
    """Names of the available templates (file names without ``.txt``), sorted."""
    return sorted(p.stem for p in _dir(prompts_dir).glob("*.txt") if p.is_file())


def _read(name: str, prompts_dir: "str | os.PathLike | None") -> tuple[Template, Path]:
    if not isinstance(name, str) or not name or "/" in name or "\\" in name or name.startswith("."):
        raise PromptError(f"template name must be a plain file stem such as 'som_vqa', got {name!r}")
    d = _dir(prompts_dir)
    path = d / f"{name.removesuffix('.txt')}.txt"
    if not path.is_file():
        raise PromptError(
            f"unknown prompt template {name!r} in {d}; available: {', '.join(list_prompts(d)) or '(none)'}"
        )
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark is no prompt text
    except UnicodeDecodeError as exc:  # else a UnicodeDecodeError that names no file
        raise PromptError(f"prompt template {path} is not UTF-8 text ({exc.reason} at byte "
                          f"{exc.start}); save it as UTF-8") from None
    if not text.strip():  # else an empty prompt was sent to the VLM
        raise PromptError(f"prompt template {path} is empty")
    return Template(text), path


def _identifiers(template: Template, path: Path) -> list[str]:
    names: list[str] = []
    for m in template.pattern.finditer(template.template):
        if m.group("invalid") is not None:
            line = template.template.count("\n", 0, m.start("invalid")) + 1
            raise PromptError(
                f"template {path.name} line {line}: a '$' that starts no variable; "
                "write variables as ${name} and a literal dollar as $$"
            )
        name = m.group("named") or m.group("braced")
        if name and name not in names:
            names.append(name)
    return names


def prompt_variables(name: str, prompts_dir: "str | os.PathLike | None" = None) -> list[str]:
    """Variables that template ``name`` needs, in order of first use."""
    template, path = _read(name, prompts_dir)
    return _identifiers(template, path)


def load_prompt(name: str, /, *, prompts_dir: "str | os.PathLike | None" = None, **variables: object) -> str:
    """Render template ``name`` with ``variables``.

    Args:
        name: template name, e.g. ``"som_vqa"`` (see :func:`list_prompts`).
        prompts_dir: folder of templates (default :func:`default_prompts_dir`).
        **variables: one value per variable of the template (converted with ``str``).

    Returns:
        The prompt text, trailing whitespace removed.

    Raises:
        PromptError: unknown template, a variable missing, or a variable the template
            does not use (the message names them and lists the template's variables).

    Example:
        >>> text = load_prompt("som_vqa", num_marks=2, mark_list="[1], [2]",
        ...                    question="Which object moved first?", cite_example="[1]")
        >>> "[1], [2]" in text
        True
    """
    template, path = _read(name, prompts_dir)
    needed = _identifiers(template, path)
    missing = [v for v in needed if v not in variables]
    extra = sorted(v for v in variables if v not in needed)
    uses = ", ".join(needed) if needed else "no variables"
    if missing:
        raise PromptError(
            f"prompt template {name!r} needs variable(s) {', '.join(missing)} (it uses: {uses})"
        )
    if extra:
        raise PromptError(
            f"prompt template {name!r} does not use variable(s) {', '.join(extra)} (it uses: {uses})"
        )
    return template.substitute({k: str(v) for k, v in variables.items()}).rstrip()


def format_mark_list(registry: MarkRegistry, ids: Iterable[int] | None = None) -> str:
    """``"[1], [2], [5]"``: the marks of ``ids`` (default: all registered), by number, each once.

    Raises:
        TypeError: ``registry`` is not a MarkRegistry, or ``ids`` not an iterable of whole numbers.
        KeyError: an id that is not registered.
    """
    check_registry(registry)
    ids = registry.ids if ids is None else list(dict.fromkeys(whole_ids(ids, "ids")))  # [3, 3]: one mark
    texts = [registry.text(i) for i in sorted(ids, key=registry.number)]
    return ", ".join(f"[{t}]" for t in texts)


def mark_prompt_variables(registry: MarkRegistry, ids: Iterable[int] | None = None) -> dict[str, str]:
    """``num_marks``, ``mark_list`` and ``cite_example`` for the marks of ``ids``
    (default: all registered). ``cite_example`` shows the first mark, or ``[1]`` /
    ``[a]`` when there are none."""
    check_registry(registry)
    ids = registry.ids if ids is None else list(dict.fromkeys(whole_ids(ids, "ids")))  # [3, 3]: 1 mark
    ordered = sorted(ids, key=registry.number)
    first = registry.text(ordered[0]) if ordered else ("1" if registry.style == "number" else "a")
    return {
        "num_marks": str(len(ordered)),
        "mark_list": format_mark_list(registry, ordered) if ordered else "(none)",
        "cite_example": f"[{first}]",
    }
