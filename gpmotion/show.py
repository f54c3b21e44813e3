"""``gpmotion show TASK``: everything a user needs to set up a run of a task."""
from __future__ import annotations

from .gp.settings import gp_settings, terminal_names
from .gp.targets import describe as describe_targets
from .task import Task, get_task


def _phase(term) -> str:
    a, b = term.phase
    if b <= a:
        return "full weight from the start"
    return f"phases in from {a:.0%} to {b:.0%} of the run"


def _params(task: Task) -> list[str]:
    rows = []
    for k, default in task.params.items():
        bound = task.bounds.get(k)
        rng = f"{bound[0]:g}..{bound[1]:g}" if bound else ""
        rng = "(0, 120]" if k == "seconds" and k not in task.bounds else rng
        ease = task.curriculum.get(k)
        doc = task.param_docs.get(k, "")
        if ease:
            doc += (f"; curriculum: eases from {ease.start:g} to the value given over "
                    f"{ease.phase[0]:.0%}..{ease.phase[1]:.0%} of the run")
        rows.append(f"  {k:<20} {default!s:<8} {rng:<14} {doc}".rstrip())
    return rows


def _terms(task: Task) -> list[str]:
    rows = []
    for t in task.terms:
        tag = "main goal" if t.main else _phase(t)
        rows.append(f"  {t.name:<18} {t.weight:>7g}  {tag:<38} {t.doc}".rstrip())
    return rows


def _wrap(label: str, names) -> str:
    import textwrap
    text = ", ".join(names) if names else "(none)"
    return textwrap.fill(text, 96, initial_indent=f"{label}: ", subsequent_indent="  ")


def _bsr_senses(fig) -> list[str]:
    from .bsr.genome import table1_sense_indices
    try:
        return [fig.sense_names[i] for i in table1_sense_indices(fig.sense_names)]
    except ValueError as e:           # a figure without com senses: say why
        return [f"(none: {e})"]


def describe_task(name: str) -> str:
    """A task's parameters, terms, figure, controlled joints, sites and senses."""
    task = get_task(name)
    fig = task.figure
    controlled = [fig.actuator_names[i] for i in task.controlled_actuators()]
    held = [n for n in fig.actuator_names if n not in controlled]
    gp = gp_settings(task)
    gp_defaults = ", ".join(f"{k} {v}" for k, v in gp.defaults.items())
    terminals = terminal_names(task)
    lines = [f"{task.id}: {task.description}",
             f"figure: {fig.name} ({fig.dimensions}-D, {fig.root} root, {fig.total_mass:.2f} kg, "
             f"{fig.n_act} actuated joints); episode {task.seconds:g} s at dt {task.dt * 1e3:g} ms",
             f"success: {task.success_threshold or '(no success test)'}",
             "",
             "parameters (--param KEY=VALUE):   default  range          meaning",
             *_params(task),
             "",
             "cost terms (cost = Σ weight × phase × value, lower is better):",
             *_terms(task),
             "  style terms phase in over the run so the main goal is learned first; a",
             "  generation's costs use that generation's weights, best.json the full weights",
             "",
             _wrap("controlled joints (one GP tree / BSR target each)", controlled)]
    if held:
        lines.append(_wrap("held at their neutral pose by PD", held))
    lines += [_wrap("sites", fig.site_names), _wrap("contacts", fig.contact_names),
              _wrap("GP terminals (senses)", terminals),
              *(f"  task sense {ts.name}" + (f" ({ts.doc})" if ts.doc else "")
                + ("" if ts.name in terminals else "; not a terminal by default")
                + f":\n    {ts.formula}" for ts in task.task_senses()),
              _wrap("GP primitives (the task's set; --primitives to change)", gp.primitives),
              _wrap("bsr-sense rules read (Auslander's Table 1)", _bsr_senses(fig)),
              f"GP search defaults: {gp_defaults or 'population 300, generations 40'}",
              f"GP targets: {describe_targets(gp.targets)} (--targets to change)"]
    return "\n".join(lines)
