"""The one interface every VLM adapter implements, plus shared input handling.

Nothing here imports torch: `import vlm_adapters` must stay cheap. The torch-dependent
helpers (`resolve_device`, `resolve_dtype`) import it when called.
"""
from __future__ import annotations

import abc
import math
import numbers
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol, Union, runtime_checkable

import numpy as np

from motionbits.frames import as_rgb_array, sample_frame_indices, whole_number
from motionbits.objects import MissingDependencyError, require, require_attr

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
    "require_attr",
    "to_rgb_frames",
    "to_pil_frames",
    "sample_frames",
    "check_local_path",
    "resolve_device",
    "resolve_dtype",
]

#: Default generation budget: enough for a list of a dozen moved objects with short descriptions.
DEFAULT_MAX_NEW_TOKENS = 256


# --------------------------------------------------------------------------- frames


def to_rgb_frames(frames: Sequence[Frame] | np.ndarray) -> list[np.ndarray]:
    """Frames as a list of (H, W, 3) uint8 RGB arrays (each converted by :func:`to_rgb_array`).

    Accepts a list of frames (see :func:`motionbits.as_rgb_array`: uint8 RGB, greyscale or
    RGBA arrays, PIL images), or one (T, H, W, 3) array. A single (H, W, 3) frame is
    treated as a one-frame video.
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
    out = [as_rgb_array(f, name=f"frame {i}") for i, f in enumerate(frames)]
    if not out:
        raise ValueError("frames is empty: pass at least one (H, W, 3) uint8 RGB frame")
    return out


def to_pil_frames(frames: Sequence[Frame] | np.ndarray) -> list[Image.Image]:
    """Frames as a list of RGB PIL images."""
    from PIL import Image

    return [Image.fromarray(f) for f in to_rgb_frames(frames)]


def sample_frames(frames: Sequence[Frame], num_frames: int | None) -> list[Frame]:
    """Up to `num_frames` frames spaced evenly over the clip; the last frame is always kept
    (see :func:`motionbits.sample_frame_indices`).

    `None` or a number >= len(frames) keeps every frame. The final frame is the one the
    benchmark scores, so it is always included. As in :func:`to_rgb_frames`, one (H, W, 3)
    array or PIL image is a one-frame video (an array's rows were sampled as frames).

    Raises:
        TypeError: `frames` is a str (its letters were sampled as frames), None or not a sequence.
    """
    if isinstance(frames, np.ndarray) and frames.ndim in (2, 3) or hasattr(frames, "convert"):
        frames = [frames]
    elif isinstance(frames, np.ndarray) and frames.ndim != 4:
        raise ValueError(f"frames must be (T, H, W, 3) or a list of (H, W, 3); got shape {frames.shape}")
    elif isinstance(frames, (str, bytes)) or not (hasattr(frames, "__len__") and hasattr(frames, "__getitem__")):
        raise TypeError("frames must be a list of (H, W, 3) uint8 RGB arrays or PIL images, or a "
                        f"(T, H, W, 3) array; got {type(frames).__name__} {frames!r:.40}")
    return [frames[i] for i in sample_frame_indices(len(frames), num_frames)]


# --------------------------------------------------------------------------- paths and devices


def check_local_path(path_or_id: str | os.PathLike, what: str = "model") -> str:
    """Return `path_or_id` as a string; raise a clear error for a local path that is missing.

    Anything that looks like a filesystem path (absolute, starts with ``.`` or ``~``, or has
    more than one ``/``) must exist. A plain ``"org/name"`` hub id is passed through to
    transformers, which will use its local cache or the hub.
    """
    if not isinstance(path_or_id, (str, os.PathLike)) or not os.fspath(path_or_id).strip():
        # else os.fspath's "expected str, bytes or os.PathLike object, not NoneType"
        raise TypeError(f"{what} must be a checkpoint folder (str or pathlib.Path), got "
                        f"{type(path_or_id).__name__} {path_or_id!r:.40}")
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


# --------------------------------------------------------------------------- generation settings


def check_generate_args(prompt: Any, *, max_new_tokens: Any, do_sample: bool, temperature: Any, seed: Any) -> None:
    """Raise a one-line error for a `generate` argument that no backend can use.

    Raises:
        TypeError: `prompt` is not a str; `max_new_tokens` or `seed` is not a whole number.
        ValueError: `max_new_tokens` < 1; with ``do_sample``, a `temperature` that is not a
            finite number >= 0 (NaN and inf are not JSON, -1 is no distribution).
    """
    if not isinstance(prompt, str):  # else None was sent as "text": null
        raise TypeError(f"prompt must be a str, got {type(prompt).__name__} {prompt!r:.40}")
    if whole_number("max_new_tokens", max_new_tokens) < 1:
        raise ValueError(f"max_new_tokens must be >= 1, got {max_new_tokens!r}")
    if do_sample and (isinstance(temperature, bool) or not isinstance(temperature, numbers.Real)
                      or not (math.isfinite(temperature) and temperature >= 0)):
        raise ValueError(f"temperature must be a finite number >= 0 when sampling, got {temperature!r:.40}")
    if seed is not None:
        whole_number("seed", seed)


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
        prompts = _broadcast_prompts(prompts, videos)
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


def _broadcast_prompts(prompts: Sequence[str] | str, videos: Sequence[Sequence[Frame]]) -> list[str]:
    """One prompt per video of `videos` (a str is used for all)."""
    if videos is None or isinstance(videos, (str, bytes)) or not hasattr(videos, "__len__"):
        # else "object of type 'NoneType' has no len()"
        raise TypeError(f"videos must be a list of videos (each a list of frames), got {type(videos).__name__}")
    n = len(videos)
    if isinstance(prompts, str):
        return [prompts] * n
    if prompts is None or not hasattr(prompts, "__iter__"):  # else "'NoneType' object is not iterable"
        raise TypeError(f"prompts must be a str or a list of str (one per video), got {type(prompts).__name__}")
    prompts = list(prompts)
    if len(prompts) != n:
        raise ValueError(f"got {len(prompts)} prompts for {n} videos; pass one prompt or one per video")
    return prompts
