"""MotionBits: learning-free segmentation of moving rigid bodies in RGB video."""

from motionbits.config import MotionBitsConfig
from motionbits.errors import InputError
from motionbits.segmenter import MotionBit, MotionBitsResult, MotionBitsSegmenter, segment_video
from motionbits.video import iter_frames

__all__ = [
    "InputError",
    "MotionBit",
    "MotionBitsConfig",
    "MotionBitsResult",
    "MotionBitsSegmenter",
    "iter_frames",
    "segment_video",
]
__version__ = "0.1.0"
