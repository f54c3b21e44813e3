"""``gpmotion robustness RUN [--trials 100]``: how a controller does from perturbed starts.

"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict

HELP = "success rate and cost spread of a controller from randomly perturbed starts"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", help="run directory or controller JSON (best.json)")
    p.add_argument("--trials", type=int, default=100, help="perturbed starts (default 100; trial 0 is nominal)")
    p.add_argument("--seed", type=int, default=0)
    for name, unit in (("joint", "rad"), ("position", "m"), ("orientation", "rad"), ("velocity", "m/s"),
                       ("angular", "rad/s")):
        p.add_argument(f"--{name}", type=float, help=f"σ of the {name} perturbation ({unit}; default: "
                       "the figure's, docs/howto/composite.md)")
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.add_argument("--plot", metavar="PNG", help="also draw the cost of every trial, successes marked")


def run_command(args) -> int:
    from ..replay import load_controller
    from ..robust import SIZE_KEYS, Perturbation, robustness, sizes_for
    task, family, actuation, genome, _ = load_controller(args.source)
    given = {k: getattr(args, k) for k in SIZE_KEYS if getattr(args, k) is not None}
    sizes = Perturbation(**{**asdict(sizes_for(type(task).figure)), **given})
    r = robustness(task, family, actuation, genome, trials=args.trials, seed=args.seed, sizes=sizes)
    if args.json:
        print(json.dumps(r))
    else:
        sz = r["sizes"]
        print(f"{args.source}: {task.name}, {family.name}, {r['trials']} starts (seed {r['seed']}); "
              f"σ joint {sz['joint']:g} rad, position {sz['position']:g} m, orientation "
              f"{sz['orientation']:g} rad, velocity {sz['velocity']:g} m/s, angular {sz['angular']:g} rad/s")
        print("| success | nominal | cost min | q25 | median | q75 | max | diverged |")
        print("|---|---|---|---|---|---|---|---|")
        print(f"| {100 * r['success_rate']:.0f}% | {'ok' if r['nominal_success'] else 'fails'} "
              f"({r['nominal_cost']:.3f}) | {r['cost_min']:.3f} | {r['cost_q25']:.3f} | {r['cost_median']:.3f} | "
              f"{r['cost_q75']:.3f} | {r['cost_max']:.3f} | {r['diverged']} |")
    if args.plot:
        _plot(args.plot, r, f"{task.name} ({family.name}): {100 * r['success_rate']:.0f}% of {r['trials']} starts succeed")
    return 0


def _plot(path, r, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from ..records import atomic_output
    costs, ok = np.asarray(r["costs"]), np.asarray(r["success"])
    order = np.argsort(costs)
    fig, ax = plt.subplots(figsize=(7, 3))
    ax.bar(np.arange(len(costs)), costs[order], color=np.where(ok[order], "tab:green", "tab:red"))
    ax.set_xlabel("perturbed start (sorted by cost)")
    ax.set_ylabel("cost (lower is better)")
    ax.set_title(title + " — green: success", fontsize=9)
    fig.tight_layout()
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    """``python -m`` entry: the same as ``gpmotion robustness ...`` (one error path, in cli.main)."""
    from . import main as cli_main
    return cli_main(["robustness", *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":
    sys.exit(main())
