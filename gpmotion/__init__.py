"""gpmotion: evolve controllers for physically simulated articulated figures."""
from .figures import SpecError, compile_spec, figure_names, load_figure, register_figure
from .model import Figure, Model, Scene, make_scene
from .sim.rollout import Trajectory, rollout, simulate

__version__ = "0.1.0"
__all__ = ["Figure", "Model", "Scene", "SpecError", "Trajectory", "compile_spec", "figure_names",
           "load_figure", "make_scene", "register_figure", "rollout", "simulate"]
