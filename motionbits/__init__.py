"""MotionBits: learning-free segmentation of moving rigid bodies in RGB video."""

from motionbits.config import MotionBitsConfig

__all__ = ["MotionBitsConfig"]
__version__ = "0.1.0"
