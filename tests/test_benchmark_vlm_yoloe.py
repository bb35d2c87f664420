"""The ``vlm-yoloe`` plug-in: entry point, ``--option`` parsing, factory errors, and the
benchmark runner end to end with a stub VLM and YOLOE built from its YAML (random weights).

The shared test venv holds the project's *installed* metadata, which may predate the entry
point; the `registered` fixture therefore puts a throwaway ``*.dist-info`` carrying the entry
points declared in this checkout's pyproject.toml on ``sys.path``, so the registry finds
``vlm-yoloe`` through ``importlib.metadata`` exactly as it would in an installed package.
"""
from __future__ import annotations

import json
import sys
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from motionbits import cli
from motionbits.baselines import available_methods, make_method, registry
from motionbits.commands.benchmark import parse_method_options
from motionbits.eval import read_label_map, write_label_map

ROOT = Path(__file__).resolve().parents[1]
ANSWER = "- red cup: slid to the right\n- blue box: pushed by the gripper\n- green ball: rolled away"
VOCAB = ["red cup", "blue box"]  # green ball has no embedding: dropped with a warning


def _declared_methods() -> dict[str, str]:
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    return project["entry-points"]["motionbits.methods"]


@pytest.fixture
def registered(tmp_path, monkeypatch):
    """The pyproject entry points installed as a throwaway distribution; registry reset."""
    dist = tmp_path / "site" / "motionbits_entry_point_probe-0.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: motionbits-entry-point-probe\nVersion: 0.0\n")
    lines = [f"{name} = {value}" for name, value in _declared_methods().items()]
    (dist / "entry_points.txt").write_text("[motionbits.methods]\n" + "\n".join(lines) + "\n")
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    monkeypatch.setattr(registry, "_REGISTRY", {k: v for k, v in registry._REGISTRY.items() if k != "vlm-yoloe"})


def _cli(argv, capsys):
    rc = cli.main(argv)
    out = capsys.readouterr()
    return rc, out.out, out.err


# --------------------------------------------------------------------------- no torch needed


def test_pyproject_entry_point_resolves_to_the_factory():
    from vlm_adapters.plugin import vlm_yoloe_method

    value = _declared_methods()["vlm-yoloe"]
    ep = metadata.EntryPoint("vlm-yoloe", value, "motionbits.methods")
    assert ep.load() is vlm_yoloe_method


def test_registry_discovers_vlm_yoloe_through_entry_point(registered):
    assert "vlm-yoloe" not in registry._REGISTRY
    methods = available_methods()
    assert "vlm_adapters.plugin:vlm_yoloe_method" in methods["vlm-yoloe"]
    assert {"flow-cc", "affine-ransac", "motionbits"} <= set(methods)
    with pytest.raises(ValueError, match="needs the option 'vlm'"):  # the factory behind the entry point runs
        make_method("vlm-yoloe")


def test_core_package_does_not_import_vlm_adapters():
    import subprocess

    code = ("import sys, motionbits, motionbits.baselines, motionbits.commands.benchmark, motionbits.cli\n"
            "bad = [m for m in ('vlm_adapters', 'torch', 'ultralytics') if m in sys.modules]\n"
            "assert not bad, bad\n")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_parse_method_options():
    opts = parse_method_options(
        ["vlm-yoloe.vlm=openai:http://h:8000/v1@Qwen/Qwen2.5-VL-7B-Instruct", "vlm-yoloe.prompt=a=b. c:d",
         "vlm-yoloe.vlm_empty=", "flow-cc.x=1"],
        ["flow-cc", "vlm-yoloe"], ["flow-cc", "vlm-yoloe", "motionbits"])
    assert opts == {"vlm-yoloe": {"vlm": "openai:http://h:8000/v1@Qwen/Qwen2.5-VL-7B-Instruct",
                                  "prompt": "a=b. c:d", "vlm_empty": ""},
                    "flow-cc": {"x": "1"}}
    assert parse_method_options(None, ["flow-cc"]) == {}
    bad = {
        "vlm-yoloe.vlm": "METHOD.KEY=VALUE",          # no '='
        "vlm=stub:x": "METHOD.KEY=VALUE",             # no method
        ".vlm=stub:x": "METHOD.KEY=VALUE",            # empty method
        "vlm-yoloe.=x": "METHOD.KEY=VALUE",           # empty key
        "vlm-yoloe.max-det=3": "METHOD.KEY=VALUE",    # key is not an identifier
        "vlm-yolo.vlm=stub:x": "unknown method 'vlm-yolo'",
        "motionbits.x=1": "not in --methods",
    }
    for item, msg in bad.items():
        with pytest.raises(ValueError, match=msg):
            parse_method_options([item], ["vlm-yoloe"], ["vlm-yoloe", "motionbits"])
    with pytest.raises(ValueError, match="given twice"):
        parse_method_options(["vlm-yoloe.vlm=a", "vlm-yoloe.vlm=b"], ["vlm-yoloe"])


def test_cli_option_errors_are_clear(tmp_path, capsys, registered):
    rc, out, _ = _cli(["benchmark", "--list"], capsys)  # no --data needed to list the plug-ins
    assert rc == 0 and any(line.startswith("vlm-yoloe ") for line in out.splitlines())
    rc, _, err = _cli(["benchmark", "--methods", "flow-cc"], capsys)
    assert rc == 2 and "--data DIR is required" in err
    data = str(tmp_path)  # never read: options are checked first
    rc, _, err = _cli(["benchmark", "--data", data, "--methods", "vlm-yoloe", "--option", "vlm-yoloe.vlm"], capsys)
    assert rc == 2 and "expected METHOD.KEY=VALUE" in err
    rc, _, err = _cli(["benchmark", "--data", data, "--methods", "flow-cc", "--option", "nope.vlm=x"], capsys)
    assert rc == 2 and "unknown method 'nope'" in err
    rc, _, err = _cli(["benchmark", "--data", data, "--methods", "flow-cc", "--option", "vlm-yoloe.vlm=x"], capsys)
    assert rc == 2 and "not in --methods" in err
    rc, _, err = _cli(["benchmark", "--data", data, "--methods", "vlm-yoloe",
                       "--option", "vlm-yoloe.yoloe=/models/yoloe-11l-seg.pt"], capsys)
    assert rc == 2 and "needs the option 'vlm'" in err and "--option vlm-yoloe.vlm=" in err
    rc, _, err = _cli(["benchmark", "--data", data, "--methods", "vlm-yoloe", "--option", "vlm-yoloe.vlm=stub:x",
                       "--option", f"vlm-yoloe.yoloe={tmp_path / 'yoloe-11l-seg.pt'}",
                       "--option", f"vlm-yoloe.text_encoder={tmp_path}"], capsys)
    assert rc == 2 and "option 'yoloe'" in err and "yoloe-11l-seg.pt" in err
    rc, _, err = _cli(["benchmark", "--data", data, "--methods", "vlm-yoloe", "--option", "vlm-yoloe.vlm=stub:x",
                       "--option", "vlm-yoloe.yoloe=y.yaml", "--option", "vlm-yoloe.embedings=e.npz"], capsys)
    assert rc == 2 and "unknown option(s) embedings" in err and "embeddings" in err


def test_factory_errors_name_the_option(tmp_path, monkeypatch):
    from vlm_adapters.base import MissingDependencyError
    from vlm_adapters.plugin import parse_vlm_spec, vlm_yoloe_method

    ok = {"vlm": "stub:x", "yoloe": "yoloe-11s-seg.yaml", "embeddings": str(tmp_path / "e.npz")}
    np.savez(tmp_path / "e.npz", names=np.array(VOCAB), embeddings=np.zeros((2, 8), np.float32))
    cases = [
        ({"vlm": None}, ValueError, "needs the option 'vlm'"),
        ({"yoloe": None}, ValueError, "needs the option 'yoloe'"),
        ({"embeddings": None}, ValueError, "'text_encoder'.*'embeddings'"),
        ({"vlm": "gpt4:x"}, ValueError, r"option 'vlm'.*qwen2\.5-vl:PATH"),
        ({"vlm": "qwen2.5-vl:"}, ValueError, "needs PATH"),
        ({"vlm": f"qwen2.5-vl:{tmp_path / 'Qwen2.5-VL-7B-Instruct'}"}, FileNotFoundError, "option 'vlm'.*does not exist"),
        ({"vlm": "openai:http://localhost:8000/v1"}, ValueError, "URL@MODEL"),
        ({"vlm": "openai:localhost:8000@m"}, ValueError, "http://"),
        ({"vlm": f"internvideo2.5:{tmp_path}"}, ValueError, "trust_remote_code=true"),
        ({"yoloe": str(tmp_path / "yoloe-11l-seg.pt")}, FileNotFoundError, "option 'yoloe'"),
        ({"text_encoder": str(tmp_path / "mobileclip_blt.ts")}, FileNotFoundError, "option 'text_encoder'"),
        ({"embeddings": str(tmp_path / "none.npz")}, FileNotFoundError, "option 'embeddings'"),
        ({"num_frames": "eight"}, ValueError, "option 'num_frames'"),
        ({"num_frames": "0"}, ValueError, "option 'num_frames'"),
        ({"conf": "high"}, ValueError, "option 'conf'"),
        ({"trust_remote_code": "maybe"}, ValueError, "option 'trust_remote_code'"),
        ({"frames": "8"}, TypeError, "unknown option.*num_frames"),
    ]
    for change, exc, msg in cases:
        with pytest.raises(exc, match=msg):
            vlm_yoloe_method(**{**ok, **change})
    np.savez(tmp_path / "bad.npz", names=np.array(VOCAB), embeddings=np.zeros((3, 8), np.float32))
    with pytest.raises(ValueError, match="option 'embeddings'"):
        vlm_yoloe_method(**{**ok, "embeddings": str(tmp_path / "bad.npz")})
    assert parse_vlm_spec("Qwen2.5-VL:/m/q") == ("qwen2.5-vl", "/m/q")
    assert parse_vlm_spec("stub: a b ") == ("stub", " a b ")
    monkeypatch.setitem(sys.modules, "ultralytics", None)  # the yoloe extra is missing
    with pytest.raises(MissingDependencyError, match=r'pip install "motionbits\[yoloe\]"'):
        vlm_yoloe_method(**ok)


def test_cli_missing_extra_is_a_clear_error(tmp_path, capsys, registered, monkeypatch):
    monkeypatch.setitem(sys.modules, "ultralytics", None)
    rc, _, err = _cli(["benchmark", "--data", str(tmp_path), "--methods", "vlm-yoloe",
                       "--option", "vlm-yoloe.vlm=stub:x", "--option", "vlm-yoloe.yoloe=yoloe-11s-seg.yaml",
                       "--option", "vlm-yoloe.text_encoder=" + __file__], capsys)
    assert rc == 2 and "method 'vlm-yoloe' cannot be built" in err and 'pip install "motionbits[yoloe]"' in err


# --------------------------------------------------------------------------- with torch + ultralytics


@pytest.fixture
def yoloe_deps():
    torch = pytest.importorskip("torch")
    pytest.importorskip("ultralytics")
    torch.manual_seed(0)
    return torch


H, W, T = 72, 96, 5


def _dataset(root: Path) -> Path:
    """Two scenes in MoRiBo layout: a red square sliding over a dark textured background."""
    rng = np.random.default_rng(0)
    for i, track in enumerate(["robot", "hand"]):
        scene = root / "data" / track / f"s{i}"
        (scene / "frames").mkdir(parents=True)
        bg = rng.integers(0, 60, (H, W, 3), dtype=np.uint8)
        for t in range(T):
            f = bg.copy()
            f[20:44, 10 + 4 * t : 34 + 4 * t] = (200, 30, 30)
            Image.fromarray(f).save(scene / "frames" / f"{t:05d}.png")
        gt = np.zeros((H, W), np.int32)
        gt[20:44, 10 + 4 * (T - 1) : 34 + 4 * (T - 1)] = 1
        write_label_map(scene / "gt.png", gt)
        (scene / "meta.json").write_text("{}")
    return root / "data"


def _embeddings(path: Path, torch) -> Path:
    np.savez(path, names=np.array(VOCAB), embeddings=torch.randn(len(VOCAB), 512).numpy())
    return path


def _options(emb: Path) -> dict[str, str]:
    """What `--option vlm-yoloe.KEY=VALUE` passes: strings only. conf=0: an untrained net's scores are tiny."""
    return {"vlm": "stub:" + ANSWER.replace("\n", "\\n"), "yoloe": "yoloe-11s-seg.yaml", "embeddings": str(emb),
            "device": "cpu", "conf": "0", "imgsz": "160", "max_det": "5", "num_frames": "3"}


@pytest.mark.filterwarnings("ignore:vlm-yoloe. no embedding")  # the calls after pytest.warns below
def test_benchmark_runner_with_stub_vlm_and_yoloe(tmp_path, registered, yoloe_deps):
    from motionbits.eval.benchmark import run_benchmark
    from motionbits.eval.dataset import discover_scenes, load_frames
    from motionbits.eval.table import format_table
    from vlm_adapters import MOVED_OBJECTS_PROMPT, StubVLM, VLMYOLOEMethod

    data = _dataset(tmp_path)
    method = make_method("vlm-yoloe", **_options(_embeddings(tmp_path / "vocab.npz", yoloe_deps)))
    assert isinstance(method, VLMYOLOEMethod) and isinstance(method.vlm, StubVLM)
    assert set(method.grounder.detector.known_phrases) == set(VOCAB)

    detected = []  # what the grounder asked YOLOE for, and what came back
    detect = method.grounder.detector.detect

    def spy(image, phrases):
        out = detect(image, phrases)
        detected.append((image.shape, list(phrases), out))
        return out

    method.grounder.detector.detect = spy
    with pytest.warns(UserWarning, match="green ball"):
        res, spf = run_benchmark(data, {"vlm-yoloe": method}, save_pred=tmp_path / "pred", progress=False)

    assert set(res) == {"vlm-yoloe"} and spf["vlm-yoloe"] > 0
    # the scores are those of the saved predictions, scored again here
    from motionbits.eval.dataset import evaluate_dataset

    rescored = evaluate_dataset(data, tmp_path / "pred" / "vlm-yoloe", progress=False)
    assert res["vlm-yoloe"]["macro"] == pytest.approx(rescored["macro"])
    table = format_table(res, seconds_per_frame=spf)
    assert any(line.startswith("vlm-yoloe ") for line in table.splitlines())
    # the VLM saw 3 of the 5 frames of each scene (full size) and the paper's prompt
    assert [(c.num_frames, c.frame_size, c.prompt, c.system) for c in method.vlm.calls] == [
        (3, (H, W), MOVED_OBJECTS_PROMPT, None)] * 2
    assert method.last_answer == ANSWER
    # the grounder got the phrases parsed from the stub's answer (those with embeddings) on the final frame
    assert method.last_phrases == VOCAB
    assert [(shape, phrases) for shape, phrases, _ in detected] == [((H, W, 3), VOCAB)] * 2
    assert all(set(d.phrases) <= set(VOCAB) and d.masks.shape[1:] == (H, W) for _, _, d in detected)
    assert sum(len(d) for _, _, d in detected) > 0  # conf=0: the masks path is exercised
    assert list(method.grounder.detector.model.model.names.values()) == VOCAB
    # the label map the runner scored: the last frame's shape, int32, labels 1..K
    for scene in discover_scenes(data):
        labels = method(load_frames(scene))
        assert labels.shape == (H, W) and labels.dtype == np.int32
        ids = np.unique(labels)
        assert set(ids[ids > 0]) == set(range(1, int(ids.max()) + 1))
        np.testing.assert_array_equal(read_label_map(tmp_path / "pred" / "vlm-yoloe" / scene.track /
                                                     f"{scene.name}.png"), labels)


def test_benchmark_cli_with_vlm_yoloe(tmp_path, capsys, registered, yoloe_deps):
    data = _dataset(tmp_path)
    opts = _options(_embeddings(tmp_path / "vocab.npz", yoloe_deps))
    argv = ["benchmark", "--data", str(data), "--methods", "flow-cc", "vlm-yoloe", "--quiet",
            "--save-pred", str(tmp_path / "pred"), "--json", str(tmp_path / "b.json")]
    for k, v in opts.items():
        argv += ["--option", f"vlm-yoloe.{k}={v}"]
    with pytest.warns(UserWarning, match="green ball"):
        rc, out, err = _cli(argv, capsys)
    assert rc == 0, err
    rows = [line.split()[0] for line in out.splitlines() if line.startswith(("flow-cc ", "vlm-yoloe "))]
    assert rows.count("vlm-yoloe") == 3 and rows.count("flow-cc") == 3  # two tracks + their average
    saved = json.loads((tmp_path / "b.json").read_text())
    assert set(saved["methods"]) == {"flow-cc", "vlm-yoloe"} and saved["seconds_per_frame"]["vlm-yoloe"] > 0
    assert set(saved["methods"]["vlm-yoloe"]["per_scene"]) == {"robot/s0", "hand/s1"}
    for key in ("robot/s0", "hand/s1"):
        pred = read_label_map(tmp_path / "pred" / "vlm-yoloe" / f"{key}.png")
        assert pred.shape == (H, W)
