"""MotionBits: learning-free segmentation of moving rigid bodies in RGB video."""

from motionbits.config import MotionBitsConfig
from motionbits.grasp import GraspProposal, grasp_from_mask, grasp_proposals
from motionbits.segmenter import MotionBit, MotionBitsResult, MotionBitsSegmenter, segment_video
from motionbits.video import iter_frames

__all__ = [
    "MotionBit",
    "MotionBitsConfig",
    "MotionBitsResult",
    "MotionBitsSegmenter",
    "GraspProposal",
    "grasp_from_mask",
    "grasp_proposals",
    "iter_frames",
    "segment_video",
]
__version__ = "0.1.0"
