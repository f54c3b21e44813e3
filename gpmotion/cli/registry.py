"""``gpmotion list``, ``show`` and ``check``: what is registered, one task in detail, the contract checks."""
from __future__ import annotations

import sys

from .common import _activate_plugins


def cmd_list(args):
    from .. import figure_names
    from ..families import family_class, family_names
    from ..gp import primitives
    from ..task import task_class, task_ids
    _activate_plugins(args)
    primitives.load_builtin()
    if args.what in ("all", "tasks"):
        print("tasks:")
        for tid in task_ids():
            t = task_class(tid)
            print(f"  {tid:<24} {t.figure:<16} {t.description}")
        print("  (a bare name means its newest version; parameters, cost terms, joints and senses "
              "of one task: gpmotion show TASK)")
    if args.what in ("all", "figures"):
        print("figures:", ", ".join(figure_names()))
    if args.what in ("all", "primitives"):
        print("primitives:", ", ".join(f"{n}/{primitives.get(n).arity}" for n in primitives.names()))
    if args.what in ("all", "controllers"):
        print("controllers:")
        for n in family_names():
            c = family_class(n)
            print(f"  {n:<12} {c.description} (default actuation {c.default_actuation})")


def cmd_show(args):
    from ..show import describe_task
    _activate_plugins(args)
    print(describe_task(args.task))


def cmd_check(args):
    from ..check import check_family, check_primitive, check_task
    from ..families import family_names
    from ..gp import primitives
    from ..task import task_ids
    if args.only_plugins and not args.plugins:
        raise ValueError("--only-plugins needs --plugins DIR")
    primitives.load_builtin()
    before = set(primitives.names()) | set(task_ids()) | set(family_names())
    _activate_plugins(args)
    checks = ([("primitive", n, check_primitive) for n in primitives.names()]
              + [("task", n, check_task) for n in task_ids()]       # every version of every task
              + [("family", n, check_family) for n in family_names()])
    if args.only_plugins:
        checks = [c for c in checks if c[1] not in before]
        if not checks:
            raise ValueError(f"{', '.join(args.plugins)}: no primitives, tasks or controller "
                             "families to check")
    from ..cache import on_cold_compile
    from ..progress import CompileNote
    print(f"checking {_counted(checks)} (each simulates or compiles: seconds each, "
          "minutes for the first on a fresh machine)", file=sys.stderr, flush=True)
    with on_cold_compile(CompileNote("simulation")):
        bad = sum(_report(f"{kind} {name}", fn, name, k, len(checks))
                  for k, (kind, name, fn) in enumerate(checks, 1))
    return 1 if bad else 0


def _counted(checks) -> str:
    """Like '25 primitives, 18 tasks and 5 families' (the kinds present)."""
    kinds = [k for k in ("primitive", "task", "family") if any(c[0] == k for c in checks)]
    parts = []
    for k in kinds:
        n = sum(c[0] == k for c in checks)
        parts.append(f"{n} {k if n == 1 else ('families' if k == 'family' else k + 's')}")
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _report(label, fn, arg, k: int, n: int):
    """One check: what runs now on stderr (a line rewritten on a terminal, cleared
    before the verdict), its verdict on stdout."""
    tty = sys.stderr.isatty()
    now = f"[{k}/{n}] checking {label} …"
    print(f"\r{now}\033[K" if tty else now, end="" if tty else "\n", file=sys.stderr, flush=True)
    try:
        fn(arg)
        verdict, bad = f"ok    {label}", 0
    except AssertionError as e:
        verdict, bad = f"FAIL  {label}: {e}", 1
    if tty:
        print("\r\033[K", end="", file=sys.stderr, flush=True)
    print(verdict, flush=True)
    return bad
