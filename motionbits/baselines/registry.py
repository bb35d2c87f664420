"""Registry of segmentation methods for the benchmark runner.

A *method* is any callable ``method(frames) -> labels``: ``frames`` is a list of (H, W, 3)
uint8 RGB arrays (the whole clip, oldest first) and ``labels`` the (H, W) int32 label map of
the *last* frame (0 = background, k > 0 = one moving rigid body). A *factory* builds a
method from keyword options, so heavy imports (models, weights) happen only when used.

Plug a method in from your own code::

    from motionbits.baselines import register_method
    register_method("vlm-yoloe", lambda **kw: MyVlmYoloe(**kw), "Qwen2.5-VL answer -> YOLOE masks")

or from an installed package, with an entry point in the group ``motionbits.methods``
whose object is such a factory (the entry point's name is the method name).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import metadata
from typing import Callable, Protocol

import numpy as np

__all__ = ["Method", "MethodInfo", "register_method", "make_method", "available_methods"]


class Method(Protocol):
    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        """Label map ((H, W) int32) of the last of ``frames`` ((H, W, 3) uint8 RGB each).

        A method whose attribute ``needs_scene`` is true is called as
        ``method(frames, scene=folder)`` by the benchmark runner (e.g. to read stored flow).
        """
        ...


@dataclass(frozen=True)
class MethodInfo:
    name: str
    factory: Callable[..., Method]
    description: str = ""


_REGISTRY: dict[str, MethodInfo] = {}
_ENTRY_POINT_GROUP = "motionbits.methods"


def register_method(name: str, factory: Callable[..., Method], description: str = "", *,
                    replace: bool = False) -> None:
    """Make ``factory(**options) -> method`` available under ``name``."""
    if not name or any(c.isspace() for c in name):
        raise ValueError(f"method name must be a non-empty word, got {name!r}")
    if name in _REGISTRY and not replace:
        raise ValueError(f"method {name!r} is already registered (pass replace=True)")
    _REGISTRY[name] = MethodInfo(name, factory, description)


def _load_entry_points() -> None:
    try:
        eps = metadata.entry_points(group=_ENTRY_POINT_GROUP)
    except Exception:  # broken metadata must not break the built-in methods
        return
    for ep in eps:
        if ep.name not in _REGISTRY:
            _REGISTRY[ep.name] = MethodInfo(ep.name, lambda ep=ep, **kw: ep.load()(**kw),
                                            f"plug-in {ep.value}")


def available_methods() -> dict[str, str]:
    """``{name: description}`` of every registered method (built-ins and plug-ins)."""
    _load_entry_points()
    return {n: i.description for n, i in sorted(_REGISTRY.items())}


def make_method(name: str, **options) -> Method:
    """Build the method registered as ``name``.

    Raises:
        KeyError: unknown name (the message lists the known ones).
    """
    _load_entry_points()
    if name not in _REGISTRY:
        raise KeyError(f"unknown method {name!r}; available: {', '.join(sorted(_REGISTRY))}")
    return _REGISTRY[name].factory(**options)
