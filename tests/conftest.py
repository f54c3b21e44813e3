"""Fixtures shared by several test modules."""
import sys

import pytest


@pytest.fixture
def forget_plugins():
    """Forget the primitives a test's plugin folder registers, so another test may
    register a primitive of the same name from another folder."""
    from gpmotion.gp import primitives
    primitives.load_builtin()                   # built-ins stay registered
    saved, mods = dict(primitives._REGISTRY), set(sys.modules)
    yield
    primitives._REGISTRY.clear()
    primitives._REGISTRY.update(saved)
    for m in set(sys.modules) - mods:
        if m.startswith("gpmotion_plugin_"):
            del sys.modules[m]
