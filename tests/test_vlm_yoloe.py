"""YOLOEGrounder on a real YOLOE network built from its ultralytics YAML (random weights).

No YOLOE weights or MobileCLIP text encoder can be downloaded here, so the network is
untrained and its detections are arbitrary: these tests check the plumbing (embeddings in,
phrases set as classes, masks at the image size, a valid label map out). Exact label
placement is tested with a stub detector in test_vlm_core.py.
"""
from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("ultralytics")

from vlm_adapters import StubVLM, YOLOEDetector, YOLOEGrounder, make_vlm_yoloe_method, masks_to_label_map  # noqa: E402


@pytest.fixture(scope="module")
def detector():
    torch.manual_seed(0)
    # conf=0: an untrained network's scores are tiny; keep every box so masks flow through
    return YOLOEDetector.from_pretrained("yoloe-11s-seg.yaml", conf=0.0, imgsz=160, max_det=5, device="cpu")


def _image(h=120, w=160):
    rng = np.random.default_rng(1)
    img = rng.integers(0, 60, (h, w, 3), dtype=np.uint8)
    img[30:80, 40:110] = (200, 30, 30)
    return img


def _check_label_map(labels, shape):
    assert labels.shape == shape and labels.dtype == np.int32
    ids = np.unique(labels)
    k = int(ids.max())
    assert set(ids[ids > 0]) == set(range(1, k + 1))  # 1..K, no gaps


def test_precomputed_embeddings_end_to_end(detector):
    grounder = YOLOEGrounder(detector, max_instances=5)
    emb = torch.randn(2, 512)
    grounder.set_classes(["red block", "drawer"], emb)
    assert set(detector.known_phrases) >= {"red block", "drawer"}
    det = grounder.detect("- red block: cube\n- drawer: slides open", _image())
    assert det.masks.shape[1:] == (120, 160) and det.masks.dtype == bool
    assert 0 < len(det) == len(det.scores) == len(det.phrases) <= 5  # conf=0: masks path exercised
    assert set(det.phrases) <= {"red block", "drawer"}
    assert detector.model.model.names == {0: "red block", 1: "drawer"} or list(
        detector.model.model.names.values()) == ["red block", "drawer"]
    labels = grounder.ground("- red block: cube\n- drawer: slides open", _image())
    _check_label_map(labels, (120, 160))
    # label k is painted from the detections, highest score first
    det = detector.detect(_image(), ["red block", "drawer"])
    assert np.array_equal(labels, masks_to_label_map(det.masks, det.scores, max_instances=5))
    assert labels.max() == len(np.unique(labels)) - 1 <= 5


def test_text_encoder_callable_goes_through_yoloe_text_head(detector):
    seen = []

    def encoder(names):  # stands in for MobileCLIP: raw (N, 512) text features
        seen.append(list(names))
        g = torch.Generator().manual_seed(len(names))
        return torch.randn(len(names), 512, generator=g)

    det = YOLOEDetector(detector.model, text_encoder=encoder, conf=0.0, imgsz=160, max_det=3, device="cpu")
    out = det.detect(_image(), ["laptop lid"])
    assert seen == [["laptop lid"]] and set(out.phrases) <= {"laptop lid"}
    det.detect(_image(), ["laptop lid"])
    assert seen == [["laptop lid"]]  # embedding cached, encoder not called again


def test_unknown_phrase_without_text_encoder_is_a_clear_error(detector):
    det = YOLOEDetector(detector.model, conf=0.0, imgsz=160, device="cpu")
    with pytest.raises(ValueError, match="set_classes"):
        det.detect(_image(), ["never registered"])


def test_missing_files_are_clear_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="yoloe-11l-seg.pt"):
        YOLOEGrounder.from_pretrained(tmp_path / "yoloe-11l-seg.pt")
    with pytest.raises(FileNotFoundError, match="mobileclip"):
        YOLOEGrounder.from_pretrained("yoloe-11s-seg.yaml", text_encoder=tmp_path / "mobileclip_blt.ts")


def test_benchmark_method_with_yoloe(detector):
    grounder = YOLOEGrounder(detector)
    grounder.set_classes(["wooden cube"], torch.randn(1, 1, 512))
    method = make_vlm_yoloe_method(StubVLM("- wooden cube: pushed to the left"), grounder, num_frames=3)
    video = np.stack([_image() for _ in range(6)])
    labels = method(video)
    _check_label_map(labels, (120, 160))
    # the method's label map is the grounder's on the final frame
    assert np.array_equal(labels, grounder.ground("- wooden cube: pushed to the left", video[-1]))
    assert method.last_phrases == ["wooden cube"]
