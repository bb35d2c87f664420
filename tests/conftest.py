"""Shared pytest configuration.

Everything in this file is a TEST-ENVIRONMENT WORKAROUND, not product behaviour.
"""
from __future__ import annotations

import glob
import importlib.util
import os


# ---------------------------------------------------------------------------
# TEST-ENVIRONMENT WORKAROUND: torchvision without its compiled ops.
#
# Our CPU-only CI can install torch only as the CPU wheel (torch==2.13.0+cpu), but
# the package registry carries torchvision only as CUDA builds. torchvision 0.28.0
# (the match for torch 2.13.0, installed with --no-deps by ci/install-vlm.sh) fails
# to load its `_C` extension against CPU torch, and `import torchvision` then dies
# with "operator torchvision::nms does not exist". transformers' image/video
# processors and ultralytics import torchvision, so the VLM and YOLOE tests would
# all fail to import.
#
# If (and only if) torchvision is installed and its `_C` extension does not load,
# we define the two operator schemas torchvision's import registers fake kernels
# for (nms, qnms), give `nms` a pure-torch CPU kernel, and tell torchvision that
# its ops are present. Nothing else of torchvision's compiled ops is provided
# (roi_align, deform_conv2d, ... raise if used). On a normal machine — a torchvision
# build that matches the installed torch — this block does nothing.
# ---------------------------------------------------------------------------
_TORCHVISION_SHIM_LIB = None


def _nms_reference(dets, scores, iou_threshold: float):
    """Greedy NMS, same contract as torchvision.ops.nms: (N,4) xyxy, (N,) -> kept indices."""
    import torch

    if dets.numel() == 0:
        return torch.empty((0,), dtype=torch.long, device=dets.device)
    order = torch.argsort(scores, descending=True)
    boxes = dets[order].float()
    x1, y1, x2, y2 = boxes.unbind(1)
    areas = (x2 - x1).clamp(min=0) * (y2 - y1).clamp(min=0)
    ix1 = torch.maximum(x1[:, None], x1[None, :])
    iy1 = torch.maximum(y1[:, None], y1[None, :])
    ix2 = torch.minimum(x2[:, None], x2[None, :])
    iy2 = torch.minimum(y2[:, None], y2[None, :])
    inter = (ix2 - ix1).clamp(min=0) * (iy2 - iy1).clamp(min=0)
    iou = inter / (areas[:, None] + areas[None, :] - inter).clamp(min=1e-12)
    suppressed = torch.zeros(len(order), dtype=torch.bool)
    keep = []
    for i in range(len(order)):
        if suppressed[i]:
            continue
        keep.append(i)
        suppressed |= iou[i] > iou_threshold
    return order[torch.tensor(keep, dtype=torch.long, device=dets.device)]


def _torchvision_ops_broken() -> bool:
    spec = importlib.util.find_spec("torchvision")
    if spec is None or not spec.submodule_search_locations:
        return False
    if importlib.util.find_spec("torch") is None:
        return False
    import torch

    libs = glob.glob(os.path.join(list(spec.submodule_search_locations)[0], "_C*.so"))
    if not libs:
        return True
    try:
        torch.ops.load_library(libs[0])
        torch.ops.torchvision.nms  # noqa: B018 - raises if the op is not registered
    except (OSError, RuntimeError, AttributeError):
        return True
    return False


def _install_torchvision_cpu_shim() -> None:
    global _TORCHVISION_SHIM_LIB
    import torch

    lib = torch.library.Library("torchvision", "DEF")
    lib.define("nms(Tensor dets, Tensor scores, float iou_threshold) -> Tensor")
    lib.define("qnms(Tensor dets, Tensor scores, float iou_threshold) -> Tensor")
    lib.impl("nms", _nms_reference, "CompositeExplicitAutograd")
    _TORCHVISION_SHIM_LIB = lib  # keep the registration alive

    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Failed to load '_C' extension" — expected here
        import torchvision.extension

    torchvision.extension._has_ops = lambda: True


if os.environ.get("MOTIONBITS_NO_TORCHVISION_SHIM") != "1" and _torchvision_ops_broken():
    _install_torchvision_cpu_shim()


# --------------------------------------------------------------------------- segmenter fixtures
import pytest


from motionbits import MotionBitsConfig, MotionBitsSegmenter
from motionbits.synth import demo_clip


def best_iou(pred, gt_mask):
    """IoU of a ground-truth mask with the predicted label covering most of it, and that label."""
    import numpy as np

    ids, cnt = np.unique(pred[gt_mask], return_counts=True)
    best = int(ids[np.argmax(cnt)])
    if best == 0:
        return 0.0, 0
    p = pred == best
    return float((p & gt_mask).sum() / (p | gt_mask).sum()), best


@pytest.fixture(scope="session")
def demo_run():
    """The built-in 480x640, 16-frame clip segmented once with the paper's defaults."""
    clip = demo_clip(n_frames=16)
    seg = MotionBitsSegmenter(MotionBitsConfig())
    results = [seg.update(f) for f in clip.frames]
    return clip, results
