"""MotionBits demos: a Gradio web app and MotionBits as a tool for agents.

* :func:`segment_moving_bodies`, :func:`ask_about_motion`: the agent tools (JSON out);
* :func:`openai_tools`: the same tools in OpenAI function-calling format;
* ``motionbits-mcp`` (:mod:`demos.mcp_server`): the tools over MCP (stdio);
* ``motionbits-demo`` (:mod:`demos.app`): the web app (Gradio);
* ``python -m demos.agent_example``: an agent with a scripted LLM calling the MCP server.

Needs the ``demo`` extra (``pip install -e ".[demo]"``). Importing this package imports
neither gradio nor mcp.
"""

from .schema import ASK_ABOUT_MOTION, SEGMENT_MOVING_BODIES, openai_tools
from .segmentation import (MAX_NODES, MAX_VIDEO_SIDE, MAX_WINDOW_FRAMES, MAX_WINDOW_PIXELS, Segmentation,
                           max_frames_for, segment_window)
from .tool import ask_about_motion, describe_motionbits, segment_moving_bodies
from .vlm import VLMError, make_vlm

__all__ = [
    "ASK_ABOUT_MOTION", "MAX_NODES", "MAX_VIDEO_SIDE", "MAX_WINDOW_FRAMES", "MAX_WINDOW_PIXELS",
    "SEGMENT_MOVING_BODIES", "Segmentation",
    "VLMError", "ask_about_motion", "describe_motionbits", "make_vlm", "max_frames_for", "openai_tools",
    "segment_moving_bodies", "segment_window",
]
