"""Time-to-solution of the main job: `gpmotion run lamp_hop` on its defaults.

Runs K seeds one after another (each run uses every core), and reports per
seed the wall time, the final distance of the best controller and whether it
solved the task (base within 5 cm of the target, not fallen).  The issue's
bar: at least 4 of 5 seeds solve it, each in under 2 minutes.

    python benchmarks/lamp_success.py [--seeds 5] [--task lamp_hop] [--json]
"""
import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from gpmotion.records import read_json
from gpmotion.run import RunConfig, run


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--task", default="lamp_hop")
    ap.add_argument("--controller", default="gp")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    params = dict(p.split("=", 1) for p in args.param)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            out = Path(tmp) / f"seed{seed}"
            t0 = time.perf_counter()
            run(RunConfig(task=args.task, family=args.controller, seed=seed, params=params), out,
                quiet=True, artifacts=False)
            wall = time.perf_counter() - t0
            best = read_json(out / "best.json", kind="best")
            terms = {r["term"]: r["value"] for r in best["terms"]}
            results.append({"seed": seed, "wall_s": round(wall, 1), "success": best["success"],
                            "final_cost": round(best["final_cost"], 4),
                            "distance_cm": round(100 * terms.get("distance", float("nan")), 1),
                            "facts": best.get("facts", [])})
            print(f"seed {seed}: {'solved' if best['success'] else 'NOT solved'} in {wall:.0f}s, "
                  f"{'; '.join(best.get('facts', []))}", file=sys.stderr, flush=True)
    summary = {"task": args.task, "controller": args.controller, "seeds": args.seeds,
               "solved": sum(r["success"] for r in results),
               "max_wall_s": max(r["wall_s"] for r in results), "runs": results}
    print(json.dumps(summary, indent=1) if args.json else
          f"{summary['solved']}/{args.seeds} seeds solved {args.task}; "
          f"slowest run {summary['max_wall_s']:.0f} s")


if __name__ == "__main__":
    main()
