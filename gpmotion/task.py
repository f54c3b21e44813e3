"""Tasks: what a motion should achieve, as a score over a batched Trajectory.

A task is one small file in ``tasks/`` (or a user's ``--plugins`` folder):

    @register_task
    class LampHop(Task):
        name = "lamp_hop"
        version = 1                      # its id: "lamp_hop-v1"
        figure = "lamp"
        params = {"distance": 0.4, "seconds": 3.0}
        terms = (Term("distance", 1.0, main=True), Term("late", 0.1, phase=(0.2, 0.6)))
        def measure(self, traj): return {"distance": ..., "late": ...}

Scores are costs (lower is better, as Gritz & Hahn); BSR's serial search is
told the same numbers and minimizes them.  Every term's raw value, weight
and phase-in factor are returned, so logs and replays show why a controller
scored as it did (like Gymnasium's ``reward_info``).

A class declares *names and defaults*; an instance holds what they resolve
to: ``Task.figure`` is the figure's registry name and ``task.figure`` the
compiled :class:`~gpmotion.model.Figure` (the task's own copy);
``Task.params`` holds the defaults and ``task.params`` the values in force.

Versions (as Gymnasium's ``register(id=...)``): a task's id is ``name-vN``;
the bare name means the newest registered version.  Publish a changed score
as a new version (a class with ``version = 2``) so results recorded under
the old id keep their meaning.  Records store the id; a record written
before ids existed names the bare task, which means its v1 (:func:`task_id`
with ``recorded=True``).

A task holds nothing a controller family owns: GP's function set,
terminals, targets and search defaults are GP's, declared on the task as
``gp = GPSettings(...)`` (:mod:`gpmotion.gp.settings`) and read by the GP
family only.
"""
from __future__ import annotations

import copy
import math
import re
import warnings
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from .figures import load_figure
from .model import Figure, Scene, make_scene

WORST = 1e6        # cost of a diverged episode: finite, so JSON logs stay valid
PARAM_BOUND = 1e6  # |numeric task parameter| ≤ this: weights × values stay far from overflow


@dataclass(frozen=True)
class Term:
    """A named score term: ``weight × phase(progress) × value``.

    ``phase = (a, b)``: the factor ramps from 0 at run progress a to 1 at b
    (progress = generation / generations), so style points arrive after the
    main goal has been learned, as in Gritz & Hahn.

    ``param``: the weight is a task parameter, ``weight × params[param]``
    (``weight`` is then its sign and scale); a task instance holds its terms
    with the weights resolved (:meth:`under`).
    """
    name: str
    weight: float
    phase: tuple[float, float] = (0.0, 0.0)
    main: bool = False
    doc: str = ""
    param: str = ""

    def factor(self, progress: float) -> float:
        return ramp(self.phase, progress)

    def under(self, params: dict) -> Term:
        """This term with the weight in force under ``params``."""
        if not self.param:
            return self
        return replace(self, weight=self.weight * float(params[self.param]), param="")


def ramp(phase: tuple[float, float], progress: float) -> float:
    """0 before progress a, 1 after b, linear between (1 throughout when a = b)."""
    a, b = phase
    if progress >= b:
        return 1.0
    if progress <= a:
        return 0.0 if b > a else 1.0
    return (progress - a) / (b - a)


@dataclass(frozen=True)
class Ease:
    """A curriculum on one numeric task parameter: over run progress
    ``phase = (a, b)`` it eases from ``start`` to the value the task was given
    (Gritz & Hahn phase style points in; an obstacle can be phased in the
    same way, so a search first learns the easy motion, then adapts it)."""
    start: float
    phase: tuple[float, float]
    doc: str = ""

    def value(self, end: float, progress: float) -> float:
        return self.start + (end - self.start) * ramp(self.phase, progress)


class _ClassProperty:
    """A read-only property that also works on the class (``LampHop.id``)."""

    def __init__(self, fget):
        self.fget, self.__doc__ = fget, fget.__doc__

    def __get__(self, obj, cls):
        return self.fget(cls)


class Task:
    """Base class; subclasses set the class attributes and ``measure``.

    On an instance ``figure`` is the compiled Figure and ``params`` the values
    in force (on the class: the figure's registry name and the defaults)."""
    name: ClassVar[str] = ""
    version: ClassVar[int] = 1                        # the id is f"{name}-v{version}"
    figure: str | Figure = ""                         # class: a registry name; instance: a Figure
    description: ClassVar[str] = ""
    params: dict = {"seconds": 3.0}                   # class: defaults; instance: values
    bounds: ClassVar[dict[str, tuple[float, float]]] = {}   # parameter -> (lo, hi), inclusive
    param_docs: ClassVar[dict[str, str]] = {}            # parameter -> what it means (units)
    terms: ClassVar[tuple[Term, ...]] = ()
    controlled: ClassVar[tuple[str, ...] | None] = None  # actuators the controller drives
    #   (None: all); the others hold the figure's neutral pose with their PD servos
    actuation: ClassVar[str] = "pd"
    record_every: ClassVar[int] = 10
    dt: ClassVar[float] = 1e-3
    success_threshold: ClassVar[str] = ""                # human-readable, for tables
    curriculum: ClassVar[dict[str, Ease]] = {}           # parameter -> Ease (scene params)
    view: ClassVar[dict] = {}                            # 3-D pictures: elev, azim, bodies, ground

    @_ClassProperty
    def id(cls) -> str:
        """The versioned id, ``name-vN`` (what records store)."""
        return f"{cls.name}-v{cls.version}"

    def __init__(self, **overrides):
        variant = overrides.pop("figure", None)   # a figure variant: name, TOML path or spec dict
        defaults = type(self).params
        unknown = set(overrides) - set(defaults)
        if unknown:
            raise ValueError(f"task {self.name}: unknown parameter(s) {sorted(unknown)}; "
                             f"known: {sorted(defaults)}")
        self.params = dict(defaults)
        for k, v in overrides.items():
            default = defaults[k]
            if isinstance(default, (int, float)) and not isinstance(default, bool):
                try:
                    v = float(v)
                except (TypeError, ValueError):
                    raise ValueError(f"task {self.name}: parameter {k} must be a number, got {v!r}") from None
                if not math.isfinite(v):
                    raise ValueError(f"task {self.name}: parameter {k} must be finite, got {v!r}")
                if abs(v) > PARAM_BOUND:
                    raise ValueError(f"task {self.name}: parameter {k} must be within "
                                     f"±{PARAM_BOUND:g}, got {v!r}")
            self.params[k] = v
        for k in self.curriculum:
            if k not in defaults or isinstance(defaults[k], bool):
                raise ValueError(f"task {self.name}: curriculum names {k!r}, not a numeric parameter")
        for k, (lo, hi) in self.bounds.items():
            if not lo <= float(self.params[k]) <= hi:
                raise ValueError(f"task {self.name}: parameter {k} must be within {lo:g}..{hi:g}, "
                                 f"got {self.params[k]:g}")
        shortest = max(0.05, 2 * self.record_every * self.dt)     # a few recorded frames
        if not shortest <= float(self.params.get("seconds", 1.0)) <= 120:
            raise ValueError(f"task {self.name}: seconds must be in [{shortest:g}, 120], "
                             f"got {self.params['seconds']}")
        self.validate()
        self.terms = tuple(t.under(self.params) for t in type(self).terms)
        self.figure = load_figure(type(self).figure)
        if variant is not None:
            self._use_variant(variant)

    def _use_variant(self, spec) -> None:
        """Run on a variant of the task's figure; it must have every actuated joint,
        site and contact the task reads (checked by name; the senses a family's
        controller reads are checked by that family)."""
        fig = load_figure(spec)
        base = self.figure
        if (fig.dimensions, fig.root) != (base.dimensions, base.root):
            raise ValueError(f"task {self.name}: figure {fig.name} is {fig.dimensions}-D with a "
                             f"{fig.root} root; the task is written for {base.name}, "
                             f"{base.dimensions}-D with a {base.root} root")
        needs = (("actuated joint", self.controlled or base.actuator_names, fig.actuator_names),
                 ("site", base.site_names, fig.site_names),
                 ("contact", base.contact_names, fig.contact_names))
        missing = [f"{kind} {n!r}" for kind, names, have in needs for n in names if n not in have]
        if missing:
            raise ValueError(f"task {self.name}: figure {fig.name} lacks {', '.join(missing)} "
                             f"(the task uses them on {base.name})")
        self.figure = fig
        self.params["figure"] = spec

    # ---- old spellings, kept for one release ------------------------------
    @property
    def fig(self) -> Figure:
        """Deprecated: ``task.figure`` (the instance's Figure)."""
        warnings.warn("Task.fig is deprecated: use task.figure (a Figure on an instance)",
                      DeprecationWarning, stacklevel=2)
        return self.figure

    @property
    def p(self) -> dict:
        """Deprecated: ``task.params`` (the instance's values)."""
        warnings.warn("Task.p is deprecated: use task.params (the values on an instance)",
                      DeprecationWarning, stacklevel=2)
        return self.params

    # ---- things a task may override -------------------------------------
    def validate(self) -> None:
        """Check parameter values; raise ValueError with one clear line."""

    def scene(self) -> Scene:
        return make_scene(**self.figure.ground)

    def initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        return self.figure.q_default.copy(), np.zeros(self.figure.nv)

    def initial_contact(self) -> np.ndarray | None:
        """The contacts' friction-anchor state at the start ([nc, k], a
        Trajectory's ``contact_end``), or None: no contact yet.  A task that
        continues another motion returns where that motion left it, so the
        start is the whole physical state, as a composite carries it."""
        return None

    def measure(self, traj) -> dict[str, np.ndarray]:
        """Raw value of every term, each an array over episodes."""
        raise NotImplementedError

    def success(self, traj, measures: dict[str, np.ndarray]) -> np.ndarray:
        """Which episodes solve the task (bool per episode)."""
        return np.zeros(traj.n_episodes, dtype=bool)

    def task_senses(self) -> tuple:
        """Senses derived from the figure's (gpmotion.gp.task_senses.TaskSense: a
        name and a formula); GP trees read the ones its settings name as terminals."""
        return ()

    def describe(self, traj, measures) -> list[str]:
        """Short human-readable facts about one episode (gait, hits...)."""
        return []

    def fall_stop(self) -> float | None:
        """Opt in to ending a fallen episode early: the base pitch (rad) beyond
        which a recorded frame ends it (planar figures), or None to simulate every
        episode to its end.  An episode that ends holds its fall frame to the end,
        so a task that opts in scores what happened up to the fall and nothing
        after; the steps after a fall are then never simulated."""
        return None

    # ---- the harness uses these ------------------------------------------
    @property
    def seconds(self) -> float:
        """The episode's length."""
        return float(self.params["seconds"])

    @property
    def motion_seconds(self) -> float:
        """How long the task's motion lasts: as a phase of a composite (and as
        an earlier stage of ``after``) a controller runs this long.  The episode
        by default; a task that scores a settling time past its motion (the
        creatures' ``hold``) hands over at the motion's end."""
        return self.seconds

    @property
    def n_steps(self) -> int:
        return int(round(self.seconds / self.dt))

    def rollout_options(self) -> dict:
        """The task's keywords of :func:`gpmotion.sim.rollout.rollout`."""
        return {"n_steps": self.n_steps, "dt": self.dt, "record_every": self.record_every,
                "stop_pitch": self.fall_stop()}

    def controlled_actuators(self) -> list[int]:
        """Indices (into the figure's actuators) of the joints the controller drives."""
        names = self.figure.actuator_names
        if self.controlled is None:
            return list(range(len(names)))
        missing = [n for n in self.controlled if n not in names]
        if missing:
            raise ValueError(f"task {self.name}: {missing} are not actuated joints of {self.figure.name}")
        return [names.index(n) for n in self.controlled]

    def params_at(self, progress: float) -> dict:
        """The parameters in force at run progress (the curriculum applied)."""
        return {**self.params, **{k: e.value(float(self.params[k]), progress)
                             for k, e in self.curriculum.items()}}

    def scene_at(self, progress: float = 1.0) -> Scene:
        """The scene at run progress: ``scene()`` on the curriculum's parameters."""
        if not self.curriculum:
            return self.scene()
        staged = copy.copy(self)
        staged.params = self.params_at(progress)
        return staged.scene()

    def phase(self, progress: float) -> tuple:
        """Everything a cost depends on through progress: the terms' factors and
        the curriculum's values (the GP reuses a cost only within one phase)."""
        return tuple(float(t.factor(progress)) for t in self.terms) + self.staged(progress)

    def staged(self, progress: float) -> tuple:
        """The curriculum's parameter values at run progress (sorted by name)."""
        p = self.params_at(progress)
        return tuple(float(p[k]) for k in sorted(self.curriculum))

    def score(self, traj, progress: float = 1.0):
        """(total cost per episode, {term: value}, success per episode)."""
        measures = self.measure(traj)
        raw = self._weighted_sum(measures, traj.n_episodes, progress)
        bad = traj.diverged | ~np.isfinite(raw)
        ok = self.success(traj, measures) & ~bad
        return self.cost(measures, traj.diverged, progress), measures, ok

    def _weighted_sum(self, measures, n: int, progress: float) -> np.ndarray:
        total = np.zeros(n)
        for term in self.terms:
            v = np.asarray(measures[term.name], dtype=np.float64)
            total += term.weight * term.factor(progress) * np.nan_to_num(v, nan=WORST, posinf=WORST)
        return total

    def cost(self, measures, diverged, progress: float = 1.0) -> np.ndarray:
        """Total cost per episode from raw term values at run progress (what
        ``score`` returns); valid under another progress's weights only while
        the scene is the same (``staged`` equal), since measures depend on it."""
        diverged = np.asarray(diverged, dtype=bool)
        total = self._weighted_sum(measures, diverged.shape[0], progress)
        bad = diverged | ~np.isfinite(total)
        total[bad] = WORST
        return np.clip(total, -WORST, WORST)      # statistics over a population stay finite

    def breakdown(self, measures, e: int, progress: float = 1.0) -> list[dict]:
        """Per-term rows for one episode: value, weight, phase factor, contribution."""
        rows = []
        for t in self.terms:
            v = float(measures[t.name][e])
            f = t.factor(progress)
            rows.append(dict(term=t.name, value=v, weight=t.weight, phase=f,
                             contribution=t.weight * f * v, main=t.main))
        return rows

    def config(self) -> dict:
        return {"task": self.id, "figure": self.figure.name, "params": dict(self.params),
                "actuation": self.actuation,
                "terms": [dict(name=t.name, weight=t.weight, phase=list(t.phase), main=t.main)
                          for t in self.terms],
                "curriculum": {k: dict(start=e.start, phase=list(e.phase))
                               for k, e in self.curriculum.items()}}


# ---- registry --------------------------------------------------------------
_TASKS: dict[str, type[Task]] = {}          # id (name-vN) -> class
_ID = re.compile(r"^(?P<name>.+)-v(?P<version>[0-9]+)$")


def register_task(cls: type[Task]) -> type[Task]:
    """Class decorator: make a task available by its id ``name-vN`` (and its
    bare name, while it is the newest version)."""
    import inspect
    if not cls.name or not cls.figure:
        raise ValueError(f"{cls.__qualname__}: a task needs 'name' and 'figure'")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", cls.name):
        raise ValueError(f"{cls.__qualname__}: task name {cls.name!r} must be an identifier "
                         "(the version goes in 'version', not the name)")
    if isinstance(cls.version, bool) or not isinstance(cls.version, int) or cls.version < 1:
        raise ValueError(f"task {cls.name}: version must be an integer >= 1, got {cls.version!r}")
    if not cls.terms or not any(t.main for t in cls.terms):
        raise ValueError(f"task {cls.name}: needs terms with one main=True term")
    unknown = [t.param for t in cls.terms if t.param and t.param not in cls.params]
    if unknown:
        raise ValueError(f"task {cls.name}: terms weighted by unknown parameter(s) {unknown}")
    old = _TASKS.get(cls.id)
    if old is not None and inspect.getsourcefile(old) != inspect.getsourcefile(cls):
        raise ValueError(f"task {cls.id!r} defined twice: {inspect.getsourcefile(old)} "
                         f"and {inspect.getsourcefile(cls)}")
    _TASKS[cls.id] = cls
    return cls


def _load_builtin() -> None:
    from . import plugins
    plugins.load_builtin()


def _newest() -> dict[str, str]:
    """bare name -> id of its newest registered version."""
    out: dict[str, tuple[int, str]] = {}
    for tid, cls in _TASKS.items():
        if cls.version > out.get(cls.name, (0, ""))[0]:
            out[cls.name] = (cls.version, tid)
    return {n: tid for n, (_, tid) in out.items()}


def task_names() -> list[str]:
    """The bare names users type (each means its newest version), sorted."""
    _load_builtin()
    return sorted(_newest())


def task_ids() -> list[str]:
    """Every registered version's id, sorted."""
    _load_builtin()
    return sorted(_TASKS)


def task_id(name: str, *, recorded: bool = False) -> str:
    """The id ``name-vN`` a task name stands for.

    A bare name typed by a user means the newest version; a bare name read
    from a record (``recorded=True``) was written before ids existed, when
    every task was at its first version, so it means ``name-v1``.
    """
    _load_builtin()
    name = str(name)
    if name in _TASKS:
        return name
    m = _ID.match(name)
    if m and m["name"] in _newest():
        known = sorted(t for t, c in _TASKS.items() if c.name == m["name"])
        raise KeyError(f"task {m['name']!r} has no version v{m['version']}; known: {', '.join(known)}")
    newest = _newest()
    if name not in newest:
        from .names import unknown
        raise KeyError(unknown("task", name, newest))
    if recorded:
        if f"{name}-v1" not in _TASKS:
            raise KeyError(f"the record names task {name!r} without a version (written before "
                           f"versioned ids: its v1), and {name}-v1 is not registered")
        return f"{name}-v1"
    return newest[name]


def get_task(name: str, **params) -> Task:
    """A task instance by id (``lamp_hop-v1``) or bare name (its newest version)."""
    return _TASKS[task_id(name)](**params)


def task_class(name: str, *, recorded: bool = False) -> type[Task]:
    """The registered class of a task id or bare name (see :func:`task_id`)."""
    return _TASKS[task_id(name, recorded=recorded)]
