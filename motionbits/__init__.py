"""MotionBits: learning-free segmentation of moving rigid bodies in RGB video.

``import motionbits`` is light (numpy): the segmenter and its dependencies (OpenCV,
SciPy) load on first use of a name that needs them, so ``somprompt`` and
``vlm_adapters`` can share :class:`Instance` and the frame helpers without loading it.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from motionbits.frames import as_rgb_array, sample_frame_indices
from motionbits.objects import (
    Instance,
    MissingDependencyError,
    check_label_map,
    decode_rle,
    encode_rle,
    from_supervision,
    instance_from_mask,
    instances_from_labels,
    labels_from_instances,
    to_supervision,
)

__version__ = "0.1.0"

_LAZY: dict[str, str] = {
    "InputError": "motionbits.errors",
    "MotionBitsConfig": "motionbits.config",
    "MotionBit": "motionbits.segmenter",
    "MotionBitsResult": "motionbits.segmenter",
    "MotionBitsSegmenter": "motionbits.segmenter",
    "segment_video": "motionbits.segmenter",
    "iter_frames": "motionbits.video",
    "GraspProposal": "motionbits.grasp",
    "grasp_from_mask": "motionbits.grasp",
    "grasp_proposals": "motionbits.grasp",
    # learned options from local weights (torch etc. imported only when they are built)
    "Sam2Refiner": "motionbits.refine_sam2",
    "RAFTFlow": "motionbits.flow_raft",
}

__all__ = [
    "InputError",  # the command line's one-line error
    # the segmenter (loaded on first use)
    "MotionBit",
    "MotionBitsConfig",
    "MotionBitsResult",
    "MotionBitsSegmenter",
    "iter_frames",
    "segment_video",
    # learned options: SAM2 refinement, RAFT flow (loaded on first use)
    "RAFTFlow",
    "Sam2Refiner",
    # the object type and helpers shared with somprompt and vlm_adapters
    "Instance",
    "MissingDependencyError",
    "as_rgb_array",
    "check_label_map",
    "decode_rle",
    "encode_rle",
    "from_supervision",
    "instance_from_mask",
    "instances_from_labels",
    "labels_from_instances",
    "sample_frame_indices",
    "to_supervision",
    # top-down grasp proposals from masks (paper Supplement B; loaded on first use)
    "GraspProposal",
    "grasp_from_mask",
    "grasp_proposals",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'motionbits' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs (names are in __all__)
    from motionbits.config import MotionBitsConfig  # noqa: F401
    from motionbits.segmenter import (  # noqa: F401
        MotionBit, MotionBitsResult, MotionBitsSegmenter, segment_video)
    from motionbits.grasp import GraspProposal, grasp_from_mask, grasp_proposals  # noqa: F401
    from motionbits.video import iter_frames  # noqa: F401
    from motionbits.flow_raft import RAFTFlow  # noqa: F401
    from motionbits.refine_sam2 import Sam2Refiner  # noqa: F401
