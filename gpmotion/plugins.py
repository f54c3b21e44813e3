"""Plugin folders: every ``*.py`` file in them is imported once; the files
register primitives (``@primitive``) and tasks (``@register_task``) as they load."""
from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path


def import_package(package: str) -> None:
    """Import every module of a built-in plugin package (gpmotion.tasks, ...)."""
    pkg = importlib.import_module(package)
    for info in pkgutil.iter_modules(pkg.__path__):
        if not info.name.startswith("_"):
            importlib.import_module(f"{package}.{info.name}")


def load_folder(folder: str | Path) -> list[str]:
    """Import a user's plugin folder; returns the primitive names it added."""
    from .gp import primitives
    from .task import _load_builtin
    _load_builtin()               # built-ins first, so a clash names the user's file
    primitives.load_builtin()
    return primitives.load_plugins(folder)
