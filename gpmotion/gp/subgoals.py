"""Subgoal terminals (Gritz & Hahn: "variables [that] contain the status of
subgoals ... nonzero once the subgoal is met, allowing if statements in the
controller program to switch behaviours").

A task declares named subgoals, each a test on one of its figure's senses
(``px`` > threshold, |px| < threshold, ...).  The GP controller evaluates the
tests every control step, *before* its trees, and latches each flag at 1.0
once its test has held (0.0 until then; reset at the start of an episode).
The flags live in the controller's own state (``cstate``), so the simulator
kernels are untouched: a task adds subgoals in its own file.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

TESTS = {"gt": 0, "lt": 1, "abs_lt": 2}     # sense > thr, sense < thr, |sense| < thr
MAX_SUBGOALS = 8


@dataclass(frozen=True)
class Subgoal:
    name: str            # the terminal's name
    sense: str           # the sense it watches
    test: str            # a key of TESTS
    threshold: float
    doc: str = ""

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"subgoal name {self.name!r} must be an identifier")
        if self.test not in TESTS:
            raise ValueError(f"subgoal {self.name}: test must be one of {', '.join(TESTS)}, "
                             f"got {self.test!r}")
        if not math.isfinite(self.threshold):
            raise ValueError(f"subgoal {self.name}: threshold must be finite")

    def met(self, value: float) -> bool:
        """The test in plain Python (the interpreter's twin)."""
        return {"gt": value > self.threshold, "lt": value < self.threshold,
                "abs_lt": abs(value) < self.threshold}[self.test]


def task_subgoals(task) -> tuple[Subgoal, ...]:
    """The subgoals a task declares (``subgoals()``), checked against its senses."""
    decl = getattr(task, "subgoals", None)
    goals = tuple(decl() if callable(decl) else (decl or ()))
    if not goals:
        raise ValueError(f"task {task.name} declares no subgoals")
    if len(goals) > MAX_SUBGOALS:
        raise ValueError(f"task {task.name}: at most {MAX_SUBGOALS} subgoals, got {len(goals)}")
    names = [g.name for g in goals]
    if len(set(names)) != len(names):
        raise ValueError(f"task {task.name}: repeated subgoal names {names}")
    for g in goals:
        if g.name in task.figure.sense_names:
            raise ValueError(f"task {task.name}: subgoal {g.name!r} has a sense's name")
        task.figure.sense_index(g.sense)              # raises on an unknown sense
    return goals


def subgoal_table(goals, sense_names) -> list[tuple[int, int, float]]:
    """(sense index, test code, threshold) per subgoal, in order."""
    sense_names = list(sense_names)
    return [(sense_names.index(g.sense), TESTS[g.test], float(g.threshold)) for g in goals]
