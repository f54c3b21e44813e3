"""Fixtures shared by several test modules."""
import importlib
import sys

import pytest
from hypothesis import settings

# No test depends on the machine's speed: a loaded CI core may take seconds
# for an example that takes milliseconds here (a kernel compiling, a busy neighbour).
settings.register_profile("gpmotion", deadline=None)
settings.load_profile("gpmotion")

# Process-wide registries a test may add to (plugin folders, primitives, tasks,
# figures, families).  Each test starts from them as loaded at start-up, so a
# test never sees what another test loaded, in any order, in any worker
# (pytest -n: a pool's workers are sent every plugin the process holds).
_REGISTRIES = [("gpmotion.plugins", "_LOADED"), ("gpmotion.plugins", "_FOLDERS"),
               ("gpmotion.plugins", "_SOURCES"), ("gpmotion.plugins", "_ENTRY_POINTS"),
               ("gpmotion.gp.primitives", "_REGISTRY"), ("gpmotion.task", "_TASKS"),
               ("gpmotion.figures", "_REGISTRY"), ("gpmotion.figures", "_CACHE"),
               ("gpmotion.families.base", "_FAMILIES")]


@pytest.fixture(autouse=True)
def registries_per_test():
    from gpmotion import plugins
    plugins.load_builtin()
    held = [getattr(importlib.import_module(m), name) for m, name in _REGISTRIES]
    saved = [dict(d) for d in held]
    mods = set(sys.modules)
    yield
    for d, s in zip(held, saved):
        d.clear()
        d.update(s)
    for m in set(sys.modules) - mods:
        if m.startswith("gpmotion_plugin_"):
            del sys.modules[m]

