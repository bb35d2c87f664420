"""Package-level checks: docstring examples run, dependency direction holds."""

import doctest
import importlib
import pkgutil
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


def test_imports_neither_motionbits_nor_vlm_adapters():
    code = (
        "import sys, somprompt, somprompt.testing; "
        "bad = [m for m in sys.modules if m.split('.')[0] in ('motionbits', 'vlm_adapters', 'torch', 'transformers')]; "
        "print(bad); sys.exit(1 if bad else 0)"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    src = Path(somprompt.__file__).parent
    for path in src.glob("*.py"):
        text = path.read_text()
        assert "import motionbits" not in text and "from motionbits" not in text, path
        assert "vlm_adapters" not in text.replace("``vlm_adapters``", ""), path
