"""gpmotion: evolve controllers for physically simulated articulated figures."""
from .cache import configure_numba as _configure_numba
_configure_numba()     # numba's cache in the user's cache folder, before any kernel compiles
import importlib as _importlib
import importlib.util as _ilu
import sys as _sys
import types as _types
from pathlib import Path as _Path


def _mount_plugin_packages():
    """Installed, ``primitives/`` and ``tasks/`` are gpmotion.primitives and
    gpmotion.tasks (setuptools package-dir).  Imported straight from a source
    checkout (``python -m pytest`` puts the repo first on sys.path), they sit
    beside this folder instead: mount them under the same names."""
    here = _Path(__file__).resolve().parent
    for sub in ("primitives", "tasks"):
        name = f"{__name__}.{sub}"
        init = here.parent / sub / "__init__.py"
        if name in _sys.modules or (here / sub).exists() or not init.exists():
            continue
        if _ilu.find_spec(name) is not None:        # an editable install's finder
            continue
        spec = _ilu.spec_from_file_location(name, init, submodule_search_locations=[str(init.parent)])
        module = _ilu.module_from_spec(spec)
        _sys.modules[name] = module
        spec.loader.exec_module(module)


_mount_plugin_packages()
from .version import __version__

# Public names, resolved on first use (PEP 562): `import gpmotion` and the
# simulator stay light, and only what a program touches is imported (the
# harness, DEAP and the CLI load when a name of theirs is first used).
_LAZY = {
    "check_family": "check", "check_primitive": "check", "check_task": "check",
    "Evaluation": "evaluation", "make_evaluator": "evaluators", "make_family": "families",
    "SpecError": "figures", "compile_spec": "figures", "figure_names": "figures",
    "load_figure": "figures", "register_figure": "figures",
    "STANDARD_PRIMITIVES": ("gp.primitives", "STANDARD"), "primitive": "gp.primitives",
    "GPSettings": "gp.settings",
    "evaluate_population": "toolbox", "make_toolbox": "toolbox",
    "Figure": "model", "Model": "model", "Scene": "model", "make_scene": "model",
    "load_plugins": ("plugins", "load_folder"), "read_json": "records",
    "load_controller": "replay", "replay_genome": "replay", "save_controller": "controller_file",
    "RunConfig": "run", "run": "run",        # the function `gpmotion.run(cfg)`, not the module
    "Trajectory": "sim.rollout", "rollout": "sim.rollout", "simulate": "sim.rollout",
    "Ease": "task", "Task": "task", "Term": "task", "get_task": "task", "register_task": "task",
    "task_ids": "task", "task_names": "task",
    "compose": ("compose", None),            # the package: composite motions
}
__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name):
    target = _LAZY.get(name)
    if target is None:
        raise AttributeError(f"module 'gpmotion' has no attribute {name!r}")
    module, attr = (target, name) if isinstance(target, str) else target
    value = _importlib.import_module(f"{__name__}.{module}")
    return value if attr is None else getattr(value, attr)


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


class _Package(_types.ModuleType):
    """Importing the submodule gpmotion.run would bind the name ``run`` to the
    module; the public name is the function, so that binding is not kept."""

    def __setattr__(self, name, value):
        if name == "run" and isinstance(value, _types.ModuleType):
            return
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package
