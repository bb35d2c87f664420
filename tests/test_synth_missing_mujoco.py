"""Without MuJoCo, the generator says how to install it (outside test_synth_mujoco.py,
whose module-level skip would hide exactly this case)."""

import importlib.util
import sys

import pytest

from motionbits.synth import mujoco_backend as mjb


def test_missing_mujoco_message(monkeypatch):
    if importlib.util.find_spec("mujoco") is not None:  # installed: make it unimportable
        monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(ImportError, match=r"pip install motionbits\[sim\]"):
        mjb.import_mujoco()
    assert "pip install motionbits[sim]" in mjb.render_check()
