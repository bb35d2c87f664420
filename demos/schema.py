"""The agent tools in OpenAI function-calling format (``tools=[...]`` of chat completions).

The same two tools are served over MCP by ``motionbits-mcp`` (:mod:`demos.mcp_server`);
a test checks that both descriptions agree with the Python signatures.
"""

from __future__ import annotations

import copy
from typing import Any

from motionbits import MotionBitsConfig

from .segmentation import MAX_NODES, MAX_VIDEO_SIDE

__all__ = ["ASK_ABOUT_MOTION", "SEGMENT_MOVING_BODIES", "openai_tools"]

_VIDEO = {"type": "string", "description": "Path of a video file or a folder of images, at most "
                                          f"{MAX_VIDEO_SIDE} px on the longer side."}
_WINDOW = {
    "start": {"type": "integer", "minimum": 0, "default": 0,
              "description": "Index of the first frame used (0-based)."},
    "frames": {"type": ["integer", "null"], "minimum": 2, "default": None,
               "description": "Number of frames used; null = to the end of the video."},
    "every": {"type": "integer", "minimum": 1, "default": 1,
              "description": "Use every k-th frame."},
    "n_nodes": {"type": "integer", "minimum": 16, "maximum": MAX_NODES, "default": MotionBitsConfig.n_nodes,
                "description": "Graph nodes of the segmenter: more = finer masks, slower."},
}

SEGMENT_MOVING_BODIES: dict[str, Any] = {
    "name": "segment_moving_bodies",
    "description": (
        "Segment every moving rigid body in a video by its motion alone (MotionBits). Returns, "
        "for each MotionBit in the last frame (largest first): id, mark number, area, box, "
        "centroid, principal axes, twist (rotation rad/step and translation px/step at its "
        "latest motion), the frames it moved in, its mask as COCO RLE, and a top-down grasp "
        "(centre, closing angle, opening width in pixels). Optionally writes the last frame "
        "with numbered marks to show a vision-language model."),
    "parameters": {
        "type": "object",
        "properties": {
            "video": _VIDEO,
            **_WINDOW,
            "marked_image": {"type": ["string", "null"], "default": None,
                             "description": "Optional .png/.jpg path for the marked last frame."},
        },
        "required": ["video"],
        "additionalProperties": False,
    },
}

ASK_ABOUT_MOTION: dict[str, Any] = {
    "name": "ask_about_motion",
    "description": (
        "Ask a question about what moves in a video. The moving bodies are segmented and "
        "shown to a vision-language model as numbered marks; the answer cites marks like "
        "[2], and the cited MotionBits (id, mark, area, box) are returned with it."),
    "parameters": {
        "type": "object",
        "properties": {
            "video": _VIDEO,
            "question": {"type": "string", "description": "The question about the video."},
            **_WINDOW,
        },
        "required": ["video", "question"],
        "additionalProperties": False,
    },
}


def openai_tools() -> list[dict[str, Any]]:
    """Both tools as OpenAI chat-completions ``tools``: ``[{"type": "function", "function": ...}]``."""
    return [{"type": "function", "function": copy.deepcopy(t)}
            for t in (SEGMENT_MOVING_BODIES, ASK_ABOUT_MOTION)]
