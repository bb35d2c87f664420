"""SAM2 refinement (motionbits/refine_sam2.py): prompts, rejection, ids, loading, the CLI.

The prompt building and the accept/reject rules are pure numpy and are tested on label maps
built here. The SAM2 path runs a tiny random-weight transformers ``Sam2Model`` (128 px input)
written with ``save_pretrained`` and loaded back as a user's checkpoint folder would be;
its masks are random, so tests that need known masks replace `predict`.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from motionbits import MotionBitsConfig, MotionBitsSegmenter
from motionbits.refine_sam2 import (
    Sam2Prompt,
    Sam2Refiner,
    build_prompts,
    judge_refinement,
    merge_refinements,
    node_centres,
)

# a 60 x 80 image on a 6 x 8 node grid (10 px cells): MotionBit 1 on node rows 1-3, cols 1-3,
# MotionBit 2 next to it on cols 4-5; everything else static background
ROWS, COLS, H, W = 6, 8, 60, 80


def _scene() -> tuple[np.ndarray, np.ndarray]:
    nodes = np.zeros((ROWS, COLS), np.int32)
    nodes[1:4, 1:4] = 1
    nodes[1:4, 4:6] = 2
    labels = np.kron(nodes, np.ones((10, 10), np.int32))
    return labels, nodes


def _label_at(labels: np.ndarray, pts: np.ndarray) -> np.ndarray:
    return labels[pts[:, 1].astype(int), pts[:, 0].astype(int)]


def test_node_centres_match_the_segmenter_grid():
    from motionbits.nodes import NodeGrid

    grid = NodeGrid.build(H, W, 6, 4)
    assert np.allclose(node_centres((H, W), 6, 6), grid.points)


def test_prompts_from_a_known_label_map():
    labels, nodes = _scene()
    p1, p2 = build_prompts(labels, nodes)
    assert (p1.id, p2.id) == (1, 2)
    assert p1.box == (10, 10, 40, 40) and p2.box == (40, 10, 60, 40)
    pos = p1.points[p1.point_labels == 1]
    neg = p1.points[p1.point_labels == 0]
    assert len(pos) == 4 and len(neg) == 4
    assert tuple(pos[0]) == (25.0, 25.0)  # the deepest node of MotionBit 1 comes first
    assert (_label_at(labels, pos) == 1).all()  # positives on the MotionBit ...
    assert (_label_at(labels, neg) != 1).all()  # ... negatives off it
    assert len({tuple(p) for p in pos}) == 4  # spread: no point twice
    # all negatives come from its ring: within 2 nodes (20 px) of its node set
    assert ((neg[:, 0] >= 10 - 20) & (neg[:, 0] < 40 + 20) & (neg[:, 1] >= 10 - 20) & (neg[:, 1] < 40 + 20)).all()
    # with room for every candidate, the neighbours are both static background and MotionBit 2
    (wide,) = build_prompts(labels, nodes, [1], n_negative=100)
    neg_labels = set(_label_at(labels, wide.points[wide.point_labels == 0]).tolist())
    assert neg_labels == {0, 2}


def test_a_motionbit_without_nodes_is_prompted_at_its_deepest_pixel():
    labels, nodes = _scene()
    nodes[nodes == 2] = 0  # its mask is carried from an earlier frame: no node this frame
    (p2,) = build_prompts(labels, nodes, [2])
    pos = p2.points[p2.point_labels == 1]
    assert len(pos) == 1 and _label_at(labels, pos)[0] == 2
    assert 45 <= pos[0, 0] <= 55 and 20 <= pos[0, 1] <= 30  # centre of the 20 x 30 block


def test_rejection_reasons():
    labels, _ = _scene()
    motion, static = labels == 1, labels == 0
    kw = dict(min_iou=0.5, max_outside=0.1)
    grown = np.zeros_like(motion)
    grown[8:42, 8:42] = True  # the same block with a 2 px rim: a boundary correction
    assert judge_refinement(grown, motion, static, 20.0, **kw) is None
    assert judge_refinement(np.zeros_like(motion), motion, static, 20.0, **kw) == "empty"
    spill = motion.copy()
    spill[40:, :] = True  # onto the static floor, far from the block
    assert judge_refinement(spill, motion, static, 5.0, **kw) == "background"
    part = np.zeros_like(motion)
    part[10:20, 10:20] = True  # a corner of the block only
    assert judge_refinement(part, motion, static, 20.0, **kw) == "low_iou"


def test_merge_keeps_ids_and_never_takes_another_motionbits_pixels():
    labels, _ = _scene()
    refined = np.zeros(labels.shape, bool)
    refined[5:45, 5:50] = True  # grows into background and into MotionBit 2
    out = merge_refinements(labels, {1: refined})
    assert set(np.unique(out)) == {0, 1, 2}
    assert ((out == 2) == (labels == 2)).all()  # MotionBit 2 untouched
    assert ((out == 1) == (refined & (labels != 2))).all()
    shrunk = np.zeros(labels.shape, bool)
    shrunk[12:38, 12:38] = True
    out = merge_refinements(labels, {1: shrunk})
    assert ((out == 1) == shrunk).all() and (out[10:12, 10:40] == 0).all()  # shrinking frees pixels


# ----------------------------------------------------------------------------- the SAM2 model


@pytest.fixture(scope="session")
def sam2_dir(tmp_path_factory):
    torch = pytest.importorskip("torch")
    transformers = pytest.importorskip("transformers")
    s = 128
    cfg = transformers.Sam2Config(
        vision_config=dict(
            backbone_config=dict(
                model_type="sam2_hiera_det_model", hidden_size=16, image_size=[s, s], blocks_per_stage=[1, 1, 2, 1],
                embed_dim_per_stage=[16, 32, 64, 128], num_attention_heads_per_stage=[1, 1, 2, 2],
                window_size_per_stage=[4, 4, 4, 4], global_attention_blocks=[3],
                window_positional_embedding_background_size=[4, 4]),
            backbone_channel_list=[128, 64, 32, 16], backbone_feature_sizes=[[s // 4] * 2, [s // 8] * 2, [s // 16] * 2],
            fpn_hidden_size=32),
        prompt_encoder_config=dict(hidden_size=32, image_size=s, patch_size=16),
        mask_decoder_config=dict(hidden_size=32, mlp_dim=64, num_attention_heads=2, iou_head_hidden_dim=32),
    )
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("tiny-sam2")
    transformers.Sam2Model(cfg).save_pretrained(path)
    transformers.Sam2Processor(image_processor=transformers.Sam2ImageProcessor(
        size={"height": s, "width": s}, mask_size={"height": s // 4, "width": s // 4})).save_pretrained(path)
    return path


@pytest.fixture(scope="session")
def refiner(sam2_dir):
    return Sam2Refiner.from_pretrained(str(sam2_dir), device="cpu")


def test_prompts_reach_the_model_and_masks_come_back_at_frame_size(refiner):
    torch = pytest.importorskip("torch")
    labels, nodes = _scene()
    prompts = build_prompts(labels, nodes)
    prompts[1] = Sam2Prompt(2, prompts[1].box, prompts[1].points[:3], prompts[1].point_labels[:3])  # ragged
    seen = {}

    def hook(module, args, kwargs):
        seen.update(points=kwargs["input_points"].clone(), labels=kwargs["input_labels"].clone(),
                    boxes=kwargs["input_boxes"].clone())

    handle = refiner.model.prompt_encoder.register_forward_pre_hook(hook, with_kwargs=True)
    try:
        frame = np.random.default_rng(0).integers(0, 255, (H, W, 3), dtype=np.uint8)
        masks = refiner.predict(frame, prompts)
    finally:
        handle.remove()
    assert masks.shape == (2, H, W) and masks.dtype == bool
    assert seen["points"].shape == (1, 2, 8, 2) and seen["boxes"].shape == (1, 2, 4)
    assert seen["labels"][0, 0].tolist() == [1, 1, 1, 1, 0, 0, 0, 0]
    assert seen["labels"][0, 1].tolist() == [1, 1, 1, -10, -10, -10, -10, -10]  # padding ignored by SAM2
    # coordinates scaled from the 80 x 60 frame to SAM2's 128 x 128 input
    assert torch.allclose(seen["boxes"][0, 0], torch.tensor([10 * 1.6, 10 * 128 / 60, 40 * 1.6, 40 * 128 / 60]))


def test_segmenter_refines_with_ids_kept_and_counts(refiner, monkeypatch):
    """End to end on the demo clip with the real model, then with known masks (SAM2's
    answer replaced): an accepted refinement keeps the id and re-measures the record."""
    from motionbits.synth import demo_clip

    clip = demo_clip(n_frames=3, size=(120, 160))
    cfg = MotionBitsConfig(n_nodes=1600)
    plain_seg = MotionBitsSegmenter(cfg)
    plain = [plain_seg.update(f) for f in clip.frames]
    assert plain[-1].ids, "the demo clip should give MotionBits"

    def one_px_larger(frame, prompts):  # an agreeing refinement: each motion mask grown by 1 px
        import cv2

        return np.stack([cv2.dilate((current == p.id).astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
                         for p in prompts]) if prompts else np.zeros((0, *frame.shape[:2]), bool)

    seg = MotionBitsSegmenter(cfg)
    seg.refiner = refiner
    monkeypatch.setattr(refiner, "predict", one_px_larger)
    for f, ref in zip(clip.frames, plain):
        current = ref.labels
        out = seg.update(f)
    assert out.ids == plain[-1].ids  # same MotionBits, same ids
    assert seg.refiner.last_stats["accepted"] == len(out.ids)
    for mb in out.motionbits:
        assert mb.area == int((out.labels == mb.id).sum()) >= int((plain[-1].labels == mb.id).sum())
    assert (out.node_labels == plain[-1].node_labels).all()  # the segmenter's own state is unchanged
    assert "refine" in out.timings
    monkeypatch.undo()
    whole = lambda frame, prompts: np.ones((len(prompts), *frame.shape[:2]), bool)  # noqa: E731
    monkeypatch.setattr(refiner, "predict", whole)
    out = seg.update(clip.frames[-1])
    assert seg.refiner.last_stats["rejected"]["background"] == len(out.ids) > 0
    assert (out.labels > 0).sum() < out.labels.size // 2  # rejected: the motion masks stayed


def test_real_model_runs_in_the_segmenter(sam2_dir):
    from motionbits.synth import demo_clip

    clip = demo_clip(n_frames=2, size=(120, 160))
    seg = MotionBitsSegmenter(MotionBitsConfig(n_nodes=1600, refine="sam2", sam2_path=str(sam2_dir)))
    results = [seg.update(f) for f in clip.frames]
    stats = seg.refiner.last_stats
    assert stats["prompted"] == len(stats["decisions"]) == stats["accepted"] + sum(stats["rejected"].values())
    assert set(results[-1].ids) <= set(stats["decisions"])  # a rejected mask keeps its id too
    assert seg.refiner.totals["frames"] == 2


# ----------------------------------------------------------------------------- errors and the CLI


def _write_clip(folder, n_frames: int) -> str:
    import cv2

    from motionbits.synth import demo_clip

    folder.mkdir()
    for i, f in enumerate(demo_clip(n_frames=n_frames, size=(120, 160)).frames):
        cv2.imwrite(str(folder / f"{i:03d}.png"), f[..., ::-1])
    return str(folder)


def test_missing_sam2_path_is_a_one_line_error(tmp_path, capsys):
    from motionbits.cli import main

    with pytest.raises(FileNotFoundError, match="no-such-sam2"):
        MotionBitsSegmenter(MotionBitsConfig(refine="sam2", sam2_path=str(tmp_path / "no-such-sam2")))
    with pytest.raises(ValueError, match="needs sam2_path"):
        MotionBitsConfig(refine="sam2")
    with pytest.raises(ValueError, match="refine"):
        MotionBitsConfig(refine="sam3")
    code = main(["segment", _write_clip(tmp_path / "clip", 1), "--refine", "sam2", "--sam2",
                 str(tmp_path / "no-such-sam2"), "--quiet", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "no-such-sam2" in err


def test_cli_writes_refinement_counts(sam2_dir, tmp_path):
    from motionbits.cli import main

    out = tmp_path / "out"
    assert main(["segment", _write_clip(tmp_path / "clip", 3), "--nodes", "1600", "--refine", "sam2", "--sam2", str(sam2_dir),
                 "--quiet", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    ref = summary["refinement"]
    assert ref["method"] == "sam2" and ref["frames"] == 3
    assert ref["prompted"] == ref["accepted"] + sum(ref["rejected"].values()) > 0
    assert set(ref["rejected"]) == {"empty", "background", "low_iou"}
    assert "refine" in summary["timings_ms"]["stages_median"]


def test_nothing_heavy_is_imported_unless_asked():
    code = (
        "import sys, numpy as np\n"
        "from motionbits import MotionBitsConfig, MotionBitsSegmenter\n"
        "import motionbits.refine_sam2, motionbits.flow_raft\n"
        "from motionbits.synth import demo_clip\n"
        "seg = MotionBitsSegmenter(MotionBitsConfig(n_nodes=400))\n"
        "for f in demo_clip(n_frames=2, size=(60, 80)).frames: seg.update(f)\n"
        "heavy = [m for m in ('torch', 'transformers', 'torchvision') if m in sys.modules]\n"
        "assert not heavy and seg.refiner is None, heavy\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_an_unimportable_sam2_class_is_a_missing_dependency(sam2_dir, monkeypatch):
    """As when torchvision's compiled ops do not load: transformers cannot import the class."""
    from vlm_adapters import MissingDependencyError

    lazy = sys.modules["transformers"]
    monkeypatch.delattr(lazy, "Sam2Model", raising=False)
    monkeypatch.setitem(sys.modules, "transformers.models.sam2.modeling_sam2", None)
    with pytest.raises(MissingDependencyError, match=r"could not import transformers.Sam2Model.*motionbits\[sam2\]"):
        Sam2Refiner.from_pretrained(str(sam2_dir))
