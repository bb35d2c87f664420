"""The toolkit as a user installs it: `pip install .` (a wheel, not editable).

Run by .ci/run with MOTIONBITS_INSTALLED=<folder the wheel was installed into> first on
PYTHONPATH, from a folder outside the checkout, so nothing can come from the sources.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

INSTALLED = Path(os.environ["MOTIONBITS_INSTALLED"]).resolve()


def test_packages_come_from_the_installed_wheel():
    import motionbits
    import somprompt
    import vlm_adapters

    for module in (motionbits, somprompt, vlm_adapters):
        assert Path(module.__file__).resolve().is_relative_to(INSTALLED), module.__file__
    templates = somprompt.default_prompts_dir()
    assert not templates.is_symlink() and templates.resolve().is_relative_to(INSTALLED)
    assert "som_vqa" in somprompt.list_prompts() and "moved_rigid_bodies" in somprompt.list_prompts()


def test_readme_snippet(tmp_path):
    from motionbits.synth import demo_clip
    from motionbits.video_writer import write_h264

    write_h264(demo_clip(n_frames=6, size=(120, 160)).frames, tmp_path / "clip.mp4")
    os.chdir(tmp_path)

    from motionbits import MotionBitsConfig, MotionBitsSegmenter
    from somprompt import GroundedVQA
    from vlm_adapters import StubVLM

    vqa = GroundedVQA(MotionBitsSegmenter(MotionBitsConfig(n_nodes=900, max_side=240)),
                      StubVLM("The mug [1] moved."))
    res = vqa("clip.mp4", question="Which object moved?")
    assert res.answer == "The mug [1] moved." and res.cited_ids == [res.registry.ids[0]]
    [(obj_id, mask)] = res.masks.items()
    assert mask.shape == (120, 160) and mask.dtype == bool and mask.any()
    assert np.array_equal(mask, res.label_maps[-1] == obj_id)


def test_python_m_motionbits():
    run = subprocess.run([sys.executable, "-m", "motionbits", "--help"], capture_output=True, text=True)
    assert run.returncode == 0 and "segment" in run.stdout, run.stderr
