"""The one interface every VLM adapter implements, plus shared input handling.

Nothing here imports torch: `import vlm_adapters` must stay cheap. The torch-dependent
helpers (`resolve_device`, `resolve_dtype`) import it when called.
"""
from __future__ import annotations

import abc
import importlib
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol, Union, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from PIL import Image

    Frame = Union[np.ndarray, Image.Image]
else:
    Frame = Any

__all__ = [
    "Frame",
    "VLMAdapter",
    "BaseVLM",
    "MissingDependencyError",
    "require",
    "to_rgb_array",
    "to_rgb_frames",
    "to_pil_frames",
    "sample_frames",
    "check_local_path",
    "resolve_device",
    "resolve_dtype",
]

#: Default generation budget: enough for a list of a dozen moved objects with short descriptions.
DEFAULT_MAX_NEW_TOKENS = 256


class MissingDependencyError(ImportError):
    """An optional dependency of an adapter is not installed; the message names the extra."""


def require(module: str, extra: str, purpose: str = "") -> Any:
    """Import `module` or raise `MissingDependencyError` that says which extra to install.

    Args:
        module: dotted module name, e.g. ``"transformers"``.
        extra: the ``motionbits`` extra that provides it, e.g. ``"vlm"`` or ``"yoloe"``.
        purpose: what needs it, for the message (e.g. ``"Qwen2_5_VLAdapter"``).
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        who = f"{purpose} needs" if purpose else "This needs"
        raise MissingDependencyError(
            f"{who} the optional dependency '{module.split('.')[0]}', which is not installed "
            f"or failed to import ({exc}). Install it with: pip install \"motionbits[{extra}]\""
        ) from exc


# --------------------------------------------------------------------------- frames


def to_rgb_array(frame: Frame, *, name: str = "frame") -> np.ndarray:
    """One frame as an (H, W, 3) uint8 RGB array.

    PIL images are converted to RGB (16-bit modes scaled, not clipped). Arrays: uint8 as
    is; uint16 scaled by 255 / 65535; floats in [0, 1] scaled by 255 (NaN or values
    outside [0, 1] are an error); (H, W) greyscale replicated; alpha dropped.

    Raises:
        TypeError: not an array or PIL image, or an unsupported dtype.
        ValueError: wrong shape, an empty frame, NaN / out-of-range float values.
    """
    if hasattr(frame, "convert") and hasattr(frame, "size"):  # PIL.Image without importing PIL
        frame = np.asarray(frame if frame.mode.startswith(("I", "F")) else frame.convert("RGB"))
    if not isinstance(frame, np.ndarray):
        raise TypeError(f"{name} must be an (H, W, 3) uint8 RGB numpy array or a PIL image, "
                        f"got {type(frame).__name__}")
    arr = frame
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4):
        raise ValueError(f"{name} must be (H, W, 3) RGB, got an array of shape {arr.shape}")
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{name} is empty ({arr.shape[1]}x{arr.shape[0]} pixels)")
    if arr.shape[2] == 4:
        arr = arr[:, :, :3]
    if arr.dtype == np.uint8:
        pass
    elif arr.dtype == np.uint16 or (np.issubdtype(arr.dtype, np.integer) and arr.dtype.itemsize > 1
                                    and arr.min() >= 0 and arr.max() <= 65535):
        arr = ((arr.astype(np.uint32) * 255 + 32767) // 65535).astype(np.uint8)
    elif np.issubdtype(arr.dtype, np.floating):
        if not np.isfinite(arr).all():
            raise ValueError(f"{name} holds NaN or infinite values")
        if arr.min() < 0 or arr.max() > 1:
            raise ValueError(f"{name} is a float array with values outside [0, 1] "
                             f"({arr.min():g}..{arr.max():g}); pass uint8 RGB or floats in [0, 1]")
        arr = np.round(arr * 255.0).astype(np.uint8)
    else:
        raise TypeError(f"{name} has unsupported dtype {arr.dtype}; pass uint8 RGB (uint16 and "
                        "floats in [0, 1] are scaled)")
    return np.ascontiguousarray(arr)


def to_rgb_frames(frames: Sequence[Frame] | np.ndarray) -> list[np.ndarray]:
    """Frames as a list of (H, W, 3) uint8 RGB arrays (each converted by :func:`to_rgb_array`).

    Accepts a list of (H, W, 3) arrays or PIL images, or one (T, H, W, 3) array.
    A single (H, W, 3) frame is treated as a one-frame video.
    """
    if isinstance(frames, np.ndarray):
        if frames.ndim == 3:
            frames = [frames]
        elif frames.ndim != 4:
            raise ValueError(f"frames must be (T, H, W, 3) or a list of (H, W, 3); got shape {frames.shape}")
    elif hasattr(frames, "convert"):  # one PIL image
        frames = [frames]
    elif frames is None or isinstance(frames, (str, bytes)) or not hasattr(frames, "__iter__"):
        raise TypeError("frames must be a list of (H, W, 3) uint8 RGB arrays or PIL images, or a "
                        f"(T, H, W, 3) array; got {type(frames).__name__}")
    out = [to_rgb_array(f, name=f"frame {i}") for i, f in enumerate(frames)]
    if not out:
        raise ValueError("frames is empty: pass at least one (H, W, 3) uint8 RGB frame")
    return out


def to_pil_frames(frames: Sequence[Frame] | np.ndarray) -> list[Image.Image]:
    """Frames as a list of RGB PIL images."""
    from PIL import Image

    return [Image.fromarray(f) for f in to_rgb_frames(frames)]


def sample_frames(frames: Sequence[Frame], num_frames: int | None) -> list[Frame]:
    """Up to `num_frames` frames spaced evenly over the clip; the last frame is always kept.

    `None` or a number >= len(frames) keeps every frame. The final frame is the one the
    benchmark scores, so it is always included.
    """
    n = len(frames)
    if num_frames is None or num_frames >= n:
        return list(frames)
    if num_frames < 1:
        raise ValueError(f"num_frames must be >= 1, got {num_frames}")
    idx = np.unique(np.round(np.linspace(0, n - 1, num_frames)).astype(int))
    return [frames[i] for i in idx]


# --------------------------------------------------------------------------- paths and devices


def check_local_path(path_or_id: str | os.PathLike, what: str = "model") -> str:
    """Return `path_or_id` as a string; raise a clear error for a local path that is missing.

    Anything that looks like a filesystem path (absolute, starts with ``.`` or ``~``, or has
    more than one ``/``) must exist. A plain ``"org/name"`` hub id is passed through to
    transformers, which will use its local cache or the hub.
    """
    s = os.fspath(path_or_id)
    expanded = os.path.expanduser(s)
    looks_local = (
        os.path.isabs(expanded) or s.startswith((".", "~")) or s.count("/") > 1 or os.sep != "/" and os.sep in s
    )
    if looks_local and not os.path.exists(expanded):
        raise FileNotFoundError(
            f"{what} path '{s}' does not exist. Pass the folder that holds the checkpoint "
            f"(config.json, *.safetensors, tokenizer and processor files), e.g. the result of "
            f"`huggingface-cli download <repo> --local-dir <folder>` or `save_pretrained(<folder>)`."
        )
    return expanded if looks_local else s


def resolve_device(device: Any = None) -> Any:
    """A `torch.device`: the given one, else CUDA when available, else CPU."""
    torch = require("torch", "vlm")
    if device is None or device == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(device)


def resolve_dtype(dtype: Any, device: Any) -> Any:
    """A `torch.dtype`: the given one (name or dtype), else bfloat16 on CUDA and float32 on CPU."""
    torch = require("torch", "vlm")
    if dtype is None or dtype == "auto":
        return torch.bfloat16 if getattr(device, "type", str(device)) == "cuda" else torch.float32
    if isinstance(dtype, str):
        try:
            return getattr(torch, dtype)
        except AttributeError:
            raise ValueError(f"unknown dtype '{dtype}'; use e.g. 'float32', 'bfloat16', 'float16'") from None
    return dtype


# --------------------------------------------------------------------------- interface


@runtime_checkable
class VLMAdapter(Protocol):
    """What every adapter offers: frames + prompt in, text out.

    `frames` is one video as a list of (H, W, 3) uint8 RGB numpy arrays or PIL images
    (a (T, H, W, 3) array also works). With ``do_sample=False`` (the default) decoding is
    greedy, so one model gives the same answer for the same input; `seed` seeds sampling.
    """

    name: str

    def generate(
        self,
        frames: Sequence[Frame],
        prompt: str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
    ) -> str: ...

    def generate_batch(
        self,
        videos: Sequence[Sequence[Frame]],
        prompts: Sequence[str] | str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
    ) -> list[str]: ...


class BaseVLM(abc.ABC):
    """Shared behaviour of the adapters: argument checking and a looping `generate_batch`.

    Subclasses implement `generate`; they override `generate_batch` where the backend
    can batch (the transformers adapters do).
    """

    name: str = "vlm"

    @abc.abstractmethod
    def generate(
        self,
        frames: Sequence[Frame],
        prompt: str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
    ) -> str:
        """Answer `prompt` about one video (list of (H, W, 3) uint8 RGB frames)."""

    def generate_batch(
        self,
        videos: Sequence[Sequence[Frame]],
        prompts: Sequence[str] | str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
    ) -> list[str]:
        """One answer per video; `prompts` is one string for all or one per video."""
        prompts = _broadcast_prompts(prompts, len(videos))
        return [
            self.generate(
                v, p, system, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature, seed=seed
            )
            for v, p in zip(videos, prompts)
        ]

    def __call__(self, frames: Sequence[Frame], prompt: str, system: str | None = None, **kwargs: Any) -> str:
        return self.generate(frames, prompt, system, **kwargs)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"


def _broadcast_prompts(prompts: Sequence[str] | str, n: int) -> list[str]:
    if isinstance(prompts, str):
        return [prompts] * n
    prompts = list(prompts)
    if len(prompts) != n:
        raise ValueError(f"got {len(prompts)} prompts for {n} videos; pass one prompt or one per video")
    return prompts
