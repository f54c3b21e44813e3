"""Fig. 13 → Fig. 14 from sense-based parts, as Auslander et al. built it (footnote 11).

    python benchmarks/sense_composite.py --seeds 100-104 --runs DIR [--search] [--grid]

For each part seed S: a cartwheel (2 s, ``w_rotations`` 10), a jump (1 s,
``w_max_height`` 4) and a shuffle (1.5 s, ``w_contact_distance`` 1), each
``bsr-sense`` with R = 10 on ``starman_auslander``, 40,000 evaluations
(``--working 10 --generations 3999``; ``--generations 999`` for 10,000), in
DIR/PART-sS.  ``--search`` runs the missing part searches (one at a time,
through ``gpmotion run``); without it they must exist.

Each part is replayed alone and judged: its strict gait label
(``gpmotion.gaits.judge``) and the phase checks of ``benchmarks/composite.py``
(cartwheel 1 ± 0.25 turns, jump clearance ≥ 5 cm, shuffle ≥ 0.1 m right).  A
part *performs its motion* when the cartwheel is labelled ``cartwheel``, the
jump clears 5 cm and every landing is upright on its feet (one at least)
with under a quarter turn, and the shuffle is labelled ``shuffle`` or ``periodic shuffle``.

Then the composite (switches 2 s and 3 s, 4.5 s): careless, and after the
transition search (Q = G = 16, H = 4) with search seeds 0–4, under
``examples/composite/starman_upright.motion`` and Table 4 as printed with
graded credits (``benchmarks/composite.py``'s TABLE4).  ``--grid`` also
scores every switch-time pair on the 20 ms frame grid (25,651 pairs) under
both scripts: how many score above zero, within 1 % of the best, at the best.
Prints one table and writes DIR/sense_composite.json.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from gpmotion import gaits
from gpmotion.compose import composite as C
from gpmotion.compose import optimize, script

sys.path.insert(0, str(Path(__file__).resolve().parent))
from composite import TABLE4, starman_checks  # benchmarks/composite.py

PARTS = {"cartwheel": ["seconds=2", "w_rotations=10"],
         "jump": ["seconds=1", "w_max_height=4"],
         "shuffle": ["seconds=1.5", "w_contact_distance=1"]}
UPRIGHT = Path(__file__).resolve().parent.parent / "examples/composite/starman_upright.motion"
SWITCHES, SECONDS = (2.0, 3.0), 4.5


def part_command(part: str, seed: int, out: Path, generations: int = 3999) -> list[str]:
    cmd = [sys.executable, "-m", "gpmotion.cli", "run", "starman_travel", "--controller", "bsr-sense",
           "--rules", "10", "--figure", "starman_auslander", "--working", "10",
           "--generations", str(generations),
           "--seed", str(seed), "--out", str(out), "--quiet", "--no-artifacts"]
    for p in PARTS[part]:
        cmd += ["--param", p]
    return cmd


def judge_part(path: Path, part: str) -> dict:
    """The part replayed alone: strict label, its measures, the phase check, and 'performs'."""
    comp = C.from_controllers([path], names=[part])
    traj, bounds = C.run(comp)
    label, m = gaits.judge(traj)
    one = {"cartwheel": "rotations", "jump": "max_t(min_i(y_i))", "shuffle": "dcm_x"}[part]
    value = float(script.evaluate(script.parse(f"phase {part} = {one}\ntotal = 0\n"), traj, bounds)[part][0])
    if part == "cartwheel":
        performs = label == "cartwheel"
    elif part == "jump":
        performs = (value >= 0.05 and 1 <= m["landed_on_feet"] == m["landings"]
                    and abs(m["turns"]) < gaits.NO_TURN)
    else:
        performs = label in ("shuffle", "periodic shuffle")
    return {"label": label, "check": value, "performs": bool(performs),
            "turns": m["turns"], "distance": m["distance"], "upright": m["upright"],
            "max_tilt_deg": m["max_tilt_deg"], "flights": m["flights"], "airborne": m["airborne"],
            "landings": m["landings"], "landed_on_feet": m["landed_on_feet"], "feet_share": m["feet_share"],
            "hands_share": m["hands_share"]}


def scored(comp, s, switches) -> dict:
    totals, _, traj, bounds = optimize.score(comp, s, [switches])
    checks, done, _ = starman_checks(comp, traj, bounds)
    lo, hi = int(bounds[0, 0]), int(bounds[0, 1])
    fig = traj.figure
    label = gaits.classify_strict(gaits.strict_measures(
        traj.times[lo:hi + 1], traj.contact_force[0, lo:hi + 1], fig.contact_names,
        traj.base()[0, lo:hi + 1, 0], traj.com[0, lo:hi + 1, 0], traj.com[0, lo:hi + 1, 1],
        traj.q[0, lo:hi + 1][:, fig.model.act_dof])) if hi - lo > 2 else "none"
    return {"switches": [round(float(x), 3) for x in switches], "total": float(totals[0]),
            "checks": checks, "completes": done, "all": all(done.values()), "cartwheel_label": label}


def transition(comp, s, seed: int) -> dict:
    rounds = []                     # (round, best score after it)
    ts = optimize.search(comp, s, seed=seed, on_round=lambda t: rounds.append((t.round, t.best_score)))
    out = scored(comp, s, ts.best)
    found = next(r for r, b in rounds if b >= ts.best_score)      # the round the final best was reached
    out.update(seed=seed, search_score=float(ts.best_score), found_round=int(found))
    return out


def grid(comp, scripts: dict, answers: dict, chunk: int = 2048) -> dict:
    """Every switch pair (t1 ≤ t2) on the frame grid, scored under each script; for each
    search answer in ``answers[script]``, how many pairs score higher and whether it is a
    local maximum (no better pair one frame away in either switch)."""
    tick, n = comp.frame_seconds, comp.n_frames
    ij = np.array([(i, j) for i in range(n) for j in range(i, n)])
    pairs = ij * tick
    res = {}
    totals = {k: np.empty(len(pairs)) for k in scripts}
    for a in range(0, len(pairs), chunk):
        traj, bounds = C.run(comp, pairs[a:a + chunk])
        for k, s in scripts.items():
            totals[k][a:a + chunk] = script.evaluate(s, traj, bounds, comp.scenes)["total"]
    for k, t in totals.items():
        best = float(np.max(t))
        square = np.full((n + 2, n + 2), -np.inf)
        square[ij[:, 0] + 1, ij[:, 1] + 1] = t
        ranks = {}
        for sw in answers.get(k, []):
            i, j = (round(x / tick) for x in sw)
            v = square[i + 1, j + 1]
            around = square[i:i + 3, j:j + 3].copy()
            around[1, 1] = -np.inf
            ranks[str(tuple(sw))] = {"score": float(v), "higher": int(np.sum(t > v + 1e-12)),
                                     "local_max": bool(v >= around.max())}
        res[k] = {"pairs": len(t), "positive": int(np.sum(t > 0)), "best": best,
                  "argbest": [round(float(x), 3) for x in pairs[int(np.argmax(t))]],
                  "at_best": int(np.sum(t >= best - 1e-12)),
                  "within_1pct": int(np.sum(t >= best - 0.01 * abs(best))),
                  "within_10pct": int(np.sum(t >= best - 0.10 * abs(best))),
                  "local_maxima": int(sum(1 for (i, j), v in zip(ij, t)
                                          if v > 0 and v >= square[i:i + 3, j:j + 3].max())),
                  "answers": ranks}
    return res


def seeds_arg(text: str) -> list[int]:
    if "-" in text:
        lo, hi = map(int, text.split("-"))
        return list(range(lo, hi + 1))
    return [int(x) for x in text.split(",")]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", default="100-104", help="part seeds (a range A-B or a comma list)")
    ap.add_argument("--runs", default="runs/sense-composite", help="folder of the part runs")
    ap.add_argument("--search-seeds", default="0-4", help="transition-search seeds")
    ap.add_argument("--search", action="store_true", help="run the missing part searches")
    ap.add_argument("--generations", type=int, default=3999,
                    help="rounds of each part search (10 evaluations a round; default 3999: 40,000)")
    ap.add_argument("--grid", action="store_true", help="score every switch pair too")
    a = ap.parse_args(argv)
    root = Path(a.runs)
    scripts = {"upright": script.parse(UPRIGHT.read_text(encoding="utf-8")),
               "table4": script.parse(TABLE4.format(2, 1, 1.5))}
    results = {}
    for seed in seeds_arg(a.seeds):
        paths = {p: root / f"{p}-s{seed}" for p in PARTS}
        for p, d in paths.items():
            if not (d / "best.json").exists():
                if not a.search:
                    sys.exit(f"{d}/best.json missing (run with --search)")
                cmd = part_command(p, seed, d, a.generations)
                print(" ".join(cmd), flush=True)
                subprocess.run(cmd, check=True)
        row = {"parts": {p: judge_part(d, p) for p, d in paths.items()}}
        comp = C.from_controllers([paths[p] for p in PARTS], switches=SWITCHES, seconds=SECONDS,
                                  names=list(PARTS))
        for k, s in scripts.items():
            row[k] = {"careless": scored(comp, s, comp.switches),
                      "searches": [transition(comp, s, q) for q in seeds_arg(a.search_seeds)]}
            row[k]["distinct"] = len({tuple(r["switches"]) for r in row[k]["searches"]})
        if a.grid:
            t0 = time.perf_counter()
            row["grid"] = grid(comp, scripts, {k: sorted({tuple(r["switches"]) for r in row[k]["searches"]})
                                               for k in scripts})
            row["grid_seconds"] = time.perf_counter() - t0
        results[seed] = row
        print_row(seed, row, flush=True)
        (root / "sense_composite.json").write_text(json.dumps(results, indent=1))
    print(f"wrote {root}/sense_composite.json")


def print_row(seed, row, flush=False):
    parts = "  ".join(f"{p}: {r['label']} ({r['check']:.2f}{' ✓' if r['performs'] else ' ✗'}, "
                      f"turns {r['turns']:+.2f}, {r['distance']:+.2f} m, upright {r['upright']:.0%})"
                      for p, r in row["parts"].items())
    print(f"part seed {seed}: {parts}", flush=flush)
    for k in ("upright", "table4"):
        c, ss = row[k]["careless"], row[k]["searches"]
        reps = "; ".join(f"s{r['seed']} {tuple(r['switches'])} {r['total']:.3f}"
                         f"{' all' if r['all'] else ''}"
                         + (" (careless kept)" if r["search_score"] <= c["total"] else f" (round {r['found_round']})")
                         for r in ss)
        print(f"  {k}: careless {c['total']:.3f} completes {c['completes']} | searched: {reps} | "
              f"{row[k]['distinct']} distinct; every phase completes in {sum(r['all'] for r in ss)}/{len(ss)}",
              flush=flush)
        if "grid" in row:
            g = row["grid"][k]
            print(f"    grid: {g['positive']}/{g['pairs']} > 0, best {g['best']:.3f} at {g['argbest']}, "
                  f"{g['at_best']} at the best, {g['within_1pct']} within 1 %, {g['within_10pct']} within 10 %, "
                  f"{g['local_maxima']} local maxima > 0; answers: "
                  + "; ".join(f"{sw} {a['higher']} pairs higher{', local max' if a['local_max'] else ''}"
                              for sw, a in g["answers"].items()), flush=flush)


if __name__ == "__main__":
    main()
