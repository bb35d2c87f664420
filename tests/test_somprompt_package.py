"""Package-level checks: docstring examples run, dependency direction holds."""

import doctest
import importlib
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

import somprompt

MODULES = sorted(m.name for m in pkgutil.iter_modules(somprompt.__path__, "somprompt."))


@pytest.mark.parametrize("name", ["somprompt"] + MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0


def test_public_api_is_exported():
    for name in somprompt.__all__:
        assert hasattr(somprompt, name), name


SHARED = ("motionbits", "motionbits.frames", "motionbits.objects")  # the light shared modules


def test_imports_only_the_shared_light_part_of_motionbits():
    code = (
        "import sys, somprompt, somprompt.testing; "
        f"bad = [m for m in sys.modules if m.split('.')[0] in ('motionbits', 'vlm_adapters', 'torch', "
        f"'transformers') and m not in {SHARED!r}]; "
        "print(bad); sys.exit(1 if bad else 0)"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    src = Path(somprompt.__file__).parent
    for path in src.glob("*.py"):
        text = path.read_text()
        imported = set(re.findall(r"^\s*(?:from|import) (motionbits[\w.]*)", text, re.M))
        # the video reader is imported lazily, only for a path given to GroundedVQA
        assert imported <= set(SHARED) | {"motionbits.video", "motionbits.video_writer"}, (path, imported)
        assert "vlm_adapters" not in text.replace("``vlm_adapters``", ""), path
