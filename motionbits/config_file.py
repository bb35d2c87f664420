"""A :class:`MotionBitsConfig` from a TOML or JSON file (``motionbits segment --config``).

The file holds any of the config's fields at the top level, e.g. ``n_nodes = 2500`` in
TOML or ``{"n_nodes": 2500}`` in JSON; fields left out keep their defaults. The
``summary.json`` that ``motionbits segment`` writes is accepted too (its ``"config"``
entry is read), so a run can be repeated from its summary.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
from pathlib import Path
from typing import Any, Mapping

from motionbits.config import MotionBitsConfig

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, from PyPI
    import tomli as tomllib

__all__ = ["config_from_dict", "load_config"]

_TYPES = {"int": int, "float": float, "bool": bool, "str": str}


def config_from_dict(values: Mapping[str, Any], *, source: str = "config") -> MotionBitsConfig:
    """A config with the given fields set (others at their defaults).

    Raises:
        ValueError: an unknown field, a value of the wrong type, or a value the config
            refuses (the message names the field).
    """
    if not isinstance(values, Mapping):  # else "'NoneType' object is not iterable"
        raise TypeError(f"{source}: values must be a mapping of MotionBitsConfig fields, got "
                        f"{type(values).__name__} {values!r:.40}")
    fields = {f.name: f for f in dataclasses.fields(MotionBitsConfig)}
    unknown = sorted(map(str, set(values) - set(fields)))  # {1: 2}: join's "expected str instance"
    if unknown:
        raise ValueError(f"{source}: unknown MotionBitsConfig field(s) {', '.join(unknown)}; "
                         f"valid fields: {', '.join(fields)}")
    checked = {}
    for name, value in values.items():
        want = _TYPES.get(fields[name].type, object)  # other types: the config checks them
        ok = isinstance(value, want) and not (want in (int, float) and isinstance(value, bool))
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            ok, value = True, float(value)
        if not ok:
            raise ValueError(f"{source}: {name} must be {fields[name].type}, got {value!r}")
        checked[name] = value
    return MotionBitsConfig(**checked)


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's dict; ValueError for a key given twice (else the last one won)."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"key {key!r} is given twice")
        out[key] = value
    return out


def load_config(path: "str | os.PathLike", **overrides: Any) -> MotionBitsConfig:
    """Read a config from ``path`` (``.toml`` or ``.json``, UTF-8 with or without a
    byte-order mark; a key given twice is an error), then apply ``overrides``.

    Example:
        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "fast.toml"
        >>> _ = p.write_text("n_nodes = 2500\\nmcl_inflation = 1.2\\n")
        >>> c = load_config(p, max_side=320)
        >>> c.n_nodes, c.mcl_inflation, c.max_side, c.k_neighbors
        (2500, 1.2, 320, 5)
    """
    if not isinstance(path, (str, os.PathLike)):  # else "expected str, bytes or os.PathLike object"
        raise TypeError(f"config path must be a str or pathlib.Path, got {type(path).__name__} {path!r:.40}")
    if not os.fspath(path).strip():  # Path("") is ".": "config file . is a folder"
        raise ValueError(f"config path is empty ({os.fspath(path)!r}); pass a .toml or .json file")
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"config file {path} does not exist")
    if path.is_dir():
        raise IsADirectoryError(f"config file {path} is a folder; pass a .toml or .json file "
                                "(or an earlier run's summary.json)")
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise ValueError(f"config file {path} must end in .toml or .json")
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark (Notepad) is no syntax error
    except UnicodeDecodeError:
        raise ValueError(f"config file {path} is not a text file (not UTF-8); "
                         f"it must hold {suffix[1:].upper()}") from None
    try:
        data = tomllib.loads(text) if suffix == ".toml" else json.loads(
            text, object_pairs_hook=_unique_keys)
    except (tomllib.TOMLDecodeError, ValueError, RecursionError) as exc:
        # ValueError: also JSON's 5000-digit numbers ("Exceeds the limit (4300 digits)") and
        # repeated keys; RecursionError: 100,000 nested brackets
        why = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise ValueError(f"config file {path} is not valid {path.suffix[1:].upper()}: {why}") from None
    if not isinstance(data, dict):
        raise ValueError(f"config file {path} must hold a table/object of MotionBitsConfig fields")
    if isinstance(data.get("config"), dict):  # a summary.json of `motionbits segment`
        data = data["config"]
    return config_from_dict({**data, **overrides}, source=str(path))
