"""The GP interpreter with libm's sin/cos against the inlined fast ones (family option fast_trig).

    python benchmarks/gp_fast_trig_ab.py [--part accuracy,interpreter,rollout] [--episodes 1]
                                         [--repeats 41] [--population 30] [--samples 200000]

Three parts, each the two forms in one process (the machine is shared and
loaded: read the ratios of one run, and the bests of interleaved repeats):

* ``accuracy``: the compiled fast ``sin``/``cos`` (gpmotion.gp.fast_trig, as
  the generated interpreter holds them) against ``math.sin``/``math.cos``:
  the largest error in ulps and the share of bitwise-identical results, on
  the arguments the trees really see (every sin/cos argument of the lamp
  bench trees and of ``--population`` first-generation lamp_hop individuals
  on the senses of the bench workload), on uniform ranges up to the clamp
  (±1e6), next to multiples of pi/2 (where the reduction cancels), and on
  magnitudes up to 1e300 with inf and NaN (libm beyond 2^20 pi/2);
* ``interpreter``: ns per control step of the stack interpreter, libm / fast,
  on the recorded senses of the GP bench workload (as
  ``gp_register_ab.py``): the three lamp bench trees, then the bench trees
  with ``--population`` first-generation individuals; with the share of
  tree outputs bit for bit equal (fast / libm) and the largest difference.
  A third form, ``no trig`` (sin and cos replaced by a multiplication,
  timing only), bounds what any sine and cosine could gain;
* ``rollout``: whole-rollout evaluations/s of lamp_hop (``gpmotion.rollout``,
  one thread) for the bench trees and for a first generation, libm / fast
  (and no trig, the bound).

The search results both ways come from ``time_to_solution.py`` (its
``--option`` passes a family option)::

    python benchmarks/time_to_solution.py --tasks lamp_hop --seeds 0,1,2,3,4 --threads 1 --only new
    python benchmarks/time_to_solution.py --tasks lamp_hop --seeds 0,1,2,3,4 --threads 1 --only new \\
        --option fast_trig=true

Measured (docs/speed.md, "A fast sine and cosine"; one run, a loaded 2-core
machine, ``--repeats 121``): at most 1 ulp from libm anywhere, 96-98 % of
results bit for bit libm's (100 % next to multiples of pi/2, where the
reduction cancels); the interpreter x1.16 on the bench trees (588.8 ->
506.2 ns a step; without any trigonometry 274.2) and x1.12 on a first
generation; lamp_hop rollouts x1.09 (bench trees) and x1.03-1.04 (first
generation).  Searches: lamp_hop seeds 0-9 reach a final cost <= 0.08 on
5/10 with fast_trig and 7/10 without (every run solved; mean cost 0.0796
and 0.0789).  Opt-in; the default stays libm's.
"""
from __future__ import annotations

import argparse
import math
import random
import statistics
import time

import numpy as np
from numba import njit

PARTS = ("accuracy", "interpreter", "rollout")


# ---------------------------------------------------------------- accuracy

def ulp_distance(a, b) -> np.ndarray:
    """|a - b| in units in the last place (0 for equal bits; NaN vs NaN is 0)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    ua, ub = ordered(a), ordered(b)
    d = np.where(ua >= ub, ua - ub, ub - ua).astype(np.float64)     # exact up to 2^53 ulp
    return np.where(np.isnan(a) & np.isnan(b), 0.0, d)


def ordered(x: np.ndarray) -> np.ndarray:
    """The bit patterns as uint64 in the order of the floats (-0.0 and 0.0 adjacent)."""
    u = x.view(np.uint64)
    sign = np.uint64(1 << 63)
    return np.where(u & sign, ~u, u | sign)


@njit(cache=False)
def _apply(f, x, out):
    for i in range(x.shape[0]):
        out[i] = f(x[i])


def compiled(f, x) -> np.ndarray:
    out = np.empty_like(x)
    _apply(f, np.ascontiguousarray(x, dtype=np.float64), out)
    return out


def trig_arguments(trees_per_ind, senses, info) -> dict:
    """Every argument sin and cos are called with, by a plain evaluation of
    the token lists with the interpreter's value rule (clamp, protected
    primitives), on every sense vector: {"sin": array, "cos": array}."""
    from gpmotion.gp import primitives as registry
    from gpmotion.gp.primitives import clamp
    funcs = {p.name: p.func for p in info.primitives}
    arity = {p.name: p.arity for p in info.primitives}
    index = dict(zip(info.terminal_names, info.sense_indices))
    seen = {"sin": [], "cos": []}

    def ev(tokens, pos, s):
        tok = tokens[pos]
        if isinstance(tok, float):
            return clamp(tok), pos + 1
        if tok in index:
            return clamp(s[index[tok]]), pos + 1
        args, pos = [], pos + 1
        for _ in range(arity[tok]):
            v, pos = ev(tokens, pos, s)
            args.append(v)
        if tok in seen:
            seen[tok].append(args[0])
        return clamp(funcs[tok](*args)), pos

    registry.load_builtin()
    for trees in trees_per_ind:
        for s in senses:
            for t in trees:
                ev(t, 0, s)
    return {k: np.array(v) for k, v in seen.items()}


def accuracy_sets(tree_args: dict, n: int) -> list[tuple[str, dict]]:
    rng = np.random.default_rng(0)
    k = np.arange(1, 1e6 / (math.pi / 2))
    near = k * (math.pi / 2)
    near = np.concatenate([near, np.nextafter(near, np.inf), np.nextafter(near, -np.inf), -near])
    mags = 10.0 ** rng.uniform(-300, 300, n) * rng.choice([-1.0, 1.0], n)
    wide = np.concatenate([mags, [np.inf, -np.inf, np.nan, 0.0, -0.0, 5e-324, 1e6, -1e6,
                                  1647099.3291652855, 1647099.3291652857]])
    sets = [(f"sin/cos arguments of the {name}", args) for name, args in tree_args.items()]
    for lo in (1.0, 10.0, 1e3, 1e6):
        x = rng.uniform(-lo, lo, n)
        sets.append((f"uniform in ±{lo:g}", {"sin": x, "cos": x}))
    sets.append(("doubles next to k pi/2 up to 1e6", {"sin": near, "cos": near}))
    sets.append(("|x| log-uniform 1e-300..1e300, inf, NaN", {"sin": wide, "cos": wide}))
    return sets


def part_accuracy(fast, tree_args: dict, n: int) -> None:
    libm = {"sin": math.sin, "cos": math.cos}
    fns = {"sin": fast._ft_sin, "cos": fast._ft_cos}
    print("accuracy: fast against math.sin / math.cos (max ulp, share bitwise identical)")
    worst = 0.0
    for name, args in accuracy_sets(tree_args, n):
        cols = []
        for f in ("sin", "cos"):
            x = args[f]
            got = compiled(fns[f], x)
            want = np.array([libm[f](v) if math.isfinite(v) else math.nan for v in x])
            u = ulp_distance(got, want)
            worst = max(worst, float(u.max()))
            cols.append(f"{f} {int(u.max())} ulp, {np.mean(u == 0):.4%} ({len(x):,} args)")
        print(f"  {name:44s} " + "; ".join(cols))
    print(f"  largest error anywhere: {int(worst)} ulp")


# ---------------------------------------------------------------- interpreter

@njit(cache=False)
def _drive(run_tree, ci, cf, n, senses, cstate, out):
    for s in range(senses.shape[0]):
        for k in range(n):
            out[s, k] = run_tree(ci, cf, k, senses[s], cstate)


def interleaved(forms: dict, repeats: int) -> dict:
    """{name: [seconds per repeat]} with the forms run in turn, after one warm call each."""
    for f in forms.values():
        f()
    times = {k: [] for k in forms}
    for _ in range(repeats):
        for k, f in forms.items():
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return times


def report(label: str, times: dict, unit: float, what: str, invert: bool = False) -> None:
    """Median and best of each form (seconds * unit), and libm / fast (ratio of the bests)."""
    parts = []
    for k, v in times.items():
        v = [unit / t if invert else t * unit for t in v]
        best = max(v) if invert else min(v)
        parts.append(f"{k} median {statistics.median(v):.1f} best {best:.1f}")
    b = {k: min(v) for k, v in times.items()}
    ratios = "".join(f", {k} x{b['libm'] / b[k]:.3f}" for k in times if k != "libm")
    print(f"  {label}: {what}: " + "; ".join(parts) + f"; speed-up over libm (bests){ratios}")


def part_interpreter(kernels, batches, senses, repeats) -> None:
    print("interpreter: ns per control step (all trees of an individual on one sense vector)")
    for label, batch in batches.items():
        rows = [(np.ascontiguousarray(batch.ci[i]), np.ascontiguousarray(batch.cf[i]))
                for i in range(batch.ci.shape[0])]
        n_steps = len(senses[label])
        outs = {k: [np.zeros((n_steps, int(ci[0]))) for ci, _ in rows] for k in kernels}
        cst = np.zeros(batch.cstate_size)

        def form(k):
            def run():
                for (ci, cf), out in zip(rows, outs[k]):
                    _drive(kernels[k].run_tree, ci, cf, int(ci[0]), senses[label], cst, out)
            return run
        times = interleaved({k: form(k) for k in kernels}, repeats)        # no trig: timing only
        a = np.concatenate([o.ravel() for o in outs["libm"]])
        b = np.concatenate([o.ravel() for o in outs["fast"]])
        same = np.mean(a.view(np.int64) == b.view(np.int64))
        per = 1e9 / (n_steps * len(rows))
        report(label, times, per, "ns/step")
        print(f"    {len(rows)} individuals x {n_steps} sense vectors; outputs bitwise equal "
              f"{same:.4%}, largest difference {np.max(np.abs(a - b)):.3g}")


# ---------------------------------------------------------------- rollout

def part_rollout(task, families, no_trig, genomes: dict, repeats) -> None:
    """``no_trig``: the module of :func:`no_trig_interpreter` (timing only)."""
    import gpmotion
    print("rollout: lamp_hop evaluations per second (one thread)")
    q0, qd0 = task.initial_state()
    fig, scene = task.figure, task.scene()
    for label, gs in genomes.items():
        batch = {k: fam.encode(gs) for k, fam in families.items()}
        batch["no trig"] = batch["libm"]._replace(module=no_trig.__file__)

        def form(k):
            return lambda: gpmotion.rollout(fig, scene, batch[k], n_steps=task.n_steps, q0=q0,
                                            qd0=qd0, dt=task.dt, threads=1)
        times = interleaved({k: form(k) for k in batch}, repeats)
        report(label, times, len(gs), "evaluations/s", invert=True)


# ---------------------------------------------------------------- main

def no_trig_interpreter(info):
    """The interpreter with sin and cos replaced by a multiplication (as
    ``gp_register_ab.py --cheap-trig``): what the trees cost without the
    trigonometry, a bound on what any sine and cosine can gain."""
    from gpmotion.cache import digest, import_file, write_module
    from gpmotion.gp.interpreter import interpreter_source
    src = (interpreter_source(info).replace("return math.cos(a)", "return a * 0.5")
           .replace("return math.sin(a)", "return a * 0.25"))
    return import_file(write_module(f"gp_notrig_{digest(src)}", src))


def first_generation(fam, n: int) -> list:
    """n ramped half-and-half individuals of lamp_hop (depth 2..6), seeded."""
    from deap import gp

    from gpmotion.gp.bytecode import tree_to_tokens
    saved = random.getstate()
    random.seed(1)
    try:
        return [[tree_to_tokens(gp.PrimitiveTree(gp.genHalfAndHalf(fam.pset, 2, 6)))
                 for _ in fam.actuators] for _ in range(n)]
    finally:
        random.setstate(saved)


def main(argv=None) -> int:
    import gpmotion
    from gpmotion.bench import bench_gp_trees
    from gpmotion.families import make_family
    from gpmotion.gp.interpreter import load_interpreter

    from kernel_profile import workload

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--part", default=",".join(PARTS))
    p.add_argument("--episodes", type=int, default=1, help="bench-workload episodes recorded")
    p.add_argument("--repeats", type=int, default=41)
    p.add_argument("--population", type=int, default=30)
    p.add_argument("--samples", type=int, default=200_000, help="arguments per uniform range")
    a = p.parse_args(argv)
    parts = a.part.split(",")
    fig, scene, ctrl, n_steps, q0, qd0, dt = workload("lamp_gp", a.episodes)
    tr = gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,
                          record_every=1, record_senses=True, threads=1)
    senses = np.ascontiguousarray(tr.senses.reshape(-1, tr.senses.shape[-1]))
    task, fam, trees = bench_gp_trees(0, figure="lamp")
    pop = first_generation(fam, a.population)
    few = senses[:: max(1, len(pop) // 2)]          # the population on fewer sense vectors
    kernels = {"libm": load_interpreter(fam.info), "fast": load_interpreter(fam.info, True),
               "no trig": no_trig_interpreter(fam.info)}
    if "accuracy" in parts:
        args = {"bench trees": trig_arguments([trees], senses, fam.info),
                f"{len(pop)} first-generation individuals": trig_arguments(pop, few, fam.info)}
        part_accuracy(kernels["fast"], args, a.samples)
    if "interpreter" in parts:
        part_interpreter(kernels, {"bench trees": fam.encode([trees]),
                                   f"bench trees + {len(pop)} first-generation":
                                       fam.encode([trees] + pop)},
                         {"bench trees": senses, f"bench trees + {len(pop)} first-generation": few},
                         a.repeats)
    if "rollout" in parts:
        fams = {"libm": fam, "fast": make_family("gp", task, fast_trig=True)}
        part_rollout(task, fams, kernels["no trig"], {"bench trees x 8 episodes": [trees] * 8,
                                  f"{len(pop)} first-generation individuals": pop},
                     max(5, a.repeats // 3))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
