"""Learned optical flow from local weights: torchvision's RAFT (``flow="raft:PATH"``).

The segmenter's default flow is OpenCV's DIS (no weights). With a RAFT weights file on
disk, ``MotionBitsConfig(flow="raft:PATH")`` / ``motionbits segment --flow raft:PATH``
swaps in RAFT (Teed & Deng, ECCV 2020) through the same flow signature
``flow(prev, next) -> (H, W, 2) float32``.

The model definition is torchvision's (``torchvision.models.optical_flow.raft_large`` /
``raft_small``); it uses plain torch operations only (convolutions, ``grid_sample``), none
of torchvision's compiled ops. The weights file is a state dict of either architecture,
e.g. torchvision's own release files (``raft_large_C_T_SKHT_V2-ff5fadd5.pth``,
``raft_small_C_T_V2-01064c6d.pth``) or ``torch.save(model.state_dict(), PATH)``; the
architecture is recognised from the file. torch and torchvision are imported when a
`RAFTFlow` is built, never at import time.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from motionbits.torch_threads import check_threads, torch_threads

__all__ = ["RAFTFlow", "RAFT_ARCHITECTURES"]

#: torchvision builders tried, in order, for a weights file.
RAFT_ARCHITECTURES = ("raft_large", "raft_small")
#: RAFT's 4-level correlation pyramid needs feature maps of >= 16 px at 1/8 resolution.
_MIN_SIDE = 128


class RAFTFlow:
    """Dense flow from a torchvision RAFT model, as a motionbits flow backend.

    Args:
        model: a torchvision ``RAFT`` module with its weights (put in eval mode here).
        iters: recurrent flow updates per call (torchvision's default: 12).
        device: ``"cpu"``, ``"cuda"``, ``"cuda:1"``, a ``torch.device``; default: CUDA when
            available, else CPU.
        architecture: name for ``repr`` (`from_file` sets the one it recognised).
        threads: torch CPU threads for each call, restored afterwards. Default ``None``
            keeps the caller's setting: inside `MotionBitsSegmenter.update` that is one
            thread (on a busy 2-core machine, 2 threads made RAFT 3-10x slower); on an idle
            many-core CPU pass the core count.

    Frames are (H, W, 3) uint8 RGB; they are scaled to [-1, 1] (RAFT's training input) and
    padded by edge replication to a multiple of 8 of at least 128 px a side; the returned
    (H, W, 2) float32 flow is cropped back to the frame.
    """

    def __init__(self, model: Any, *, iters: int = 12, device: Any = None, architecture: str = "raft",
                 threads: int | None = None) -> None:
        from vlm_adapters.base import resolve_device

        if int(iters) < 1:
            raise ValueError(f"RAFT iters must be >= 1, got {iters}")
        self.iters = int(iters)
        self.threads = check_threads(threads, "RAFT")
        self.architecture = architecture
        self.device = resolve_device(device)
        self.model = model.to(self.device).eval()

    @classmethod
    def from_file(cls, path: str | os.PathLike, *, iters: int = 12, device: Any = None,
                  threads: int | None = None) -> RAFTFlow:
        """Load a RAFT state dict (raft_large or raft_small, recognised from the file).

        `iters`, `device` and `threads`: see the class docstring.

        Raises:
            TypeError: `path` is not a (non-empty) path.
            FileNotFoundError / IsADirectoryError: no file at `path`, or a folder.
            MissingDependencyError: torch / torchvision missing or failing to import.
            ValueError: the file is not a state dict of either architecture.
        """
        from motionbits.objects import require

        if not isinstance(path, (str, os.PathLike)) or not os.fspath(path).strip():
            # else "expected str, bytes or os.PathLike object" / "'' does not exist"
            raise TypeError(f"RAFT weights must be a file path, got {type(path).__name__} {path!r:.40}")
        path = os.path.expanduser(os.fspath(path))
        if os.path.isdir(path):  # was reported as "does not exist"
            raise IsADirectoryError(f"RAFT weights file '{path}' is a folder; pass the weights file in it "
                                    "(a torchvision RAFT state dict, .pth)")
        if not os.path.isfile(path):
            raise FileNotFoundError(
                f"RAFT weights file '{path}' does not exist; pass a torchvision RAFT state dict, "
                "e.g. raft_large_C_T_SKHT_V2-ff5fadd5.pth from download.pytorch.org/models/")
        torch = require("torch", "raft", "RAFT flow")
        optical_flow = require("torchvision.models.optical_flow", "raft", "RAFT flow")
        try:
            state = torch.load(path, map_location="cpu", weights_only=True)
        except Exception as exc:  # pickle / zip errors of a file that is not a torch checkpoint
            raise ValueError(f"RAFT weights file '{path}' could not be read by torch.load: {exc}") from exc
        if isinstance(state, dict) and isinstance(state.get("state_dict"), dict):
            state = state["state_dict"]
        if not isinstance(state, dict):
            raise ValueError(f"RAFT weights file '{path}' holds a {type(state).__name__}, not a state dict")
        for arch in RAFT_ARCHITECTURES:
            model = getattr(optical_flow, arch)(weights=None)
            try:
                model.load_state_dict(state)
            except RuntimeError:  # missing / unexpected keys or shapes: the other architecture
                continue
            return cls(model, iters=iters, device=device, architecture=arch, threads=threads)
        raise ValueError(f"RAFT weights file '{path}' fits neither of torchvision's "
                         f"{' / '.join(RAFT_ARCHITECTURES)} architectures")

    @classmethod
    def from_spec(cls, spec: str) -> RAFTFlow:
        """Build from a flow spec ``"raft:PATH"`` (the part after ``raft:`` is the path)."""
        if not isinstance(spec, str):  # None: AttributeError 'partition'
            raise TypeError(f"a RAFT flow spec is 'raft:PATH' (a weights file), got {type(spec).__name__} {spec!r:.40}")
        prefix, sep, path = spec.partition(":")
        if prefix.lower() != "raft" or not sep or not path:
            raise ValueError(f"a RAFT flow spec is 'raft:PATH' (a weights file), got {spec!r}")
        return cls.from_file(path)

    def _to_tensor(self, frame: np.ndarray, pad: tuple[int, int]) -> Any:
        import torch
        import torch.nn.functional as F

        x = torch.from_numpy(np.ascontiguousarray(frame)).to(self.device)
        x = x.permute(2, 0, 1)[None].float() * (2.0 / 255.0) - 1.0
        return F.pad(x, (0, pad[1], 0, pad[0]), mode="replicate") if any(pad) else x

    def __call__(self, prev: np.ndarray, nxt: np.ndarray) -> np.ndarray:
        """(H, W, 2) float32 flow (dx, dy) from `prev` to `nxt`, two (H, W, 3) uint8 RGB frames."""
        import torch

        if prev.shape != nxt.shape or prev.ndim != 3 or prev.shape[2] != 3:
            raise ValueError(f"RAFT flow needs two (H, W, 3) RGB frames of one size, got "
                             f"{prev.shape} and {nxt.shape}")
        h, w = prev.shape[:2]
        pad = (max(_MIN_SIDE, -(-h // 8) * 8) - h, max(_MIN_SIDE, -(-w // 8) * 8) - w)
        with torch_threads(self.threads), torch.inference_mode():
            flows = self.model(self._to_tensor(prev, pad), self._to_tensor(nxt, pad),
                               num_flow_updates=self.iters)
        return flows[-1][0, :, :h, :w].permute(1, 2, 0).float().cpu().numpy()

    def __repr__(self) -> str:
        return (f"RAFTFlow(architecture={self.architecture!r}, iters={self.iters}, "
                f"device={str(self.device)!r})")
