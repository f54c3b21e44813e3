"""What the GP family reads from a task: its function set, terminals, targets
and search defaults.

A task declares them as one object, so the task layer itself knows nothing of
GP (BSR and keyframes read other things from the same task)::

    from gpmotion.gp.settings import GPSettings

    @register_task
    class LampHop(Task):
        ...
        gp = GPSettings(defaults={"generations": 24}, paper_terminals=("px", ...))

A task that chooses them from its parameters replaces its instance's copy in
``__init__`` (``self.gp = replace(self.gp, terminals=...)``).  A task that
declares nothing gets :data:`DEFAULT`: the standard function set, every sense
of the figure as a terminal, angle targets, the family's search defaults.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

from . import targets as gp_targets
from .primitives import STANDARD

# what a task wrote before GP's settings were one object: refused with the new spelling
LEGACY = {"primitives": "primitives", "terminals": "terminals", "gp_targets": "targets",
          "gp_defaults": "defaults", "paper_terminals": "paper_terminals"}


@dataclass(frozen=True)
class GPSettings:
    """GP's view of a task (checked when the task's class is defined).

    ``primitives``: the function set, in opcode order (a plugin's new
    primitive changes no existing task's runs); ``terminals``: the sense
    names trees read (None: every sense of the figure); ``targets``: what a
    tree's output means (:mod:`gpmotion.gp.targets`, ``--targets``);
    ``defaults``: search settings over the family's (e.g. a population);
    ``paper_terminals``: the paper's terminal set (the gritz-hahn preset)."""
    primitives: tuple[str, ...] = STANDARD
    terminals: tuple[str, ...] | None = None
    targets: str = "angle"
    defaults: Mapping = field(default_factory=dict)
    paper_terminals: tuple[str, ...] = ()

    def __post_init__(self):
        for name in ("primitives", "paper_terminals") + (("terminals",) if self.terminals is not None else ()):
            value = getattr(self, name)
            if not isinstance(value, (tuple, list)) or not all(isinstance(n, str) for n in value):
                raise ValueError(f"GPSettings {name}: a tuple of names, got {value!r}")
            object.__setattr__(self, name, tuple(value))
        if not self.primitives:
            raise ValueError("GPSettings primitives: name at least one primitive")
        try:
            gp_targets.parse(self.targets)
        except ValueError as e:
            raise ValueError(f"GPSettings targets: {e}") from None
        if not isinstance(self.defaults, Mapping) or not all(isinstance(k, str) for k in self.defaults):
            raise ValueError(f"GPSettings defaults: a dict of search settings, got {self.defaults!r}")
        object.__setattr__(self, "defaults", MappingProxyType(dict(self.defaults)))


DEFAULT = GPSettings()


def gp_settings(task) -> GPSettings:
    """The task's GP settings (:data:`DEFAULT` when it declares none)."""
    legacy = [k for k in LEGACY if hasattr(task, k)]
    if legacy:
        raise ValueError(f"task {task.name}: {', '.join(legacy)} belong to GP's settings: declare "
                         f"gp = GPSettings({', '.join(f'{LEGACY[k]}=...' for k in legacy)}) "
                         "(gpmotion.gp.settings)")
    try:
        settings = task.gp
    except AttributeError:
        settings = DEFAULT
    if not isinstance(settings, GPSettings):
        raise ValueError(f"task {task.name}: gp must be a gpmotion.gp.settings.GPSettings, "
                         f"got {type(settings).__name__}")
    return settings


def terminal_names(task) -> list[str]:
    """The sense names a task's GP trees read, each checked against its figure
    (a task sense the task derives counts as known)."""
    settings = gp_settings(task)
    names = (list(settings.terminals) if settings.terminals is not None
             else list(task.figure.sense_names))
    derived = {s.name for s in task.task_senses()}
    for n in names:
        if n not in derived:
            task.figure.sense_index(n)    # an unknown sense: one line naming the figure's
    return names
