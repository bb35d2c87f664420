"""MotionBits with the simulator's exact flow instead of DIS: the flow's share of the error.

``motionbits synth --flow`` stores, per scene, the exact optical flow between consecutive
frames in both directions (``flow/NNNNN.npz``, see docs/evaluation.md). :class:`StoredFlow`
is a flow backend that replays it; :class:`OracleFlowMotionBits` is the benchmark method
``motionbits-oracle-flow`` (the segmenter with that backend). The difference between it and
``motionbits`` on the same scenes is the error due to the flow; what remains is the rest.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

__all__ = ["StoredFlow", "OracleFlowMotionBits", "load_flow_pair"]


def load_flow_pair(scene: str | os.PathLike, k: int) -> dict[str, np.ndarray]:
    """The stored flow between frames ``k - 1`` and ``k`` of a scene (float32 / bool arrays:
    ``backward``, ``backward_valid``, ``forward``, ``forward_valid``).

    Raises:
        FileNotFoundError: the scene has no ``flow/`` for that frame (generate it with
            ``motionbits synth --flow``).
    """
    path = Path(scene) / "flow" / f"{int(k):05d}.npz"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found: this scene has no exact flow; generate it "
                                "with `motionbits synth ... --flow`")
    with np.load(path) as z:
        return {n: (z[n].astype(np.float32) if z[n].dtype.kind == "f" else z[n]) for n in z.files}


class StoredFlow:
    """Flow backend ``flow(a, b) -> (h, w, 2)`` replaying a scene's exact flow.

    The caller says which frame of the clip is being processed (:attr:`frame`, the later
    frame k); each argument is then identified as frame k - 1 or k by its content (the
    nearer of the two, at the argument's size), so the call order and any resizing by the
    segmenter do not matter. The stored (H, W) flow is resized to the arguments' size with
    its vectors scaled.

    Args:
        scene: the scene folder (with ``flow/``).
        frames: the clip's (H, W, 3) uint8 frames, as given to the method.
    """

    def __init__(self, scene: str | os.PathLike, frames: list[np.ndarray]) -> None:
        self.scene = Path(scene)
        self.frames = frames
        self.frame = 1
        self._pair: tuple[int, dict[str, np.ndarray]] | None = None

    def _which(self, img: np.ndarray) -> int:
        k = self.frame
        h, w = img.shape[:2]
        a = img.astype(np.float32)
        errs = []
        for i in (k - 1, k):
            ref = self.frames[i]
            if ref.shape[:2] != (h, w):
                ref = cv2.resize(ref, (w, h), interpolation=cv2.INTER_AREA)
            ref = ref.astype(np.float32)
            if ref.ndim != a.ndim:
                ref = cv2.cvtColor(ref, cv2.COLOR_RGB2GRAY) if a.ndim == 2 else ref
            errs.append(float(np.abs(ref - a).mean()))
        return k - 1 if errs[0] < errs[1] else k

    def __call__(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        k = self.frame
        if not 1 <= k < len(self.frames):
            raise ValueError(f"StoredFlow.frame must be in 1..{len(self.frames) - 1}, got {k}")
        ia, ib = self._which(a), self._which(b)
        if ia == ib:
            return np.zeros((*a.shape[:2], 2), np.float32)
        if self._pair is None or self._pair[0] != k:
            self._pair = (k, load_flow_pair(self.scene, k))
        flow = self._pair[1]["forward" if ia == k - 1 else "backward"]
        h, w = a.shape[:2]
        H, W = flow.shape[:2]
        if (h, w) != (H, W):
            flow = cv2.resize(flow, (w, h), interpolation=cv2.INTER_LINEAR)
            flow = flow * np.array([w / W, h / H], np.float32)
        return np.ascontiguousarray(flow, dtype=np.float32)


class OracleFlowMotionBits:
    """Benchmark method ``motionbits-oracle-flow``: the segmenter on the stored exact flow.

    Called as ``method(frames, scene=path)`` (its :attr:`needs_scene` asks the benchmark
    runner for the scene folder).

    Args:
        config: a ``motionbits.MotionBitsConfig`` or a dict of its fields (default: paper's).
        **changes: config fields to change.
    """

    needs_scene = True

    def __init__(self, config=None, **changes) -> None:
        from motionbits.baselines.motionbits_method import MotionBitsMethod

        # the same conversion and checks as ``motionbits`` (``--option`` values are strings)
        self.config = MotionBitsMethod(config, **changes).config
        # the stored flow is exact between the clip's frames only: no second flow pass on
        # camera-stabilised frames, unless asked for
        if "camera_reflow" not in changes:
            self.config = self.config.with_(camera_reflow=False)

    def __call__(self, frames: list[np.ndarray], scene: str | os.PathLike | None = None) -> np.ndarray:
        import motionbits

        if scene is None:
            raise ValueError("motionbits-oracle-flow needs the scene folder (scene=...) to read "
                             "its flow/; run it through motionbits benchmark")
        if len(frames) < 2:
            raise ValueError("a clip needs at least 2 frames")
        flow = StoredFlow(scene, frames)
        load_flow_pair(scene, 1)  # fail early, with the reason, if the scene has no flow
        seg = motionbits.MotionBitsSegmenter(self.config, flow=flow)
        result = None
        for k, frame in enumerate(frames):
            flow.frame = max(k, 1)
            result = seg.update(frame)
        return np.asarray(result.labels, dtype=np.int32)
