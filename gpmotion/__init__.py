"""gpmotion: evolve controllers for physically simulated articulated figures."""
import importlib.util as _ilu
import sys as _sys
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

from .check import check_family, check_primitive, check_task
from .evaluation import Evaluation
from .evaluators import make_evaluator
from .families import make_family
from .figures import SpecError, compile_spec, figure_names, load_figure, register_figure
from .gp.primitives import STANDARD as STANDARD_PRIMITIVES, primitive
from .toolbox import evaluate_population, make_toolbox
from .model import Figure, Model, Scene, make_scene
from .plugins import load_folder as load_plugins
from .records import read_json
from .replay import load_controller, replay_genome
from .controller_file import save_controller
from .run import RunConfig, run     # the function: `gpmotion.run(cfg)`; the module is gpmotion.run's home
from .sim.rollout import Trajectory, rollout, simulate
from .task import Ease, Task, Term, get_task, register_task, task_ids, task_names
from . import compose  # composite motions: script language, composites, transition search, robust starts

__all__ = ["Ease", "Task", "Term", "check_family", "check_primitive", "check_task", "get_task", "register_task",
           "task_names", "task_ids", "STANDARD_PRIMITIVES", "Figure", "Model", "Scene", "SpecError", "Trajectory", "compile_spec",
           "figure_names", "load_figure", "make_scene", "register_figure", "rollout", "simulate",
           "primitive", "load_plugins", "RunConfig", "run", "load_controller", "replay_genome",
           "save_controller", "read_json", "make_family", "make_evaluator", "Evaluation",
           "make_toolbox", "evaluate_population", "__version__"]
