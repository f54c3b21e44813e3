"""Time-to-solution of the main job: `gpmotion run lamp_hop` on its defaults.

Runs K seeds one after another (each run uses every core), and reports per
seed the wall time, the final distance of the best controller and whether it
solved the task (base within 5 cm of the target, not fallen).  The issue's
bar: at least 4 of 5 seeds solve it, each in under 2 minutes.  ``--preset
gritz-hahn`` runs the paper's configuration instead (gpmotion.gp.presets).

    python benchmarks/lamp_success.py [--seeds 5] [--task lamp_hop] [--preset P] [--json]
"""
import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from gpmotion.families import family_class
from gpmotion.records import read_json
from gpmotion.run import RunConfig, run


def run_seed(task: str, seed: int, params: dict, controller: str = "gp",
             preset: str | None = None, tmp: str | None = None) -> dict:
    """One quiet run; its result row (wall time, success, final cost, facts...)."""
    fam, search = family_class(controller).apply_preset(preset, task, {}, {}) if preset else ({}, {})
    with tempfile.TemporaryDirectory(dir=tmp) as d:
        out = Path(d) / f"seed{seed}"
        t0 = time.perf_counter()
        run(RunConfig(task=task, family=controller, seed=seed, params=params,
                      family_options=fam, search=search), out, quiet=True, artifacts=False)
        wall = time.perf_counter() - t0
        best = read_json(out / "best.json", kind="best")
        generations = len((out / "log.csv").read_text().splitlines()) - 1
    terms = {r["term"]: r["value"] for r in best["terms"]}
    return {"seed": seed, "wall_s": round(wall, 1), "success": best["success"],
            "generations": generations, "final_cost": round(best["final_cost"], 4),
            "distance_cm": round(100 * terms.get("distance", float("nan")), 1),
            "facts": best.get("facts", [])}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--controller", default="gp")
    ap.add_argument("--preset", default=None, help="GP preset (default | gritz-hahn)")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    params = dict(p.split("=", 1) for p in args.param)
    results = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        r = run_seed(args.task, seed, params, args.controller, args.preset)
        results.append(r)
        print(f"seed {seed}: {'solved' if r['success'] else 'NOT solved'} in {r['wall_s']:.0f}s "
              f"({r['generations']} generations), {'; '.join(r['facts'])}",
              file=sys.stderr, flush=True)
    summary = {"task": args.task, "controller": args.controller, "preset": args.preset or "default",
               "seeds": args.seeds, "solved": sum(r["success"] for r in results),
               "max_wall_s": max(r["wall_s"] for r in results), "runs": results}
    print(json.dumps(summary, indent=1) if args.json else
          f"{summary['solved']}/{args.seeds} seeds solved {args.task} "
          f"(preset {summary['preset']}); slowest run {summary['max_wall_s']:.0f} s")


if __name__ == "__main__":
    main()
