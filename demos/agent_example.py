"""An agent that uses MotionBits through MCP, with a scripted LLM standing in for a real one.

The loop is the usual function-calling loop: the LLM sees the conversation and the tools
(in OpenAI format, converted from the MCP server's ``tools/list``), answers with tool calls
or a final message; tool calls go to ``motionbits-mcp`` over stdio and their results come
back as ``tool`` messages. :class:`ScriptedLLM` plays the LLM deterministically: segment,
ask the VLM which body to pick up, then propose a grasp of the largest body.
Swap it for any chat-completions client with the same ``__call__(messages, tools)``.

Run::

    python -m demos.agent_example [VIDEO] [--nodes N]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
from typing import Any

__all__ = ["ScriptedLLM", "main", "run_agent", "server_command"]

TASK = "Find the moving bodies in the video and tell me how to grasp the largest one."


class ScriptedLLM:
    """A deterministic stand-in for a function-calling LLM.

    ``__call__(messages, tools) -> message``: an assistant message in OpenAI format, with
    either ``tool_calls`` or ``content``. It reads the tool results from ``messages``.
    """

    def __init__(self, video: str, n_nodes: int = 2500):
        self.video, self.n_nodes = video, n_nodes

    def __call__(self, messages: list[dict[str, Any]], tools: list[dict[str, Any]]) -> dict[str, Any]:
        names = {t["function"]["name"] for t in tools}
        results = [json.loads(m["content"]) for m in messages if m["role"] == "tool"]
        errors = [r["error"] for r in results if "error" in r]
        if errors:
            return {"role": "assistant", "content": f"The tool failed: {errors[-1]}"}
        if not results:
            assert "segment_moving_bodies" in names, "the server does not offer segment_moving_bodies"
            return _call("segment_moving_bodies", {"video": self.video, "n_nodes": self.n_nodes})
        if len(results) == 1:
            return _call("ask_about_motion", {"video": self.video, "n_nodes": self.n_nodes,
                                              "question": "Which object should the robot pick up first?"})
        bodies, answer = results[0]["motionbits"], results[1]["answer"]
        if not bodies:
            return {"role": "assistant", "content": "Nothing moved in the video, so there is nothing to grasp."}
        b = bodies[0]
        g = b["grasp"]
        return {"role": "assistant", "content": (
            f"{len(bodies)} moving bodies. The largest is MotionBit {b['id']} (mark [{b['mark']}], "
            f"{b['area']} px): grasp it top-down at ({g['center'][0]:.1f}, {g['center'][1]:.1f}) px, "
            f"jaws closing at {g['angle']:.2f} rad from the image x axis, opened to {g['width']:.0f} px. "
            f"The VLM said: {answer}")}


def _call(name: str, arguments: dict[str, Any]) -> dict[str, Any]:
    return {"role": "assistant", "content": None, "tool_calls": [{
        "id": f"call_{name}", "type": "function",
        "function": {"name": name, "arguments": json.dumps(arguments)}}]}


def _arguments(text: Any) -> dict[str, Any] | str:
    """A tool call's arguments as the LLM wrote them (a JSON object; empty = none), or the
    error message to send back to it as the tool's result. Arguments a client has already
    decoded into a dict (Ollama's does) are taken as they are."""
    if text is None or (isinstance(text, str) and not text.strip()):
        return {}
    if isinstance(text, dict):  # was: "not valid JSON (the JSON object must be str ..., not dict)"
        return dict(text)
    try:
        arguments = json.loads(text)
    except (TypeError, ValueError) as e:
        return f"the tool call's arguments are not valid JSON ({e}): {str(text)[:200]!r}"
    if not isinstance(arguments, dict):
        return f"the tool call's arguments must be a JSON object, got {type(arguments).__name__}"
    return arguments


def server_command() -> list[str]:
    """``motionbits-mcp`` if installed next to this Python, else ``python -m demos.mcp_server``."""
    script = shutil.which("motionbits-mcp", path=os.path.dirname(sys.executable))
    return [script] if script else [sys.executable, "-m", "demos.mcp_server"]


async def run_agent(llm: Any, task: str = TASK, *, server: list[str] | None = None,
                    max_turns: int = 6) -> list[dict[str, Any]]:
    """Run the function-calling loop against an MCP server; returns the conversation.

    Args:
        llm: ``llm(messages, tools) -> assistant message`` (OpenAI format).
        task: the user's request.
        server: the server's command line (default :func:`server_command`).
        max_turns: most LLM replies before giving up.
    """
    from mcp import ClientSession
    from mcp.client.stdio import StdioServerParameters, stdio_client

    command = server or server_command()
    # the SDK starts servers with a minimal environment; keep PYTHONPATH for source checkouts
    env = {"PYTHONPATH": os.environ["PYTHONPATH"]} if "PYTHONPATH" in os.environ else None
    params = StdioServerParameters(command=command[0], args=command[1:], env=env)
    messages: list[dict[str, Any]] = [{"role": "user", "content": task}]
    async with stdio_client(params) as (read, write), ClientSession(read, write) as session:
        await session.initialize()
        listed = await session.list_tools()
        tools = [{"type": "function", "function": {"name": t.name, "description": t.description or "",
                                                   "parameters": t.input_schema}} for t in listed.tools]
        for _ in range(max_turns):
            reply = llm(messages, tools)
            messages.append(reply)
            if not reply.get("tool_calls"):
                return messages
            for call in reply["tool_calls"]:
                fn = call["function"]
                arguments = _arguments(fn.get("arguments"))
                if isinstance(arguments, str):  # what the LLM wrote is not a JSON object
                    content = json.dumps({"error": arguments})
                else:
                    result = await session.call_tool(fn["name"], arguments)
                    if result.is_error:
                        content = json.dumps({"error": " ".join(c.text for c in result.content if hasattr(c, "text"))})
                    else:
                        content = json.dumps(result.structured_content)
                messages.append({"role": "tool", "tool_call_id": call["id"], "content": content})
    raise RuntimeError(f"the agent did not finish in {max_turns} turns")


def main(argv: list[str] | None = None) -> int:
    import anyio

    parser = argparse.ArgumentParser(prog="python -m demos.agent_example",
                                     description="An agent with a scripted LLM using motionbits-mcp.")
    parser.add_argument("video", nargs="?", help="video to look at (default: the generated demo clip)")
    parser.add_argument("--nodes", type=int, default=2500, help="graph nodes (default: %(default)s)")
    args = parser.parse_args(argv)
    video = args.video
    if video is None:
        from .media import write_demo_clip

        video = str(write_demo_clip(os.path.join(tempfile.mkdtemp(), "clip.mp4")))
    messages = anyio.run(run_agent, ScriptedLLM(video, args.nodes))
    for m in messages:
        if m["role"] == "tool":
            print(f"tool -> {m['content'][:160]}{'...' if len(m['content']) > 160 else ''}")
        elif m.get("tool_calls"):
            for c in m["tool_calls"]:
                print(f"assistant calls {c['function']['name']}({c['function']['arguments']})")
        else:
            print(f"{m['role']}: {m['content']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
