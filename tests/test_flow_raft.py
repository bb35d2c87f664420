"""RAFT flow from a local weights file (motionbits/flow_raft.py, ``flow="raft:PATH"``).

The weights are torchvision's raft_small architecture with random values, saved here as a
state dict the way torchvision's release files are; the flow values are meaningless, the
tests check the plumbing (file -> architecture, input scaling, padding, output layout).
"""
from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")
optical_flow = pytest.importorskip("torchvision.models.optical_flow")

from motionbits import MotionBitsConfig, MotionBitsSegmenter  # noqa: E402
from motionbits.flow import make_flow  # noqa: E402
from motionbits.flow_raft import RAFTFlow  # noqa: E402


@pytest.fixture(scope="session")
def raft_file(tmp_path_factory):
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("raft") / "raft_small_random.pth"
    torch.save(optical_flow.raft_small(weights=None).state_dict(), path)
    return path


@pytest.fixture(scope="session")
def raft(raft_file):
    return RAFTFlow.from_file(raft_file, iters=2, device="cpu")


def _frames(h: int, w: int):
    rng = np.random.default_rng(0)
    a = rng.integers(0, 255, (h, w, 3), dtype=np.uint8)
    return a, np.roll(a, 2, axis=1)


def test_architecture_is_recognised_from_the_file(raft):
    assert raft.architecture == "raft_small" and raft.iters == 2
    assert "raft_small" in repr(raft)


def test_flow_is_the_models_last_estimate_on_scaled_frames(raft):
    a, b = _frames(128, 136)  # a multiple of 8, >= 128: no padding
    flow = raft(a, b)
    to = lambda f: torch.from_numpy(f).permute(2, 0, 1)[None].float() / 255 * 2 - 1  # noqa: E731
    with torch.inference_mode():
        expected = raft.model(to(a), to(b), num_flow_updates=2)[-1][0].permute(1, 2, 0).numpy()
    assert flow.shape == (128, 136, 2) and flow.dtype == np.float32
    np.testing.assert_allclose(flow, expected, atol=1e-5)


def test_small_and_odd_frames_are_padded_and_cropped(raft):
    a, b = _frames(50, 71)  # below RAFT's 128 px minimum and not a multiple of 8
    flow = raft(a, b)
    assert flow.shape == (50, 71, 2) and np.isfinite(flow).all()
    with pytest.raises(ValueError, match="same size|one size"):
        raft(a, b[:, :70])


@pytest.mark.parametrize("threads", [None, 2])
def test_thread_count_of_a_call(raft_file, threads):
    """Inside the segmenter's one-thread limit RAFT keeps it, unless given its own count."""
    from threadpoolctl import threadpool_limits

    flow = RAFTFlow.from_file(raft_file, iters=1, device="cpu", threads=threads)
    seen = []
    handle = flow.model.feature_encoder.register_forward_hook(lambda *a: seen.append(torch.get_num_threads()))
    try:
        with threadpool_limits(limits=1):
            flow(*_frames(128, 128))
            after = torch.get_num_threads()
    finally:
        handle.remove()
    assert seen == [threads or 1] and after == 1


def test_make_flow_builds_raft_from_a_spec(raft_file):
    flow = make_flow(f"raft:{raft_file}")
    assert isinstance(flow, RAFTFlow) and flow.iters == 12


def test_segmenter_runs_on_raft_flow(raft):
    from motionbits.synth import demo_clip

    seg = MotionBitsSegmenter(MotionBitsConfig(n_nodes=400, max_side=128), flow=raft)
    results = [seg.update(f) for f in demo_clip(n_frames=2, size=(96, 128)).frames]
    assert results[-1].labels.shape == (96, 128)
    assert results[-1].timings["flow"] > 0


def test_bad_weights_files(tmp_path, capsys):
    with pytest.raises(FileNotFoundError, match="no-such.pth"):
        make_flow(f"raft:{tmp_path / 'no-such.pth'}")
    wrong = tmp_path / "wrong.pth"
    torch.save({"conv.weight": torch.zeros(3, 3)}, wrong)
    with pytest.raises(ValueError, match="neither"):
        RAFTFlow.from_file(wrong)
    junk = tmp_path / "junk.pth"
    junk.write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match="torch.load"):
        RAFTFlow.from_file(junk)
    with pytest.raises(ValueError, match="raft:PATH"):
        RAFTFlow.from_spec("raft:")

    import cv2

    from motionbits.cli import main

    (tmp_path / "clip").mkdir()
    cv2.imwrite(str(tmp_path / "clip" / "000.png"), _frames(60, 80)[0])
    code = main(["segment", str(tmp_path / "clip"), "--flow", f"raft:{tmp_path / 'no-such.pth'}", "--quiet",
                 "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "no-such.pth" in err[0]


def test_unimportable_torchvision_is_a_missing_dependency(raft_file, monkeypatch):
    import sys

    from vlm_adapters import MissingDependencyError

    monkeypatch.setitem(sys.modules, "torchvision.models.optical_flow", None)
    with pytest.raises(MissingDependencyError, match=r"torchvision.*motionbits\[raft\]"):
        RAFTFlow.from_file(raft_file)
