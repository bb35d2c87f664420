"""A client for OpenAI-compatible chat-completions servers (vLLM, SGLang, LMDeploy, Ollama, ...).

This is how most people serve Qwen2.5-VL and InternVL, e.g.::

    vllm serve Qwen/Qwen2.5-VL-32B-Instruct --limit-mm-per-prompt '{"image": 16}'

Frames are sent as base64 data-URL images (``image_url`` content parts) in one user message,
followed by the prompt text. Standard library only (urllib): no extra to install.
"""
from __future__ import annotations

import base64
import http.client
import io
import json
import numbers
import os
import urllib.error
import urllib.request
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from motionbits.frames import as_rgb_array

from .base import DEFAULT_MAX_NEW_TOKENS, BaseVLM, Frame, _broadcast_prompts, check_generate_args, to_pil_frames

__all__ = ["OpenAICompatibleVLM", "encode_image_data_url"]

_IMAGE_FORMATS = ("png", "jpeg", "jpg")


def _check_image_format(image_format: Any) -> str:
    """``image_format`` as PIL's name for it (``"png"`` / ``"jpeg"``), else ValueError."""
    if not isinstance(image_format, str) or image_format.lower() not in _IMAGE_FORMATS:
        raise ValueError(f"image_format must be 'png' or 'jpeg', got {image_format!r}")
    fmt = image_format.lower()
    return "jpeg" if fmt == "jpg" else fmt


def _check_max_side(value: Any, name: str) -> None:
    """ValueError unless ``value`` is None or an int >= 1 (a longest image side, px)."""
    if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Integral)
                              or value < 1):
        raise ValueError(f"{name} must be None or an int >= 1, got {value!r}")


def encode_image_data_url(image: Any, image_format: str = "png", max_side: int | None = None) -> str:
    """One image as a ``data:image/...;base64,...`` URL.

    Args:
        image: a PIL image, or a frame as :func:`~vlm_adapters.base.to_rgb_frames` takes it
            ((H, W, 3) uint8 RGB array, greyscale, RGBA, 16-bit).
        image_format: ``"png"`` (lossless: set-of-mark numbers stay crisp) or ``"jpeg"`` (smaller).
        max_side: downscale so the longer side is at most this many pixels, >= 1 (None: keep size).
    """
    _check_max_side(max_side, "max_side")  # else 0 or -3 sent a 1x1 image
    fmt = _check_image_format(image_format)  # else PIL's KeyError 'BOGUS'
    if not hasattr(image, "save"):  # an array: else "'numpy.ndarray' object has no attribute 'save'"
        from PIL import Image

        image = Image.fromarray(as_rgb_array(image, name="image"))
    if max_side is not None and max(image.size) > max_side:
        scale = max_side / max(image.size)
        image = image.resize((max(1, round(image.size[0] * scale)), max(1, round(image.size[1] * scale))))
    buf = io.BytesIO()
    image.save(buf, format=fmt.upper(), **({"quality": 90} if fmt == "jpeg" else {}))
    return f"data:image/{fmt};base64," + base64.b64encode(buf.getvalue()).decode("ascii")


class OpenAICompatibleVLM(BaseVLM):
    """Chat-completions client: frames as images, prompt as text, answer as a string.

    Args:
        base_url: the server's API root, e.g. ``"http://localhost:8000/v1"`` (``/chat/completions``
            is appended).
        model: the served model name (vLLM: the name given to ``vllm serve``).
        api_key: sent as ``Authorization: Bearer ...``; default ``$OPENAI_API_KEY`` if set.
        image_format: ``"png"`` or ``"jpeg"`` for the data URLs.
        max_image_side: downscale frames so their longer side is at most this, >= 1 (None: as given).
        timeout: seconds per request (None: wait for ever).
        max_workers: parallel requests in `generate_batch`.
        extra_body: extra JSON fields for every request (e.g. ``{"top_k": 1}`` for vLLM).
        name: short name for tables (default: `model`).

    Example:
        >>> vlm = OpenAICompatibleVLM("http://localhost:8000/v1", model="Qwen/Qwen2.5-VL-32B-Instruct")
        >>> vlm.generate(frames, "What rigid bodies have moved?", seed=0)  # doctest: +SKIP
    """

    def __init__(
        self,
        base_url: str,
        model: str,
        *,
        api_key: str | None = None,
        image_format: str = "png",
        max_image_side: int | None = None,
        timeout: float = 300.0,
        max_workers: int = 4,
        extra_body: dict[str, Any] | None = None,
        name: str | None = None,
    ) -> None:
        if not isinstance(base_url, str) or not base_url.startswith(("http://", "https://")):
            raise ValueError(f"base_url must be a str starting with http:// or https://, got {base_url!r}")
        _check_image_format(image_format)
        _check_max_side(max_image_side, "max_image_side")
        if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, numbers.Real)
                                    or not timeout > 0):
            raise ValueError(f"timeout must be None or a number of seconds > 0, got {timeout!r}")
        self.base_url = base_url.rstrip("/")
        self.model = model
        self.api_key = api_key if api_key is not None else os.environ.get("OPENAI_API_KEY")
        self.image_format = image_format
        self.max_image_side = max_image_side
        self.timeout = timeout
        self.max_workers = max(1, int(max_workers))
        self.extra_body = dict(extra_body or {})
        self.name = name or model

    @classmethod
    def from_pretrained(cls, model: str, *, base_url: str = "http://localhost:8000/v1", **kwargs: Any):
        """transformers-style spelling: the served model name first, the server second."""
        return cls(base_url, model, **kwargs)

    @property
    def endpoint(self) -> str:
        return self.base_url + "/chat/completions"

    def build_request(
        self,
        frames: Sequence[Frame],
        prompt: str,
        system: str | None = None,
        *,
        max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS,
        do_sample: bool = False,
        temperature: float = 1.0,
        seed: int | None = None,
    ) -> dict[str, Any]:
        """The JSON body of one chat-completions request.

        Raises:
            TypeError, ValueError: a setting no server can take (see
                :func:`~vlm_adapters.base.check_generate_args`), before anything is sent.
        """
        check_generate_args(prompt, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature,
                            seed=seed)
        content: list[dict[str, Any]] = [
            {"type": "image_url", "image_url": {"url": encode_image_data_url(im, self.image_format, self.max_image_side)}}
            for im in to_pil_frames(frames)
        ]
        content.append({"type": "text", "text": prompt})
        messages: list[dict[str, Any]] = []
        if system:
            messages.append({"role": "system", "content": system})
        messages.append({"role": "user", "content": content})
        body: dict[str, Any] = {
            "model": self.model,
            "messages": messages,
            "max_tokens": int(max_new_tokens),
            # greedy decoding is temperature 0 in this API
            "temperature": float(temperature) if do_sample else 0.0,
        }
        if seed is not None:
            body["seed"] = int(seed)
        body.update(self.extra_body)
        return body

    def _post(self, body: dict[str, Any]) -> dict[str, Any]:
        data = json.dumps(body).encode("utf-8")
        headers = {"Content-Type": "application/json"}
        if self.api_key:
            headers["Authorization"] = f"Bearer {self.api_key}"
        req = urllib.request.Request(self.endpoint, data=data, headers=headers, method="POST")
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as resp:
                raw = resp.read()
        except urllib.error.HTTPError as exc:
            detail = exc.read().decode("utf-8", "replace")[:2000]
            raise RuntimeError(f"{self.endpoint} answered HTTP {exc.code}: {detail}") from exc
        except urllib.error.URLError as exc:
            raise ConnectionError(
                f"could not reach {self.endpoint} ({exc.reason}); is the server running "
                f"(e.g. `vllm serve {self.model}`)?"
            ) from exc
        except http.client.HTTPException as exc:  # a status line or body that is not HTTP
            raise RuntimeError(f"{self.endpoint} sent a broken HTTP response ({type(exc).__name__}: "
                               f"{str(exc).strip()[:200]}); is it a chat-completions server?") from exc
        except TimeoutError as exc:  # the answer (not the connection) took too long
            raise TimeoutError(f"{self.endpoint} did not answer within {self.timeout} s; raise "
                               f"timeout= for long videos or slow models") from exc
        except OSError as exc:  # e.g. the connection reset while reading the answer
            raise ConnectionError(f"the connection to {self.endpoint} failed while waiting for the "
                                  f"answer ({type(exc).__name__}: {exc})") from exc
        try:
            return json.loads(raw.decode("utf-8"))
        except (ValueError, RecursionError) as exc:  # not UTF-8, not JSON, or nested too deep
            raise RuntimeError(f"{self.endpoint} did not answer JSON: {raw[:500]!r}") from exc

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
        """Send frames + prompt, return the first choice's message content ("" if it has none).

        Raises:
            ConnectionError: the server cannot be reached.
            RuntimeError: an HTTP error, or a reply that is not a chat completion with text.
        """
        body = self.build_request(
            frames, prompt, system, max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature, seed=seed
        )
        reply = self._post(body)
        if isinstance(reply, dict) and reply.get("error") and "choices" not in reply:
            err = reply["error"]
            msg = err.get("message", err) if isinstance(err, dict) else err
            raise RuntimeError(f"{self.endpoint} answered an error: {str(msg)[:500]}")
        try:
            content = reply["choices"][0]["message"]["content"]
        except (KeyError, IndexError, TypeError) as exc:
            raise RuntimeError(f"unexpected reply from {self.endpoint}: {str(reply)[:500]}") from exc
        if isinstance(content, list):  # some servers return content parts
            parts = [p.get("text", "") if isinstance(p, dict) else p for p in content]
            if all(isinstance(p, str) for p in parts):
                content = "".join(parts)
        if content is None:  # a message without text
            return ""
        if not isinstance(content, str):
            raise RuntimeError(f"unexpected reply from {self.endpoint}: the message content is not text: "
                               f"{str(reply)[:500]}")
        return content.strip()

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
        """One request per video, `max_workers` in flight; answers in input order."""
        prompts = _broadcast_prompts(prompts, videos)
        kw = dict(max_new_tokens=max_new_tokens, do_sample=do_sample, temperature=temperature, seed=seed)
        with ThreadPoolExecutor(self.max_workers) as pool:
            futures = [pool.submit(self.generate, v, p, system, **kw) for v, p in zip(videos, prompts)]
            return [f.result() for f in futures]

    def __repr__(self) -> str:
        return f"OpenAICompatibleVLM(base_url={self.base_url!r}, model={self.model!r})"
