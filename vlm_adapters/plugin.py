"""The ``vlm-yoloe`` benchmark method: VLM answer -> YOLOE masks, built from string options.

``motionbits benchmark`` finds this factory through the entry point ``vlm-yoloe`` in the
group ``motionbits.methods`` (see pyproject.toml) and calls it with the command's
``--option vlm-yoloe.KEY=VALUE`` pairs, so every option arrives as a string::

    motionbits benchmark --data DIR --methods motionbits vlm-yoloe \\
        --option vlm-yoloe.vlm=qwen2.5-vl:/models/Qwen2.5-VL-7B-Instruct \\
        --option vlm-yoloe.yoloe=/models/yoloe-11l-seg.pt \\
        --option vlm-yoloe.text_encoder=/models/mobileclip_blt.ts

The core package ``motionbits`` never imports this module; the dependency goes one way.

VLM specs (`load_vlm`), ``KIND:ARGUMENT``:

=====================  ==========================================================
``qwen2.5-vl:PATH``     `Qwen2_5_VLAdapter` from a checkpoint folder
``videollama3:PATH``    `VideoLlama3Adapter` (transformers-format checkpoint)
``internvl:PATH``       `InternVLAdapter` (an InternVL ``-hf`` checkpoint)
``internvideo2.5:PATH`` `InternVideo25Adapter`; runs checkpoint code, so it also needs
                        the option ``trust_remote_code=true``
``openai:URL@MODEL``    `OpenAICompatibleVLM`, e.g. ``openai:http://localhost:8000/v1@Qwen/Qwen2.5-VL-7B-Instruct``
                        (API key from ``$OPENAI_API_KEY``)
``stub:TEXT``           `StubVLM` answering TEXT to every clip (``\\n`` in TEXT is a new line)
=====================  ==========================================================
"""
from __future__ import annotations

import inspect
import math
import os
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from motionbits.frames import whole_number

from .base import VLMAdapter, check_local_path, require
from .method import VLMYOLOEMethod
from .phrases import MOVED_OBJECTS_PROMPT, phrases_from_answer

__all__ = ["VLM_KINDS", "parse_vlm_spec", "check_vlm_files", "load_vlm", "load_embeddings", "vlm_yoloe_method"]

METHOD_NAME = "vlm-yoloe"

#: spec kind -> (adapter class name in `vlm_adapters`, what the argument is)
VLM_KINDS: dict[str, tuple[str, str]] = {
    "qwen2.5-vl": ("Qwen2_5_VLAdapter", "PATH"),
    "videollama3": ("VideoLlama3Adapter", "PATH"),
    "internvl": ("InternVLAdapter", "PATH"),
    "internvideo2.5": ("InternVideo25Adapter", "PATH"),
    "openai": ("OpenAICompatibleVLM", "URL@MODEL"),
    "stub": ("StubVLM", "TEXT"),
}

_SPEC_HELP = ", ".join(f"{k}:{arg}" for k, (_, arg) in VLM_KINDS.items())
_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


def _opt(key: str) -> str:
    return f"{METHOD_NAME} option '{key}'"


def parse_vlm_spec(spec: str) -> tuple[str, str]:
    """``"KIND:ARGUMENT"`` -> ``(kind, argument)``; the kind is checked, case-insensitive.

    Raises:
        ValueError: no ``:`` or an unknown kind (the message lists the valid forms).
    """
    kind, sep, arg = str(spec).partition(":")
    kind = kind.strip().lower()
    if not sep or kind not in VLM_KINDS:
        raise ValueError(f"{_opt('vlm')}: cannot read VLM spec {spec!r}; use one of {_SPEC_HELP}")
    if kind != "stub" and not arg.strip():
        raise ValueError(f"{_opt('vlm')}: {kind}: needs {VLM_KINDS[kind][1]}, got {spec!r}")
    return kind, arg if kind == "stub" else arg.strip()


def check_vlm_files(kind: str, arg: str) -> None:
    """Cheap checks before anything is loaded (missing checkpoint folder, malformed URL)."""
    if VLM_KINDS[kind][1] == "PATH":
        check_local_path(arg, what=f"{_opt('vlm')}: {VLM_KINDS[kind][0]} checkpoint")
    elif kind == "openai":
        url, at, model = arg.rpartition("@")
        if not at or not url or not model:
            raise ValueError(f"{_opt('vlm')}: use openai:URL@MODEL, e.g. "
                             f"openai:http://localhost:8000/v1@Qwen/Qwen2.5-VL-7B-Instruct; got 'openai:{arg}'")
        if not url.startswith(("http://", "https://")):
            raise ValueError(f"{_opt('vlm')}: the server URL must start with http:// or https://, got {url!r}")


def load_vlm(
    spec: str,
    *,
    device: Any = None,
    dtype: Any = None,
    fps: float | None = None,
    frames_as: str | None = None,
    trust_remote_code: bool = False,
) -> VLMAdapter:
    """Build a VLM adapter from a ``KIND:ARGUMENT`` spec (see the module docstring).

    `device`, `dtype`, `fps` and `frames_as` go to the transformers adapters (InternVideo2.5
    takes `device` and `dtype` only); the HTTP client and the stub ignore them.
    """
    import vlm_adapters

    kind, arg = parse_vlm_spec(spec)
    check_vlm_files(kind, arg)
    cls = getattr(vlm_adapters, VLM_KINDS[kind][0])
    if kind == "stub":
        return cls(arg.replace("\\n", "\n"))
    if kind == "openai":
        url, _, model = arg.rpartition("@")
        return cls(url, model)
    if kind == "internvideo2.5":
        return cls.from_pretrained(arg, trust_remote_code=trust_remote_code, device=device, dtype=dtype)
    return cls.from_pretrained(arg, device=device, dtype=dtype, fps=fps, frames_as=frames_as)


def load_embeddings(path: str | os.PathLike) -> tuple[list[str], np.ndarray]:
    """Precomputed YOLOE prompt embeddings: ``(names, (N, D) float32)``.

    The file is an ``.npz`` with the arrays ``names`` (N strings) and ``embeddings`` (N, D)
    (what ``YOLOE.get_text_pe(names)`` returns, reshaped to (N, D)), e.g. written with
    ``np.savez(path, names=np.array(names), embeddings=pe.reshape(len(names), -1).cpu().numpy())``.
    """
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise FileNotFoundError(f"{_opt('embeddings')}: file '{p}' does not exist")
    try:
        with np.load(p, allow_pickle=False) as z:
            names = [str(n) for n in z["names"].reshape(-1)]
            emb = np.asarray(z["embeddings"], np.float32)
    except (KeyError, ValueError, OSError) as exc:
        raise ValueError(f"{_opt('embeddings')}: '{p}' must be an .npz with arrays 'names' (N,) and "
                         f"'embeddings' (N, D): {exc}") from None
    emb = emb.reshape(-1, emb.shape[-1]) if emb.ndim else emb
    if emb.ndim != 2 or len(emb) != len(names) or not names:
        raise ValueError(f"{_opt('embeddings')}: '{p}' holds {len(names)} names and embeddings of shape "
                         f"{emb.shape}; need N names and (N, D) embeddings, N >= 1")
    return names, emb


def _int(key: str, value: Any, *, none_words: Sequence[str] = (), minimum: int | None = None) -> int | None:
    if value is None or (isinstance(value, str) and value.strip().lower() in none_words):
        return None
    extra = f" or {'/'.join(none_words)}" if none_words else ""
    try:  # a str as the command line gives it; from Python a whole number (2.5 read as 2, True as 1)
        number = int(value) if isinstance(value, str) else whole_number(key, value)
    except (TypeError, ValueError):
        raise ValueError(f"{_opt(key)} must be an integer{extra}, got {value!r}") from None
    if minimum is not None and number < minimum:
        raise ValueError(f"{_opt(key)} must be >= {minimum}{extra}, got {value!r}")
    return number


def _float(key: str, value: Any, *, low: float = -math.inf, high: float = math.inf,
           positive: bool = False) -> float | None:
    """A finite number in [low, high] (> 0 with ``positive``): else NaN, 5 or -1 reached the
    model after it was loaded."""
    if value is None:
        return None
    what = "a number > 0" if positive else f"a number in [{low:g}, {high:g}]"
    try:
        if isinstance(value, bool):
            raise TypeError
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{_opt(key)} must be {what}, got {value!r}") from None
    if not (math.isfinite(number) and low <= number <= high) or positive and number <= 0:
        raise ValueError(f"{_opt(key)} must be {what}, got {value!r}")
    return number


def _bool(key: str, value: Any) -> bool:
    if isinstance(value, bool):
        return value
    s = str(value).strip().lower()
    if s in _TRUE | _FALSE:
        return s in _TRUE
    raise ValueError(f"{_opt(key)} must be true or false, got {value!r}")


def _file(key: str, value: Any, what: str) -> str:
    p = os.path.expanduser(os.fspath(value))
    if not os.path.isfile(p):
        raise FileNotFoundError(f"{_opt(key)}: {what} '{p}' does not exist")
    return p


def vlm_yoloe_method(
    *,
    vlm: str | VLMAdapter | None = None,
    yoloe: str | os.PathLike | None = None,
    text_encoder: str | os.PathLike | Callable[[list[str]], Any] | None = None,
    embeddings: str | os.PathLike | None = None,
    device: str | None = None,
    dtype: str | None = None,
    num_frames: int | str | None = 8,
    fps: float | str | None = None,
    frames_as: str | None = None,
    prompt: str | None = None,
    system: str | None = None,
    max_new_tokens: int | str | None = None,
    conf: float | str = 0.25,
    imgsz: int | str = 640,
    max_det: int | str = 100,
    trust_remote_code: bool | str = False,
    **unknown: Any,
) -> VLMYOLOEMethod:
    """Factory of the ``vlm-yoloe`` benchmark method (entry point ``motionbits.methods``).

    Every option may be a string, as ``--option vlm-yoloe.KEY=VALUE`` passes it.

    Args:
        vlm: required. A spec ``KIND:ARGUMENT`` (``qwen2.5-vl:PATH``, ``videollama3:PATH``,
            ``internvl:PATH``, ``internvideo2.5:PATH``, ``openai:URL@MODEL``, ``stub:TEXT``),
            or an adapter object when called from Python.
        yoloe: required. Local YOLOE segmentation weights (``yoloe-11l-seg.pt``; the paper
            used YOLOE-L), or an ultralytics model YAML (random weights, tests only).
        text_encoder: local MobileCLIP text encoder (``mobileclip_blt.ts``): embeds any phrase
            (from Python also a callable ``list[str] -> (N, D)`` raw text features).
        embeddings: ``.npz`` of precomputed prompt embeddings (`load_embeddings`). Without a
            text encoder only these phrases can be found; other phrases of the answer are
            dropped with a warning. One of `text_encoder` / `embeddings` is required.
        device: for the VLM and YOLOE (``cpu``, ``cuda``, ``cuda:1``); default CUDA if available.
        dtype: VLM dtype (``bfloat16``, ``float32``, ...); default bfloat16 on CUDA.
        num_frames: frames sent to the VLM, evenly spaced, the last always included
            (``all``: every frame). Default 8.
        fps, frames_as: passed to the transformers adapters.
        prompt, system: the question (default `MOVED_OBJECTS_PROMPT`) and a system message.
        max_new_tokens: VLM generation budget.
        conf, imgsz, max_det: YOLOE confidence threshold, inference size, detections per image.
        trust_remote_code: needed (``true``) for ``internvideo2.5:`` checkpoints.

    Raises:
        TypeError: an unknown option.
        ValueError: a required option missing or a malformed value (names the option).
        FileNotFoundError: a file or checkpoint folder that does not exist (names the option).
        MissingDependencyError: an extra is not installed (names ``pip install "motionbits[...]"``).
    """
    if unknown:
        valid = sorted(p.name for p in inspect.signature(vlm_yoloe_method).parameters.values()
                       if p.kind is p.KEYWORD_ONLY)
        raise TypeError(f"{METHOD_NAME}: unknown option(s) {', '.join(sorted(unknown))}; valid: {', '.join(valid)}")
    if vlm is None or (isinstance(vlm, str) and not vlm.strip()):
        raise ValueError(f"{METHOD_NAME} needs the option 'vlm', a VLM spec ({_SPEC_HELP}); on the command "
                         f"line: --option {METHOD_NAME}.vlm=qwen2.5-vl:/models/Qwen2.5-VL-7B-Instruct")
    if yoloe is not None and not isinstance(yoloe, (str, os.PathLike)):  # else os.fspath's message
        raise TypeError(f"{_opt('yoloe')} must be a file path, got {type(yoloe).__name__} {yoloe!r:.40}")
    if yoloe is None or not os.fspath(yoloe).strip():
        raise ValueError(f"{METHOD_NAME} needs the option 'yoloe', a local YOLOE segmentation checkpoint; "
                         f"on the command line: --option {METHOD_NAME}.yoloe=/models/yoloe-11l-seg.pt")
    if text_encoder is None and embeddings is None:
        raise ValueError(f"{METHOD_NAME} needs the option 'text_encoder' (a local MobileCLIP file such as "
                         f"mobileclip_blt.ts) or 'embeddings' (an .npz of precomputed YOLOE prompt embeddings)")

    # cheap checks first: nothing heavy is loaded before every option is known to be usable
    n_frames = _int("num_frames", num_frames, none_words=("all", "none"), minimum=1)
    fps_f = _float("fps", fps, positive=True)
    tokens = _int("max_new_tokens", max_new_tokens, minimum=1)
    conf_f = _float("conf", conf, low=0.0, high=1.0)
    imgsz_i, max_det_i = _int("imgsz", imgsz, minimum=1), _int("max_det", max_det, minimum=1)
    trust = _bool("trust_remote_code", trust_remote_code)
    weights = os.path.expanduser(os.fspath(yoloe))
    if not weights.endswith((".yaml", ".yml")):
        weights = _file("yoloe", weights, "YOLOE weights")
    encoder = text_encoder
    if text_encoder is not None and not callable(text_encoder):
        encoder = _file("text_encoder", text_encoder, "MobileCLIP text encoder")
    vocab = load_embeddings(os.path.expanduser(os.fspath(embeddings))) if embeddings is not None else None
    if isinstance(vlm, str):
        kind, arg = parse_vlm_spec(vlm)
        check_vlm_files(kind, arg)
        if kind == "internvideo2.5" and not trust:
            raise ValueError(f"{_opt('vlm')}: internvideo2.5 checkpoints run their own Python code; read it, "
                             f"then add --option {METHOD_NAME}.trust_remote_code=true")
        if VLM_KINDS[kind][1] == "PATH":
            require("transformers", "vlm", f"{METHOD_NAME} ({kind})")
            require("torch", "vlm", f"{METHOD_NAME} ({kind})")
    elif not isinstance(vlm, VLMAdapter):
        raise TypeError(f"{_opt('vlm')} must be a spec string or a VLMAdapter, got {type(vlm).__name__}")
    require("ultralytics", "yoloe", METHOD_NAME)
    require("torch", "yoloe", METHOD_NAME)

    from .grounding import YOLOEDetector, YOLOEGrounder

    detector = YOLOEDetector.from_pretrained(weights, text_encoder=encoder, conf=conf_f, imgsz=imgsz_i,
                                             max_det=max_det_i, device=device)
    parse = phrases_from_answer
    if vocab is not None:
        detector.set_classes(*vocab)
        if encoder is None:
            parse = _vocabulary_filter(detector)
    grounder = YOLOEGrounder(detector, parse=parse)
    if isinstance(vlm, str):
        vlm = load_vlm(vlm, device=device, dtype=dtype, fps=fps_f, frames_as=frames_as, trust_remote_code=trust)
    gen = {} if tokens is None else {"max_new_tokens": tokens}
    return VLMYOLOEMethod(vlm, grounder, prompt if prompt is not None else MOVED_OBJECTS_PROMPT,
                          system=system, num_frames=n_frames, generate_kwargs=gen, name=METHOD_NAME)


def _vocabulary_filter(detector: Any):
    """`phrases_from_answer`, keeping only phrases the detector has embeddings for."""

    def parse(text: str) -> list[str]:
        phrases = phrases_from_answer(text)
        known = set(detector.known_phrases)
        dropped = [p for p in phrases if p not in known]
        if dropped:
            warnings.warn(f"{METHOD_NAME}: no embedding for {dropped} and no text_encoder; these phrases are "
                          f"not searched for", stacklevel=2)
        return [p for p in phrases if p in known]

    return parse

