"""``motionbits-mcp`` over stdio, driven by the official MCP SDK client (initialize,
tools/list, tools/call), and the OpenAI function-calling description of the same tools."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mcp")
pytest.importorskip("av")
pytest.importorskip("pycocotools")

import anyio  # noqa: E402  (installed with mcp)
from mcp import ClientSession  # noqa: E402
from mcp.client.stdio import StdioServerParameters, stdio_client  # noqa: E402
from pycocotools import mask as coco_mask  # noqa: E402

from demos import openai_tools  # noqa: E402
from demos.media import write_demo_clip  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
# the installed console script when this environment has it (CI: pip install -e), else the
# same entry point through python -m
_SCRIPT = Path(sys.executable).with_name("motionbits-mcp")
SERVER = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "demos.mcp_server"]


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> str:
    return str(write_demo_clip(tmp_path_factory.mktemp("mcp") / "clip.mp4", n_frames=8, size=(120, 160)))


async def _session_run(clip: str, marked: str) -> dict:
    env = {"PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    params = StdioServerParameters(command=SERVER[0], args=SERVER[1:], env=env, cwd=str(ROOT))
    out: dict = {}
    with anyio.fail_after(60):
        async with stdio_client(params) as (read, write):
            async with ClientSession(read, write) as session:
                out["init"] = await session.initialize()
                out["tools"] = await session.list_tools()
                out["bad_path"] = await session.call_tool(
                    "segment_moving_bodies", {"video": clip + ".missing"})
                out["bad_arg"] = await session.call_tool(
                    "segment_moving_bodies", {"video": clip, "every": 0})
                out["not_video"] = await session.call_tool(
                    "segment_moving_bodies", {"video": str(ROOT / "pyproject.toml")})
                out["seg"] = await session.call_tool(
                    "segment_moving_bodies", {"video": clip, "n_nodes": 900, "marked_image": marked})
                out["ask"] = await session.call_tool(
                    "ask_about_motion", {"video": clip, "question": "Which body is largest?",
                                         "n_nodes": 900})
    return out


def _payload(result) -> dict:
    if result.structured_content is not None:
        return result.structured_content
    return json.loads(result.content[0].text)


def test_mcp_server_initialize_list_call(clip, tmp_path):
    marked = str(tmp_path / "marked.png")
    out = anyio.run(_session_run, clip, marked)
    assert out["init"].server_info.name == "motionbits"

    tools = {t.name: t for t in out["tools"].tools}
    assert set(tools) == {"segment_moving_bodies", "ask_about_motion"}
    # the MCP schemas and the OpenAI function-calling schemas describe the same arguments
    for spec in openai_tools():
        fn = spec["function"]
        mcp_schema = tools[fn["name"]].input_schema
        assert set(mcp_schema["properties"]) == set(fn["parameters"]["properties"])
        assert set(mcp_schema.get("required", [])) == set(fn["parameters"]["required"])

    # bad input comes back as a tool error, and the server keeps serving
    for key, words in (("bad_path", "not found"), ("bad_arg", "every"), ("not_video", "could not open")):
        assert out[key].is_error, key
        assert words in out[key].content[0].text, (key, out[key].content[0].text)

    seg = out["seg"]
    assert not seg.is_error, seg.content
    data = _payload(seg)
    assert data["frame_indices"] == list(range(8)) and data["size"] == [120, 160]
    bodies = data["motionbits"]
    assert len(bodies) >= 3
    assert [b["area"] for b in bodies] == sorted((b["area"] for b in bodies), reverse=True)
    for b in bodies:
        m = coco_mask.decode({"size": b["mask"]["size"], "counts": b["mask"]["counts"].encode()})
        assert int(m.sum()) == b["area"]
        ys, xs = np.nonzero(m)
        assert b["box"] == [int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1]
        assert b["centroid"] == pytest.approx([xs.mean(), ys.mean()], abs=0.01)
        assert b["grasp"]["center"] == b["centroid"]
        x0, y0, x1, y1 = b["box"]
        assert 0 < b["grasp"]["width"] <= np.hypot(x1 - x0, y1 - y0)
        assert b["grasp"]["width"] == b["principal_axes"]["minor_length"]
        assert all(0 < f < 8 for f in b["moved_frames"])
    assert Path(data["marked_image"]).stat().st_size > 0

    ask = _payload(out["ask"])
    largest = bodies[0]
    assert f"[{largest['mark']}]" in ask["answer"]
    assert [c["id"] for c in ask["cited"]] == [largest["id"]]


def test_mcp_server_refuses_a_bad_vlm_spec_at_start(capsys):
    from demos.mcp_server import main

    with pytest.raises(SystemExit) as exit_info:
        main(["--vlm", "nonsense"])
    assert exit_info.value.code == 2
    assert "could not load the VLM 'nonsense': cannot read VLM spec" in capsys.readouterr().err
