"""``gpmotion compare``: controller families side by side under one budget."""
from __future__ import annotations

from .common import _activate_plugins, _params


def cmd_compare(args):
    from ..compare import compare
    from ..families import family_class, family_names
    from ..names import unknown
    from ..records import validate_number
    ctrls = [c.strip() for c in args.controllers.split(",") if c.strip()]
    if not ctrls:
        raise ValueError("--controllers: give at least one controller family (gpmotion list controllers)")
    for c in ctrls:
        if c not in family_names():
            raise ValueError(f"--controllers: {unknown('controller', c, family_names())}")
    validate_number("--seeds", args.seeds, lo=1, hi=1000, integer=True)
    validate_number("--budget", args.budget, lo=10, hi=10**9, integer=True)
    with_population = [c for c in ctrls if family_class(c).takes_population]
    if args.population is not None and not with_population:
        raise ValueError(f"--population does not apply: no family in --controllers has a "
                         f"population (those with one: "
                         f"{', '.join(n for n in family_names() if family_class(n).takes_population)})")
    population = validate_number("--population", args.population, lo=2, hi=10**6, integer=True,
                                 allow_none=True)
    out = args.out or f"runs/compare-{args.task}"
    _activate_plugins(args)
    _, md = compare(args.task, ctrls, args.seeds, args.budget, out, actuation=args.actuation,
                    params=_params(args.param), population=population,
                    workers=args.workers, scheduler=args.scheduler, quiet=args.quiet,
                    force=args.force)
    print(md)
    print(f"wrote {out}/compare.md, compare.csv, runs.json, curves.png (the ledger: results.jsonl; "
          "the same command resumes a cut comparison)")
