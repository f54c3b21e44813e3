"""Composite motion, Auslander et al. Fig. 13 → Fig. 14: careless concatenation, then the
transition search with the Table 4 script; timed.

    python benchmarks/composite.py CART JUMP SHUFFLE [--seed 0] [--Q 16 --G 16 --H 4] [--out DIR]

CART, JUMP, SHUFFLE: saved controllers (best.json or run directories) of one
figure.  The careless composite runs each for its own task's duration; the
script is Table 4 with those durations.  Prints the careless and repaired
scores, per-phase measures, the search's wall time (1 + Q·G·H simulations),
and writes both composites, filmstrips and summary.json to --out.

A phase "completes" when: the cartwheel turns one whole rotation and lands
upright (1 ± 0.25 turns at its end: a cartwheel that stops upside down, 1.5
turns, has not completed), the jump clears the ground (every contact point
≥ 5 cm up at once), the shuffle moves the centre of mass ≥ 0.1 m right.
(Our thresholds, stated here and printed.)

The lamp (GP): hop, pass under the limbo pole, hop to the next target —
a composite file (per-phase scenes: each phase's goal, the pole only in the
limbo phase) and a script:

    python benchmarks/composite.py --composite examples/composite/lamp_careless.json \
        --script examples/composite/lamp_composite.motion --seed S

A lamp phase "completes" when the base centre is within 5 cm of the phase's
goal at its last frame (lamp_hop's "arrived") and, in a phase with a pole,
the pole is never touched; the whole motion must not fall (base pitch beyond
1 rad, the lamp tasks' "fell") and the head must never touch the ground.

K perturbed starts against K single evaluations (``--robust-starts``) is
timed by ``benchmarks/robust_timing.py``.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from gpmotion.compose import composite as C
from gpmotion.compose import optimize, script

TABLE4 = """\
# Auslander et al. 1995, Table 4 (durations: each controller's own, in seconds)
phase cartwheel = Δcm_x × (Δtime ≟ {0:g})
phase jump      = max_t{{min_i{{y_i(t)}}}} × (Δtime ≟ {1:g})
phase shuffle   = Δcm_x × (Δtime ≟ {2:g})
total = (1.0 + cartwheel) × (1.0 + jump) × (1.0 + shuffle)
"""
CHECKS = """\
phase cartwheel = rotations
phase jump = max_t(min_i(y_i))
phase shuffle = dcm_x
total = 0
"""
DONE = {"cartwheel": (0.75, 1.25), "jump": (0.05, np.inf), "shuffle": (0.1, np.inf)}   # [lo, hi]


LAMP_ARRIVED = 0.05          # m: lamp_hop's "at the target"
LAMP_FELL = 1.0              # rad: the lamp tasks' "fell"


def starman_checks(comp, traj, bounds):
    checks = script.evaluate(script.parse(CHECKS), traj, bounds)
    done = {k: bool(lo <= checks[k][0] <= hi) for k, (lo, hi) in DONE.items()}
    line = (f"rotations {checks['cartwheel'][0]:.2f}  clearance {checks['jump'][0]:.3f} m  "
            f"shuffle Δx {checks['shuffle'][0]:.3f} m")
    return {k: float(v[0]) for k, v in checks.items() if k != "total"}, done, line


def lamp_checks(comp, traj, bounds):
    """Per phase (episode 0): the base centre's distance to the phase's goal at its last frame and
    the deepest pole penetration in its frames; the whole motion: fell, head touched."""
    fig, b = comp.figure, bounds[0]
    base = traj.site("base_centre")[0]                               # [F, 2]
    checks, done = {}, {}
    for k, part in enumerate(comp.parts):
        lo, hi = int(b[k]), int(b[k + 1])
        d = float(np.linalg.norm(base[hi] - comp.scenes[k].goal[:2]))
        pole = float(traj.pole_hit[0, lo + 1:hi + 1].max()) if hi > lo else 0.0   # frames this phase ran
        checks[f"{part.name}_distance"], checks[f"{part.name}_pole"] = d, pole
        done[part.name] = bool(d < LAMP_ARRIVED and pole <= 0)
    heads = [fig.contact_names.index(c) for c in ("head_tip", "head_rim")]
    checks["max_pitch"] = float(np.abs(traj.base()[0, :, 0]).max())
    checks["head_force"] = float(traj.contact_force[0][:, heads].max())
    done["upright"] = bool(checks["max_pitch"] <= LAMP_FELL and checks["head_force"] == 0)
    line = "  ".join(f"{p.name}: {checks[p.name + '_distance'] * 100:.1f} cm"
                     + (f", pole {checks[p.name + '_pole'] * 1000:.1f} mm" if checks[p.name + '_pole'] else "")
                     for p in comp.parts) + f"  max |pitch| {checks['max_pitch']:.2f} rad"
    return checks, done, line


def report(label, comp, s, switches):
    totals, credits, traj, bounds = optimize.score(comp, s, [switches])
    checks, done, line = (lamp_checks if comp.figure.name == "lamp" else starman_checks)(comp, traj, bounds)
    print(f"{label}: switches {np.round(switches, 3).tolist()} s  total {totals[0]:.4f}  "
          + "  ".join(f"{k} {v[0]:.3f}" for k, v in credits.items() if k != "total"))
    print(f"   {line}  completes {done}  all {all(done.values())}  diverged {bool(traj.diverged[0])}")
    return {"switches": list(map(float, switches)), "total": float(totals[0]),
            "credits": {k: float(v[0]) for k, v in credits.items() if k != "total"},
            "checks": checks, "completes": done, "all": all(done.values())}, traj


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("controllers", nargs="*")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--Q", type=int, default=16)
    ap.add_argument("--G", type=int, default=16)
    ap.add_argument("--H", type=int, default=4)
    ap.add_argument("--out", default="runs/composite-demo")
    ap.add_argument("--script", help="a script file instead of Table 4 with the controllers' durations")
    ap.add_argument("--composite", help="a composite file (per-phase scenes) instead of three controllers; "
                                        "needs --script")
    ap.add_argument("--refine", help="then refine these phases' controllers (comma list; "
                                     "gpmotion.compose.refine), switch times fixed")
    ap.add_argument("--refine-rounds", type=int, default=16)
    ap.add_argument("--refine-mutants", type=int, default=16)
    a = ap.parse_args(argv)
    if a.composite:
        if a.controllers or not a.script:
            ap.error("--composite FILE takes --script and no controllers")
        comp = C.load(a.composite)
    elif len(a.controllers) != 3:
        ap.error("give three controllers: CART JUMP SHUFFLE (or --composite FILE)")
    else:
        comp = C.from_controllers(a.controllers, names=["cartwheel", "jump", "shuffle"])
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    own = [p.task.seconds for p in comp.parts]
    text = Path(a.script).read_text(encoding="utf-8") if a.script else TABLE4.format(*own)
    s = script.parse(text)
    (out / "script.motion").write_text(text)
    t0 = time.perf_counter()
    optimize.score(comp, s, [comp.switches])          # compile every phase's kernel before timing
    print(f"(warm-up incl. kernel compile/load: {time.perf_counter() - t0:.1f} s)")
    careless, traj0 = report("careless", comp, s, comp.switches)
    t0, c0 = time.perf_counter(), time.process_time()
    ts = optimize.search(comp, s, Q=a.Q, G=a.G, H=a.H, seed=a.seed)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"transition search: {ts.evaluations} simulations of {comp.seconds:g} s in {wall:.1f} s wall, "
          f"{cpu:.1f} s CPU (load average {load:.1f}; Q={a.Q}, G={a.G}, H={a.H}, seed {a.seed})")
    fixed = optimize.repaired(comp, ts)
    repaired, traj1 = report("repaired", fixed, s, fixed.switches)
    refined = None
    C.save(out / "careless.json", comp)
    C.save(out / "repaired.json", fixed)
    if a.refine:
        from gpmotion.compose.refine import refine, save_refined
        t0, c0 = time.perf_counter(), time.process_time()
        fixed, climbs = refine(fixed, s, [p for p in a.refine.split(",") if p], rounds=a.refine_rounds,
                               mutants=a.refine_mutants, seed=a.seed)
        rwall, rcpu = time.perf_counter() - t0, time.process_time() - c0
        n = sum(c["evaluations"] for c in climbs.values())
        print(f"refinement of {a.refine}: {n} simulations in {rwall:.1f} s wall, {rcpu:.1f} s CPU; "
              + "; ".join(f"{k}: {c['before']:.4f} -> {c['after']:.4f} ({c['accepted']} accepted)"
                          for k, c in climbs.items()))
        refined, traj1 = report("refined", fixed, s, fixed.switches)
        refined.update(climbs=climbs, refine_seconds=rwall, refine_cpu_seconds=rcpu)
        fixed = save_refined(out, fixed, climbs)
        C.save(out / "refined.json", fixed)
    try:
        if any(sc is not None for sc in comp.phase_scene_settings):    # per-phase scenes: a strip each
            from gpmotion.compose.playback import render
            _, _, tr0, b0 = optimize.score(comp, s, [comp.switches])
            render(comp, tr0, b0[0], out / "careless.png")
            _, _, tr1, b1 = optimize.score(fixed, s, [fixed.switches])
            render(fixed, tr1, b1[0], out / ("refined.png" if refined else "repaired.png"))
        else:
            from gpmotion.render3d import render_any
            render_any(traj0, out / "careless.png", None, title="careless concatenation (Fig. 13)")
            render_any(traj1, out / ("refined.png" if refined else "repaired.png"), None,
                       title="after the transition search (Fig. 14)" + (" and refinement" if refined else ""))
    except Exception as e:          # pictures are a bonus; the numbers are the result
        print(f"(no filmstrips: {e})")
    summary = {"controllers": a.controllers or [p.source for p in comp.parts], "script": text, "seed": a.seed, "Q": a.Q, "G": a.G, "H": a.H,
               "simulations": ts.evaluations, "search_seconds": wall, "search_cpu_seconds": cpu, "careless": careless,
               "repaired": repaired, **({"refined": refined} if refined else {})}
    if comp.figure.name != "lamp":
        summary["done_ranges"] = {k: [lo, str(hi)] for k, (lo, hi) in DONE.items()}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"wrote {out}/summary.json, careless/repaired .json and .png")


if __name__ == "__main__":
    main()
