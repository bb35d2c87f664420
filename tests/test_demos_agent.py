"""The example agent end to end: scripted LLM -> MCP client -> motionbits-mcp -> tools."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("mcp")
pytest.importorskip("pycocotools")

import anyio  # noqa: E402

from demos.agent_example import ScriptedLLM, run_agent  # noqa: E402
from demos.media import write_demo_clip  # noqa: E402


def test_agent_segments_asks_and_proposes_a_grasp(tmp_path):
    clip = str(write_demo_clip(tmp_path / "clip.mp4", n_frames=6, size=(120, 160)))
    messages = anyio.run(run_agent, ScriptedLLM(clip, n_nodes=400))
    calls = [c["function"]["name"] for m in messages for c in m.get("tool_calls") or []]
    assert calls == ["segment_moving_bodies", "ask_about_motion"]
    tool_results = [json.loads(m["content"]) for m in messages if m["role"] == "tool"]
    assert "error" not in tool_results[0] and "error" not in tool_results[1]
    largest = tool_results[0]["motionbits"][0]
    final = messages[-1]["content"]
    assert f"MotionBit {largest['id']} (mark [{largest['mark']}]" in final
    x, y = largest["grasp"]["center"]
    assert f"({x:.1f}, {y:.1f}) px" in final
    assert f"[{largest['mark']}]" in tool_results[1]["answer"]  # the stub VLM cites the largest


def test_scripted_llm_reports_a_tool_error():
    llm = ScriptedLLM("missing.mp4")
    tools = [{"type": "function", "function": {"name": "segment_moving_bodies"}}]
    first = llm([{"role": "user", "content": "go"}], tools)
    assert first["tool_calls"][0]["function"]["name"] == "segment_moving_bodies"
    error = {"role": "tool", "tool_call_id": "x", "content": json.dumps({"error": "video not found: missing.mp4"})}
    last = llm([{"role": "user", "content": "go"}, first, error], tools)
    assert last == {"role": "assistant", "content": "The tool failed: video not found: missing.mp4"}


class _SloppyLLM:
    """Writes broken JSON as its first tool call's arguments, then reports what came back."""

    def __call__(self, messages, tools):
        tool = [m for m in messages if m["role"] == "tool"]
        if not tool:
            return {"role": "assistant", "content": None, "tool_calls": [{
                "id": "call_1", "type": "function",
                "function": {"name": "segment_moving_bodies", "arguments": '{"video": "clip.mp4",'}}]}
        return {"role": "assistant", "content": tool[-1]["content"]}


def test_malformed_tool_arguments_go_back_to_the_llm_as_an_error():
    messages = anyio.run(run_agent, _SloppyLLM())
    result = json.loads(messages[-1]["content"])
    assert "not valid JSON" in result["error"]  # the loop went on; the LLM saw the error
