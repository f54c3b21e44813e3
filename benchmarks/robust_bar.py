"""Issue 16's robustness bar: controllers evolved with perturbed starts against
controllers evolved without, each judged from 100 perturbed starts.

For every seed: one run from the nominal start and one with ``--robust-starts
K`` (otherwise the same settings), then ``gpmotion robustness RUN --trials
100`` on both (the same 100 starts for every controller: trial 0 nominal,
the others from the figure's default sizes, a stream no run trains on).
Runs go one after another into ``--out`` and are reused (or resumed) when the
script is started again.  Prints a markdown table and a summary line.

    python benchmarks/robust_bar.py --task lamp_hop --seeds 5 --starts 8 \
        --search stop_on_success=true
    python benchmarks/robust_bar.py --task lamp_hop --seeds 5 --starts 8 --confirm 24 \
        --require 0.9 --extend 40 --search stop_on_success=true --search population=100
    python benchmarks/robust_bar.py --task starman_travel --controller bsr-time \
        --param seconds=2 --search n_generations=300 --seeds 5 --starts 4
"""
import argparse
import json
import sys
import time
from pathlib import Path

from gpmotion.robust import robustness
from gpmotion.replay import load_controller
from gpmotion.run import RunConfig, run
from gpmotion.task import task_id


def _fail(msg: str) -> None:
    print(f"robust_bar: {msg}", file=sys.stderr)
    sys.exit(2)


def _pairs(items, what):
    out = {}
    for it in items or []:
        k, eq, v = it.partition("=")
        if not eq:
            _fail(f"{what} expects KEY=VALUE, got {it!r}")
        out[k] = json.loads(v) if v in ("true", "false") or v.lstrip("-").replace(".", "", 1).isdigit() else v
    return out


def recorded_as_asked(cfg: RunConfig, out: Path) -> None:
    """Refuse to reuse a run folder recorded with other settings (never mix runs)."""
    doc = json.loads((out / "config.json").read_text())["run"]
    want = cfg.to_json()
    diff = [k for k in ("family", "seed", "params", "search") if doc.get(k) != want.get(k)]
    if task_id(doc.get("task", ""), recorded=True) != task_id(cfg.task):
        diff.insert(0, "task")
    got_r, want_r = doc.get("robust") or {}, cfg.robust or {}
    diff += [f"robust {k}" for k in ("starts", "aggregate", "confirm", "require")
             if got_r.get(k) != want_r.get(k)]
    if diff:
        _fail(f"{out} was run with other settings ({', '.join(diff)}); use another --out")


def one_run(cfg: RunConfig, out: Path) -> float:
    """Run (or finish) one run; seconds spent now (0 when it was done already)."""
    if (out / "config.json").exists():
        recorded_as_asked(cfg, out)
    if (out / "best.json").exists():
        return 0.0
    t0 = time.perf_counter()
    if (out / "config.json").exists():
        run(None, out, resume=True, quiet=True, artifacts=False)
    else:
        run(cfg, out, quiet=True, artifacts=False, force=True)
    return time.perf_counter() - t0


def searched(out: Path) -> dict:
    """The finished search's rounds (GP generations, serial rounds: re-scores are not
    rounds), evaluations (controllers scored, re-scores included) and whether it
    stopped on success (GP ``stop_on_success``) rather than ran out of generations."""
    st = json.loads((out / "checkpoint.json").read_text())["search"]
    return {"generation": int(st["generation"]), "evaluations": int(st["evaluations"]),
            "stopped": bool(st.get("stopped", False))}


def extend(out: Path, n: int) -> float:
    """Add n generations to a finished run that did not stop on success (once); seconds spent."""
    cfg = json.loads((out / "config.json").read_text())
    if not n or searched(out)["stopped"] or cfg.get("extended_generations") is not None:
        return 0.0
    t0 = time.perf_counter()
    (out / "best.json").unlink()
    run(None, out, resume=True, quiet=True, artifacts=False, extend_generations=n)
    return time.perf_counter() - t0


def judge(out: Path, trials: int) -> dict:
    task, family, actuation, genome, _ = load_controller(str(out))
    r = robustness(task, family, actuation, genome, trials=trials, seed=0)
    return {k: r[k] for k in ("success_rate", "nominal_success", "nominal_cost", "cost_median")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--controller", default="gp")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--starts", type=int, default=8, help="K perturbed starts per controller")
    ap.add_argument("--aggregate", default="mean", help="mean, worst or qNN (q80: the 80th-percentile start)")
    ap.add_argument("--confirm", type=int, default=0, help="M confirmation starts (robust run only)")
    ap.add_argument("--require", type=float, default=1.0, help="success = this fraction of starts")
    ap.add_argument("--extend", type=int, default=0, metavar="N",
                    help="a robust run that found no confirmed solver gets N more generations (once)")
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--param", action="append", metavar="KEY=VALUE", help="task parameter")
    ap.add_argument("--search", action="append", metavar="KEY=VALUE", help="search setting (both runs)")
    ap.add_argument("--nominal-search", action="append", metavar="KEY=VALUE",
                    help="search setting of the nominal run only, over --search (e.g. "
                         "stop_on_success=false: the nominal run's best after every generation)")
    ap.add_argument("--out", default="/tmp/robust_bar")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    params, search = _pairs(a.param, "--param"), _pairs(a.search, "--search")
    nominal_own = _pairs(a.nominal_search, "--nominal-search")
    nominal_search = {**search, **nominal_own}
    ntag = "".join(f"-{k}{v}" for k, v in sorted(nominal_own.items()))
    base = Path(a.out) / f"{a.task}-{a.controller}"
    tag = f"-k{a.starts}" + "".join(f"-{k}{v}" for k, v in (("c", a.confirm), ("r", a.require))
                                     if v not in (0, 1.0))
    tag += "" if a.aggregate == "mean" else f"-{a.aggregate}"
    rows = []
    for seed in range(a.first_seed, a.first_seed + a.seeds):
        row = {"seed": seed}
        method = {"starts": a.starts, "aggregate": a.aggregate,
                  **({"confirm": a.confirm} if a.confirm else {}),
                  **({"require": a.require} if a.require != 1.0 else {})}
        for kind, robust in (("nominal", {}), ("robust", method)):
            out = base / (f"{kind}{ntag}-seed{seed}" if kind == "nominal" else f"{kind}{tag}-seed{seed}")
            cfg = RunConfig(task=a.task, family=a.controller, seed=seed, params=dict(params),
                            search=dict(nominal_search if kind == "nominal" else search),
                            robust=robust)
            row[f"{kind}_wall_s"] = round(one_run(cfg, out), 1)
            if kind == "robust":
                row["robust_wall_s"] += round(extend(out, a.extend), 1)
            done = searched(out)                     # after any extension
            if kind == "robust":
                row["robust_stopped"], row["robust_generations"] = done["stopped"], done["generation"]
            row[f"{kind}_evaluations"] = done["evaluations"]
            row[f"{kind}_episodes"] = row[f"{kind}_evaluations"] * (a.starts if kind == "robust" else 1)
            row[kind] = judge(out, a.trials)
        rows.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    if a.json:
        print(json.dumps(rows))
        return 0
    print(f"{a.task} ({a.controller}), K = {a.starts} starts ({a.aggregate}), confirm {a.confirm}, "
          f"require {a.require} vs nominal; "
          f"success from {a.trials} perturbed starts (trial 0 nominal)")
    print("| seed | evolved nominally: success | nominal start | episodes | evolved robust: success "
          "| nominal start | episodes (K × evaluations) | robust run: generations, stopped on a "
          "confirmed solver |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        n, b = r["nominal"], r["robust"]
        print(f"| {r['seed']} | {100 * n['success_rate']:.0f} % | {'ok' if n['nominal_success'] else 'fails'} "
              f"| {r['nominal_episodes']:,} "
              f"| {100 * b['success_rate']:.0f} % | {'ok' if b['nominal_success'] else 'fails'} "
              f"| {r['robust_episodes']:,} "
              f"| {r['robust_generations']}, {'yes' if r['robust_stopped'] else 'no'} |")
    for kind in ("nominal", "robust"):
        s = sorted(r[kind]["success_rate"] for r in rows)
        print(f"{kind}: median {100 * s[len(s) // 2]:.0f} %, mean {100 * sum(s) / len(s):.0f} %, "
              f"≥ 80 %: {sum(x >= 0.8 for x in s)} of {len(s)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
