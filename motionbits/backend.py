"""Implementations of the heavy steps of a frame, chosen by ``MotionBitsConfig.backend``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from motionbits.mcl import _mcl_block
from motionbits.propagation import propagate_labels
from motionbits.twists import _fit_neighbourhoods

__all__ = ["Ops", "make_ops"]


@dataclass(frozen=True)
class Ops:
    """The three heavy steps, each with the signature of its numpy function.

    Attributes:
        name: "numpy" or "torch:<device>".
        fit_neighbourhoods: :func:`motionbits.twists._fit_neighbourhoods`.
        propagate_labels: :func:`motionbits.propagation.propagate_labels`.
        mcl_block: :func:`motionbits.mcl._mcl_block`.
    """

    name: str
    fit_neighbourhoods: Callable
    propagate_labels: Callable
    mcl_block: Callable


NUMPY_OPS = Ops("numpy", _fit_neighbourhoods, propagate_labels, _mcl_block)


def make_ops(backend: str) -> Ops:
    """The ops of a backend string (see ``MotionBitsConfig.backend``).

    Raises:
        ValueError: an unknown backend; ImportError: a torch backend without torch;
        RuntimeError: a CUDA backend without a usable GPU.
    """
    if backend == "numpy":
        return NUMPY_OPS
    if backend == "torch" or backend.startswith("torch:"):
        from motionbits.torch_ops import TorchOps, resolve_device  # imports torch

        ops = TorchOps(resolve_device(backend))
        return Ops(f"torch:{ops.device}", ops.fit_neighbourhoods, ops.propagate_labels,
                   ops.mcl_block)
    from motionbits.config import BACKENDS

    raise ValueError(f"unknown backend {backend!r}; choose one of {', '.join(BACKENDS)}")
