"""The docstring examples of motionbits and vlm_adapters run (somprompt's: test_somprompt_package.py)."""

import doctest
import importlib
import pkgutil

import pytest

import motionbits
import vlm_adapters

MODULES = sorted(
    m.name for pkg in (motionbits, vlm_adapters)
    for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + ".")
    if not m.name.endswith(".__main__")  # runs the command line when imported
)


@pytest.mark.parametrize("name", ["motionbits", "vlm_adapters"] + MODULES)
def test_doctests(name):
    try:
        module = importlib.import_module(name)
    except ImportError as exc:  # a module of an optional extra that is not installed
        pytest.skip(f"{name}: {exc}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} doctest examples of {name} failed"
