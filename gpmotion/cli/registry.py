"""``gpmotion list``, ``show`` and ``check``: what is registered, one task in detail, the contract checks."""
from __future__ import annotations

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
    bad = sum(_report(f"{kind} {name}", fn, name) for kind, name, fn in checks)
    return 1 if bad else 0


def _report(label, fn, arg):
    try:
        fn(arg)
        print(f"ok    {label}")
        return 0
    except AssertionError as e:
        print(f"FAIL  {label}: {e}")
        return 1
