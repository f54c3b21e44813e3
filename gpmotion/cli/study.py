"""``gpmotion study``: run a study spec, tabulate and plot its ledger, list the
shipped studies, publish their tables into the docs."""
from __future__ import annotations

import argparse
import sys

HELP = "grids of searches from a spec (TOML): run, amend, table, plot, list, show, publish"

DESCRIPTION = """\
A study is configurations × seeds × starts (× stages) of searches, each run
through the loop `gpmotion run` uses (checkpointed, resumable), one row per
search in DIR/results.jsonl.  Seeds are split into tune_seeds (the settings
were chosen on them: counts only) and report_seeds (fresh: the rates, with
95 % Wilson intervals).  The spec format is in docs/studies.md.

  gpmotion study list                          the shipped studies
  gpmotion study show auslander-2d             its configurations and ledger
  gpmotion study run auslander-2d --out runs/a2d --seeds report --workers 2
  gpmotion study run SPEC.toml --out DIR --quick
  gpmotion study amend SPEC.toml --out DIR     bind DIR to an amended spec (new
                                               configurations, labels, judges)
  gpmotion study table DIR [--judge gait] [--format md|csv|json] [--seeds tune]
  gpmotion study plot DIR                      rates and learning curves (PNG)
  gpmotion study publish [--check]             rewrite the docs' study tables

Kill it at any moment (Ctrl-C, SIGTERM, SIGKILL): the same `study run`
command continues and gives the same rows.  A changed spec is refused in an
existing DIR, unless `study amend` shows the amendment leaves every row
true (a new configuration, label or judge: rows are re-judged from their
kept measures).
"""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.description = DESCRIPTION
    sub = p.add_subparsers(dest="study_cmd", required=True, metavar="ACTION")
    r = sub.add_parser("run", help="run a spec's searches into a study directory (resumes)")
    r.add_argument("spec", help="a spec file (SPEC.toml) or a shipped study's name")
    r.add_argument("--out", required=True, help="the study directory (created; reused to resume)")
    r.add_argument("--seeds", default="all",
                   help="tune, report, all (default) or a comma list of the spec's seeds")
    r.add_argument("--configs", metavar="NAME[,NAME]",
                   help="run only these configurations (default all); rows are the same as "
                   "a full run's, so a later run without --configs adds the rest")
    r.add_argument("--quick", action="store_true",
                   help="the spec's [quick] form: few seeds, a small search")
    g = r.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, default=1,
                   help="searches run at once in spawned processes (default 1: in this process)")
    g.add_argument("--scheduler", help="Dask scheduler ('local' or tcp://HOST:PORT): every "
                   "search's evaluations go to it")
    r.add_argument("--runs", metavar="DIR", help="where the searches' run directories go "
                   "(default OUT/runs)")
    r.add_argument("--quiet", action="store_true", help="no progress lines")
    a = sub.add_parser("amend", help="bind a study directory to an amended spec whose "
                       "searches with rows are unchanged (runs nothing)")
    a.add_argument("spec", help="the amended spec file (SPEC.toml) or a shipped study's name")
    a.add_argument("--out", required=True, help="the study directory")
    a.add_argument("--quick", action="store_true", help="the directory was run with --quick")
    t = sub.add_parser("table", help="the table of a study directory or a shipped study")
    t.add_argument("study", help="a study directory or a shipped study's name")
    t.add_argument("--format", choices=["md", "csv", "json"], default="md")
    t.add_argument("--judge", help="re-judge every row from its kept measures (a judge name)")
    t.add_argument("--seeds", choices=["report", "tune"], default="report",
                   help="report seeds (rates, default) or tune seeds (counts only)")
    pl = sub.add_parser("plot", help="success rates (95 %% intervals) and learning curves")
    pl.add_argument("study", help="a study directory or a shipped study's name")
    pl.add_argument("-o", "--output", default="study.png", help="PNG (default study.png)")
    pl.add_argument("--seeds", choices=["report", "tune"], default="report")
    pl.add_argument("--judge", help="re-judge every row from its kept measures")
    sub.add_parser("list", help="the shipped studies, a line each")
    s = sub.add_parser("show", help="a shipped study's configurations and ledger")
    s.add_argument("name", help="a shipped study's name (gpmotion study list)")
    pb = sub.add_parser("publish", help="rewrite the README's and docs' study tables from "
                        "the shipped ledgers")
    pb.add_argument("--check", action="store_true",
                    help="change nothing: exit 1 naming each table that differs")
    pb.add_argument("--root", default=".", help="the project folder (default .)")


def run_command(args) -> int:
    return {"run": _run, "amend": _amend, "table": _table, "plot": _plot, "list": _list, "show": _show,
            "publish": _publish}[args.study_cmd](args)


def _run(args) -> int:
    from ..records import validate_number
    from ..study import spec_path
    from ..study.driver import run_study
    from ..study.spec import load, select_seeds
    workers = validate_number("--workers", args.workers, lo=1, hi=1024, integer=True)
    spec = load(spec_path(args.spec), quick=args.quick)
    seeds = select_seeds(spec, args.seeds)
    rows = run_study(spec, args.out, seeds, workers=workers, scheduler=args.scheduler,
                     runs=args.runs, quiet=args.quiet,
                     configs=args.configs.split(",") if args.configs else None)
    from ..study.table import markdown, summarize
    n = sum(r["seed"] in seeds for r in rows)
    print(f"{args.out}: {n} rows for seeds {','.join(map(str, seeds))} "
          f"({len(rows)} in the ledger)")
    for which in ("tune", "report"):
        if any(r["seeds"] == which and r["seed"] in seeds for r in rows):
            print(f"\n{which} seeds:\n")
            print(markdown(summarize(spec, rows, which)), end="")
    return 0


def _amend(args) -> int:
    from ..study import spec_path
    from ..study.amend import amend
    from ..study.spec import load
    spec = load(spec_path(args.spec), quick=args.quick)
    a = amend(args.out, spec)
    if a.same:
        print(f"{args.out}: already bound to this spec; nothing changed")
        return 0
    what = [f"added {', '.join(a.added)}"] if a.added else []
    what += [f"{n} re-judged {old} → {new}" for n, (old, new) in a.rejudged.items()]
    if a.rejudged:
        what.append(f"{a.changed} verdicts changed")
    print(f"{args.out}: bound to {args.spec} (digest {spec.digest()[:12]}…)"
          + (f"; {'; '.join(what)}" if what else "; every row unchanged"))
    return 0


def _loaded(name):
    from ..study import load_directory, shipped_names, study_dir
    path = study_dir(name)
    if name in shipped_names() and not (path / "study.json").exists():
        raise ValueError(f"the shipped study {name} has no ledger yet; run it: "
                         f"gpmotion study run {name} --out DIR")
    return load_directory(path)


def _table(args) -> int:
    from ..study.table import render, summarize
    spec, rows = _loaded(args.study)
    sys.stdout.write(render(summarize(spec, rows, args.seeds, args.judge), args.format))
    return 0


def _plot(args) -> int:
    from ..study.plot import plot
    spec, rows = _loaded(args.study)
    plot(spec, rows, args.output, args.seeds, args.judge)
    print(f"wrote {args.output}")
    return 0


def _list(args) -> int:
    from ..study import SHIPPED, shipped_names
    from ..study.ledger import read_rows
    from ..study.spec import load
    for name in shipped_names():
        spec = load(SHIPPED / name / "spec.toml")
        rows = read_rows(SHIPPED / name)
        rep = sum(r["seeds"] == "report" for r in rows)
        print(f"{name:<18} {spec.title} ({len(spec.configurations)} configurations; "
              f"ledger: {len(rows)} rows, {rep} on report seeds)")
    return 0


def _show(args) -> int:
    from ..study import spec_path, study_dir
    from ..study.ledger import read_rows
    from ..study.spec import load
    spec = load(spec_path(args.name))
    rows = read_rows(study_dir(args.name)) if args.name in _shipped() else []
    print(f"{spec.name}: {spec.title}")
    if spec.description:
        print(spec.description.strip())
    print(f"tune seeds {spec.tune_seeds}; report seeds {spec.report_seeds}")
    for c in spec.configurations.values():
        done = [r for r in rows if r["config"] == c.name]
        st = c.stages
        what = (" → ".join(f"{s.name}: {s.task}" for s in st) if c.staged
                else f"{st[0].task} ({st[0].family})")
        print(f"  {c.name}: {c.label}\n      {what}; judge {c.judge}"
              + (f" (expects {' or '.join(c.expect)})" if c.expect else "")
              + (f"; best of {c.starts} starts" if c.starts > 1 else "")
              + f"; ledger rows: {len(done)}")
    return 0


def _shipped():
    from ..study import shipped_names
    return shipped_names()


def _publish(args) -> int:
    from ..study.publish import publish
    changed = publish(args.root, check=args.check)
    for path, name in changed:
        print(f"{path}: study table {name} {'differs' if args.check else 'rewritten'}")
    if args.check and changed:
        return 1
    if not changed:
        print("every study table is what the ledgers give")
    return 0
