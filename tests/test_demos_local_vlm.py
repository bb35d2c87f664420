"""The web demo with a local transformers model folder as its VLM (``--vlm FOLDER``), on the
tiny random-weight Qwen2.5-VL checkpoint that tests/test_vlm_transformers.py builds."""

from __future__ import annotations

import pytest

pytest.importorskip("torch")
pytest.importorskip("transformers")
pytest.importorskip("tokenizers")
pytest.importorskip("av")
pytest.importorskip("pycocotools")

from test_vlm_transformers import qwen_dir  # noqa: E402,F401  (fixture: the tiny checkpoint folder)

from demos.app import DemoConfig, _Handlers  # noqa: E402
from demos.media import write_demo_clip  # noqa: E402


def test_app_answers_with_a_local_model_folder(qwen_dir, tmp_path):  # noqa: F811
    clip = write_demo_clip(tmp_path / "clip.mp4", n_frames=4, size=(120, 160))
    h = _Handlers(DemoConfig(vlm=str(qwen_dir), max_new_tokens=4), tmp_path)
    seg = h.run(str(clip), 100, 0, 0, 1, progress=lambda *a, **k: None)[4]
    answer, image, status = h.ask(seg, "What moved?")
    assert type(h._vlm).__name__ == "Qwen2_5_VLAdapter"  # picked from config.json's model_type
    assert status.startswith("Highlighted:"), status
    assert isinstance(answer, str) and image.shape == (120, 160, 3)
