"""Named GP configurations: ``default`` (ours) and ``gritz-hahn`` (the paper's).

A preset fills family options (primitives, terminals) and search options;
options the user gives explicitly win.  The expansion is stored in the run's
config.json, so a run resumes without knowing presets.

``gritz-hahn``, for tasks that declare the paper's terminal set
(``GPSettings.paper_terminals``: the lamp tasks):

* functions: Koza's + - * and protected %, and the paper's three-argument
  conditional ``ifpos`` (evaluate the first subtree; the second if it is
  positive, else the third);
* terminals: the lamp's position relative to the goal, its velocity, the
  force on its base from the floor, time, and random constants -- not our
  19 senses (joint angles and rates, pitch, centre of mass, head forces);
  task senses the task adds to its terminals (``lamp_limbo --param
  pole_senses=1``) are kept, as the paper proposes such senses;
* fitness-proportionate selection, 90 % crossover and the rest reproduction,
  no mutation, no constant creep, no elitism, one population;
* the run stops when an individual solves the task (the paper's termination
  criterion; once the curriculum, if any, has reached the final scene).

Population and generations stay ours (the paper's numbers are not in our
copy of the text).
"""
from __future__ import annotations

PAPER_PRIMITIVES = ("add", "sub", "mul", "div", "ifpos")

PRESETS = {
    "default": {"family": {}, "search": {}},
    "gritz-hahn": {
        "family": {"primitives": list(PAPER_PRIMITIVES)},
        "search": {"selection": "roulette", "p_crossover": 0.9, "p_mutation": 0.0,
                   "p_creep": 0.0, "elitism": 0, "islands": 1, "stop_on_success": True},
    },
}


def preset_names() -> list[str]:
    return list(PRESETS)


def preset_options(name: str, task) -> tuple[dict, dict]:
    """(family options, search options) of preset ``name`` for ``task`` (a Task)."""
    if name not in PRESETS:
        raise ValueError(f"unknown GP preset {name!r}; known: {', '.join(PRESETS)}")
    fam, search = dict(PRESETS[name]["family"]), dict(PRESETS[name]["search"])
    if name == "gritz-hahn":
        from .settings import gp_settings, terminal_names
        terms = gp_settings(task).paper_terminals
        if not terms:
            raise ValueError(f"preset gritz-hahn needs a task that declares the paper's terminal "
                             f"set (GPSettings paper_terminals: lamp_hop, lamp_limbo); "
                             f"{task.name} does not")
        derived = {s.name for s in task.task_senses()}    # task senses the task adds stay
        fam["terminals"] = list(terms) + [t for t in terminal_names(task) if t in derived]
    return fam, search


def apply_preset(name: str | None, task, family_options: dict | None = None,
                 search: dict | None = None) -> tuple[dict, dict]:
    """Merge preset ``name`` for ``task`` (a Task) under the given options (given,
    non-None values win).  (Other families refuse presets: ``Family.apply_preset``.)"""
    family_options = {k: v for k, v in (family_options or {}).items() if v is not None}
    search = {k: v for k, v in (search or {}).items() if v is not None}
    if not name:
        return family_options, search
    fam, srch = preset_options(name, task)
    return {**fam, **family_options}, {**srch, **search}
