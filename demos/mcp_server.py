"""``motionbits-mcp``: the agent tools served over MCP (stdio) with the official ``mcp`` SDK.

Tools: ``segment_moving_bodies`` and ``ask_about_motion`` (:mod:`demos.tool`). Bad input
(a missing file, a non-video, a bad argument, a VLM that does not answer) comes back as
an MCP tool error (``isError: true`` with a one-line message); the server keeps serving.

Register it with an MCP client, e.g.::

    {"mcpServers": {"motionbits": {"command": "motionbits-mcp", "args": ["--vlm", "stub"]}}}
"""

from __future__ import annotations

import argparse
from typing import Annotated, Any

from pydantic import Field

from motionbits import MotionBitsConfig

from .schema import ASK_ABOUT_MOTION, SEGMENT_MOVING_BODIES
from .segmentation import MAX_NODES
from .tool import ask_about_motion, segment_moving_bodies
from .vlm import VLMError, _resolve, check_vlm_spec, make_vlm, vlm_spec_help

__all__ = ["build_server", "main"]

_P = SEGMENT_MOVING_BODIES["parameters"]["properties"]
_Q = ASK_ABOUT_MOTION["parameters"]["properties"]

Video = Annotated[str, Field(description=_P["video"]["description"])]
Start = Annotated[int, Field(ge=0, description=_P["start"]["description"])]
Frames = Annotated["int | None", Field(ge=2, description=_P["frames"]["description"])]
Every = Annotated[int, Field(ge=1, description=_P["every"]["description"])]
Nodes = Annotated[int, Field(ge=16, le=MAX_NODES, description=_P["n_nodes"]["description"])]
Marked = Annotated["str | None", Field(description=_P["marked_image"]["description"])]
Question = Annotated[str, Field(description=_Q["question"]["description"])]

#: errors that are the caller's (bad path, bad argument, unusable VLM): reported as such
_USER_ERRORS = (FileNotFoundError, ValueError, TypeError, VLMError)


def build_server(vlm: str = "stub") -> Any:
    """An ``mcp.server.mcpserver.MCPServer`` with both tools; ``vlm`` answers questions.

    ``vlm``: a spec of :func:`demos.vlm.make_vlm`, checked now without loading anything
    (:func:`demos.vlm.check_vlm_spec`: a malformed spec or a missing model folder raises
    :class:`demos.vlm.VLMError`); a model or endpoint is built on the first question
    (``"stub"``: a new stub per question that cites the largest MotionBit).
    """
    check_vlm_spec(vlm)
    is_stub = _resolve(vlm).lower() == "stub"  # None and "" are the stub (None.strip() failed)
    from mcp.server.mcpserver import MCPServer
    from mcp.server.mcpserver.exceptions import ToolError

    state: dict[str, Any] = {}

    def the_vlm() -> Any:
        if is_stub:
            return None  # ask_about_motion builds the default stub for each video
        if "vlm" not in state:
            state["vlm"] = make_vlm(vlm)
        return state["vlm"]

    server = MCPServer(name="motionbits", instructions=(
        "Segment the moving rigid bodies of a video (MotionBits) and ask questions about "
        "what moved; paths are on the server's machine."))

    @server.tool(name="segment_moving_bodies", description=SEGMENT_MOVING_BODIES["description"])
    def _segment(video: Video, start: Start = 0, frames: Frames = None, every: Every = 1,
                 n_nodes: Nodes = MotionBitsConfig.n_nodes, marked_image: Marked = None) -> dict[str, Any]:
        try:
            return segment_moving_bodies(video, start=start, frames=frames, every=every,
                                         n_nodes=n_nodes, marked_image=marked_image)
        except _USER_ERRORS as exc:
            raise ToolError(str(exc)) from exc

    @server.tool(name="ask_about_motion", description=ASK_ABOUT_MOTION["description"])
    def _ask(video: Video, question: Question, start: Start = 0, frames: Frames = None,
             every: Every = 1, n_nodes: Nodes = MotionBitsConfig.n_nodes) -> dict[str, Any]:
        try:
            return ask_about_motion(video, question, vlm=the_vlm(), start=start, frames=frames,
                                    every=every, n_nodes=n_nodes)
        except _USER_ERRORS as exc:
            raise ToolError(str(exc)) from exc

    return server


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``motionbits-mcp``: serve the tools on stdin/stdout."""
    parser = argparse.ArgumentParser(
        prog="motionbits-mcp",
        description="Serve segment_moving_bodies and ask_about_motion over MCP (stdio).")
    parser.add_argument("--vlm", default="stub", help=f"VLM for ask_about_motion: {vlm_spec_help()}")
    args = parser.parse_args(argv)
    try:
        server = build_server(args.vlm)
    except VLMError as exc:  # before serving: the client sees the server exit with the reason
        parser.error(str(exc))
    server.run("stdio")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
