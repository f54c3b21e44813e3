"""Fixtures shared by several test modules."""
import sys

import pytest


@pytest.fixture
def forget_plugins():
    """Unregister the primitives a test's plugin folder adds: the default GP
    function set is every registered primitive, so later tests must not see them."""
    from gpmotion.gp import primitives
    primitives.load_builtin()                   # built-ins stay registered
    before, mods = set(primitives.names()), set(sys.modules)
    yield
    for name in set(primitives.names()) - before:
        primitives.unregister(name)
    for m in set(sys.modules) - mods:
        if m.startswith("gpmotion_plugin_"):
            del sys.modules[m]
