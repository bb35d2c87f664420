"""Which VLM answers questions in the demos: the stub, a local model folder or an endpoint."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from somprompt import MarkRegistry

__all__ = ["VLMError", "check_vlm_spec", "make_vlm", "stub_answer", "vlm_spec_help"]

#: transformers ``model_type`` (config.json) -> ``vlm_adapters.load_vlm`` kind
_MODEL_TYPES = {"qwen2_5_vl": "qwen2.5-vl", "internvl": "internvl", "video_llama_3": "videollama3"}
#: kinds whose checkpoints exist only as remote code (transformers runs Python files of the
#: checkpoint folder: ``trust_remote_code``). Naming one in the spec is the opt-in, so it
#: must name a local folder, whose code the user can read, never a hub id to download.
_REMOTE_CODE_KINDS = {"internvideo2.5"}


class VLMError(RuntimeError):
    """A VLM could not be loaded or did not answer (one-line message for the user)."""


def vlm_spec_help() -> str:
    """The VLM specs :func:`make_vlm` accepts, in one line."""
    return ("stub (default, scripted: does not look at the video), stub:TEXT, a local model folder "
            "(Qwen2.5-VL, InternVL or VideoLLaMA3 in transformers format), KIND:PATH "
            "(qwen2.5-vl, internvl, videollama3, internvideo2.5: this one runs the Python files "
            "of its folder), openai:URL@MODEL (an OpenAI-compatible server such as vLLM)")


def stub_answer(label_maps: Sequence[np.ndarray]) -> str:
    """What the default stub says: it cites the largest MotionBit of the last frame.

    ``label_maps``: the (H, W) integer label maps of the video, in order (mark numbers
    are given in order of first appearance, as GroundedVQA does).
    """
    if isinstance(label_maps, (str, bytes, np.ndarray)) or not isinstance(label_maps, Sequence) or not label_maps:
        # else IndexError (an empty list) or "'NoneType' object is not subscriptable"
        raise ValueError(f"label_maps must be a non-empty list of (H, W) label maps, got "
                         f"{type(label_maps).__name__} {label_maps!r:.40}")
    last = np.asarray(label_maps[-1])
    ids, counts = np.unique(last[last > 0], return_counts=True)
    if len(ids) == 0:
        return "Stub VLM (scripted, it does not look at the video): no MotionBit is marked."
    registry = MarkRegistry.from_label_maps(label_maps)
    mark = registry.text(int(ids[np.argmax(counts)]))
    return (f"Stub VLM (scripted, it does not look at the video): the largest moving body "
            f"is [{mark}].")


def _kind_of_folder(folder: Path) -> str:
    config = folder / "config.json"
    try:
        model_type = json.loads(config.read_text()).get("model_type", "")
    except (OSError, ValueError) as exc:
        raise VLMError(f"{folder} is not a transformers model folder (cannot read config.json: {exc})") from None
    if model_type not in _MODEL_TYPES:
        raise VLMError(f"{folder}: model_type {model_type!r} is not supported; use one of "
                       f"{', '.join(sorted(_MODEL_TYPES))} or a KIND:PATH spec")
    return _MODEL_TYPES[model_type]


def make_vlm(spec: str = "stub", *, stub_text: str | None = None, timeout: float = 120.0) -> Any:
    """Build the VLM named by ``spec`` (see :func:`vlm_spec_help`).

    Args:
        spec: ``"stub"``, ``"stub:TEXT"``, a local model folder, ``"KIND:PATH"`` or
            ``"openai:URL@MODEL"``.
        stub_text: what the plain ``"stub"`` answers (default: a fixed sentence).
        timeout: seconds an endpoint may take to answer.

    Returns:
        An object with ``generate(frames, prompt, system=None) -> str``.

    ``internvideo2.5:FOLDER`` loads with transformers' ``trust_remote_code=True``: the
    checkpoint exists only as remote code, so the Python files in FOLDER run; naming that
    kind with a local folder is the opt-in (a hub id is refused: nothing is downloaded
    and run unread).

    Raises:
        VLMError: the spec is malformed, the folder is not a supported model, or loading
            failed (the message says why in one line).
    """
    from vlm_adapters import OpenAICompatibleVLM, StubVLM
    from vlm_adapters.plugin import load_vlm, parse_vlm_spec

    spec = _resolve(spec)
    if spec.lower() == "stub":
        return StubVLM(stub_text or "Stub VLM (scripted, it does not look at the video).")
    try:
        kind, arg = parse_vlm_spec(spec)
        if kind == "openai":
            url, at, model = arg.rpartition("@")
            if not at or not url or not model:
                raise ValueError(f"use openai:URL@MODEL, got {spec!r}")
            return OpenAICompatibleVLM(url, model, timeout=timeout)
        if kind in _REMOTE_CODE_KINDS:
            _check_remote_code_folder(kind, arg)
            return load_vlm(spec, trust_remote_code=True)
        return load_vlm(spec)
    except Exception as exc:  # any loader failure becomes one readable line
        raise _load_error(spec, exc) from exc


def check_vlm_spec(spec: str) -> None:
    """Check a spec of :func:`make_vlm` without loading anything: its form, that the model
    folder or checkpoint exists (a local folder for ``internvideo2.5:``, whose code runs),
    that an endpoint's URL is well formed.

    Raises:
        VLMError: what is wrong, in one line.
    """
    from vlm_adapters.plugin import check_vlm_files, parse_vlm_spec

    spec = _resolve(spec)
    if spec.lower() == "stub":
        return
    try:
        kind, arg = parse_vlm_spec(spec)
        check_vlm_files(kind, arg)
        if kind in _REMOTE_CODE_KINDS:
            _check_remote_code_folder(kind, arg)
    except Exception as exc:
        raise _load_error(spec, exc) from exc


def _check_remote_code_folder(kind: str, arg: str) -> None:
    """A remote-code kind runs the code of a local folder only (ValueError otherwise)."""
    if not os.path.isdir(os.path.expanduser(arg)):
        raise ValueError(f"{kind} checkpoints run their own Python code, so give the local folder that "
                         f"holds it (read its .py files first), e.g. one made with `huggingface-cli "
                         f"download OpenGVLab/InternVideo2_5_Chat_8B --local-dir DIR`; {arg!r} is not a folder")


def _resolve(spec: str | None) -> str:
    """The spec stripped ("" -> "stub"), a model folder as ``KIND:FOLDER``."""
    if spec is not None and not isinstance(spec, str):
        raise VLMError(f"a VLM spec is a string ({vlm_spec_help()}), got {type(spec).__name__} {spec!r:.40}")
    spec = (spec or "").strip() or "stub"
    expanded = os.path.expanduser(spec)
    if spec.lower() != "stub" and os.path.isdir(expanded):
        spec = f"{_kind_of_folder(Path(expanded))}:{expanded}"
    return spec


def _load_error(spec: str, exc: Exception) -> VLMError:
    from vlm_adapters.plugin import METHOD_NAME

    msg = " ".join(str(exc).split()) or type(exc).__name__
    msg = msg.removeprefix(f"{METHOD_NAME} option 'vlm': ")  # the benchmark's wording, not ours
    return VLMError(f"could not load the VLM {spec!r}: {msg}")
