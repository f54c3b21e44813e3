"""Simulator throughput benchmark: ``gpmotion bench [--figure F] [--controller sine|gp] [--json] [--quick]``.

The workload is the one a search runs: a batch of controlled episodes of a
figure on the ground, targets changing every step, so the figure moves,
lands and hops: the contact code is exercised, not skipped.  Two controllers:

* ``--controller sine`` (default): each episode drives every actuated joint
  with ``offset + amplitude·sin(ω t + φ)`` (the ``schedule.sines``
  controller) with its own random frequencies;
* ``--controller gp`` (lamp and herman): the figure driven *in-kernel* by
  random GP trees (:func:`bench_gp_trees`: ramped half-and-half trees over
  the primitive set of the figure's GP bench task, fixed seed, rejection-
  sampled to a node-count window), from that task's scene and initial
  state, episodes of the task's length unless ``--seconds`` says otherwise.
  Every episode runs the same trees.

  - lamp: ``lamp_hop``, three trees of 30–40 nodes (3 s episodes);
    ``benchmarks/compare_mujoco.py`` runs the same trees in a MuJoCo +
    ``deap.gp.compile`` Python loop;
  - herman (the 3-D humanoid, fixed pelvis, 29 dof, 6 foot contacts):
    ``herman_touch_nose``, one tree per right-arm actuator (six) of 20–30
    nodes; the other 23 joints hold their neutral pose with PD servos
    (1.5 s episodes).  ``--figure herman`` uses this controller by default.

Reported (one JSON object with ``--json``):

* ``steps_per_s`` — controlled simulation steps per second on ONE thread
  (best of ``repeats`` timed runs after a warm-up compile);
* ``steps_per_s_all_threads`` and ``threads`` — the same batch on every
  rollout thread;
* ``warm_start_s`` — wall time of a fresh ``python`` process that imports
  gpmotion and runs a tiny rollout with the kernel cache warm (interpreter
  start-up included; ``warm_start_inner_s`` excludes it);
* ``gp_evals_per_s`` — random GP controllers on ``lamp_hop`` scored through
  the in-process evaluator (episodes per second, all threads), and
  ``gp_steps_per_s`` the simulated steps per second that implies;
* ``contact_frames`` / ``airborne_frames`` — fractions of recorded frames with
  some / no ground contact, proof that the workload touches the ground;
* ``controller`` (``sine`` or ``gp``) and ``tree_nodes`` (node count of
  each GP tree; ``null`` for sine);
* with ``--controller gp``, ``lazy_branches``: the same trees encoded with
  lazy conditional branches (the default: only the branch taken runs) and
  eagerly (every argument evaluated), timed alternately in one run:
  ``steps_per_s_lazy`` / ``steps_per_s_eager`` (the whole controlled
  simulation, one thread), ``tree_evals_per_s_lazy`` / ``_eager`` (the
  interpreter alone, every tree on the senses the simulation recorded),
  ``ops_per_eval_lazy`` / ``_eager`` (bytecode ops executed per tree
  evaluation, counted in Python on the same senses), and
  ``same_targets`` (both forms gave identical targets on every sense);
* versions, cpu count, figure, episodes, steps.

Timings are wall clock on a shared machine: compare ratios within one run.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

QUICK = dict(seconds=0.5, episodes=8, repeats=2, gp_population=8)
FULL = dict(seconds=2.0, episodes=64, repeats=3, gp_population=64)

_WARM_SNIPPET = """
import time
t0 = time.perf_counter()
import gpmotion
tr = gpmotion.simulate({figure!r}, 0.05)
assert not tr.diverged[0]
print(time.perf_counter() - t0)
"""


def sine_workload(fig, episodes: int, seed: int = 0):
    """Per-episode random sines around the neutral pose (amplitudes big enough to hop).

    Returns ``(offset, amplitude, omega, phase)``, each ``[episodes, n_act]``.
    """
    rng = np.random.default_rng(seed)
    na = fig.n_act
    lim = fig.actuator_limits()
    span = np.where(np.isfinite(lim[:, 1] - lim[:, 0]), lim[:, 1] - lim[:, 0], 2.0)
    offset = fig.model.neutral + rng.uniform(-0.1, 0.1, (episodes, na)) * span
    amplitude = rng.uniform(0.2, 0.4, (episodes, na)) * span
    omega = rng.uniform(4.0, 14.0, (episodes, na))
    phase = rng.uniform(0.0, 2 * np.pi, (episodes, na))
    return offset, amplitude, omega, phase


CONTROLLERS = ("sine", "gp")
GP_TREE_SEED = 0
GP_TREE_NODES = (30, 40)          # inclusive node-count window of each benchmark tree
GP_TREE_DEPTH = (2, 6)            # ramped half-and-half depth range
# figure → (GP bench task, node-count window of its trees)
GP_BENCH_TASKS = {"lamp": ("lamp_hop", GP_TREE_NODES), "herman": ("herman_touch_nose", (20, 30))}


def bench_gp_trees(seed: int = GP_TREE_SEED, nodes: tuple[int, int] | None = None,
                   depth: tuple[int, int] = GP_TREE_DEPTH, max_tries: int = 100_000,
                   figure: str = "lamp"):
    """The benchmark's GP controller: ``(task, family, trees)`` for a figure's GP
    bench task (``GP_BENCH_TASKS``: ``lamp_hop`` for the lamp, ``herman_touch_nose``
    for herman).

    ``trees`` is one token list per controlled actuator (three for the lamp, the
    six right-arm actuators for herman), each a ramped half-and-half tree of
    the task's primitive set whose node count lies in ``nodes`` (default: the
    figure's window; rejection sampling).  Deterministic for a seed; Python's
    global ``random`` state (DEAP's generator) is restored after.
    """
    import random

    from deap import gp

    from .families.gp import GPFamily
    from .gp.bytecode import tree_to_tokens
    from .task import get_task

    task_name, default_nodes = GP_BENCH_TASKS[figure]
    task = get_task(task_name)
    fam = GPFamily(task)
    lo, hi = nodes or default_nodes
    saved = random.getstate()
    try:
        random.seed(seed)
        trees = []
        for _ in range(max_tries):
            t = gp.PrimitiveTree(gp.genHalfAndHalf(fam.pset, depth[0], depth[1]))
            if lo <= len(t) <= hi:
                trees.append(tree_to_tokens(t))
                if len(trees) == len(fam.actuators):
                    break
        else:
            raise RuntimeError(f"no {len(fam.actuators)} trees of {lo}..{hi} nodes "
                               f"in {max_tries} draws")
    finally:
        random.setstate(saved)
    return task, fam, trees


def _count_ops(ci, cf, tree_index, senses, prims) -> int:
    """Bytecode ops run_tree executes on one sense vector (plain Python walk)."""
    from .gp.bytecode import HEADER, OP_ARG_SENSE0, OP_JUMP, OP_PRIM0, OP_PUSH_SENSE
    from .gp.primitives import branch_index, clamp
    h = HEADER + 3 * tree_index
    pos, end = int(ci[h + 1]), int(ci[h + 1]) + 2 * int(ci[h + 2])
    stack, n = [], 0
    while pos < end:
        op, arg = int(ci[pos]), int(ci[pos + 1])
        pos, n = pos + 2, n + 1
        if op == OP_JUMP:
            pos += 2 * arg
        elif op < OP_JUMP:
            stack.append(clamp(senses[arg]) if op == OP_PUSH_SENSE else float(cf[arg]))
        elif op < OP_PRIM0:                     # a subgoal flag (bench trees have none)
            stack.append(0.0)
        else:
            p = prims[op - OP_PRIM0]
            if arg >= OP_ARG_SENSE0:            # fused: push sense arg - OP_ARG_SENSE0, apply
                stack.append(clamp(senses[arg - OP_ARG_SENSE0]))
                arg = 0
            k = p.arity if arg == 0 else len(p.select)
            args = stack[len(stack) - k:]
            del stack[len(stack) - k:]
            if arg == 0:
                stack.append(clamp(p.func(*args)))
            else:
                j = int(branch_index(p, args))
                pos += 2 * (len(p.branches) - 1 if j == 0 else j - 1)
    return n


def _lazy_vs_eager(fig, scene, fam, trees, episodes, n_steps, q0, qd0, dt, repeats) -> dict:
    """The same trees, lazy and eager bytecode: whole-simulation steps/s on one
    thread, interpreter-only tree evaluations/s, ops per evaluation."""
    import gpmotion
    from numba import njit

    from .gp.bytecode import encode_batch
    from .gp.interpreter import load_interpreter
    kernel = load_interpreter(fam.info)
    forms = {lz: encode_batch([trees] * episodes, fam.info, fam.actuators, lazy=lz)
             for lz in (True, False)}
    tr = gpmotion.rollout(fig, scene, forms[True], n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,
                          threads=1, record_senses=True)
    senses = np.ascontiguousarray(tr.senses[0].reshape(-1, tr.senses.shape[-1]), dtype=np.float64)

    @njit(cache=False)
    def drive(run_tree, ci, cf, n_trees, senses, stack, out):
        for s in range(senses.shape[0]):
            for k in range(n_trees):
                out[s, k] = run_tree(ci, cf, k, senses[s], stack)

    stack = np.zeros(forms[True].cstate_size)
    outs, best_steps, best_evals = {}, {True: np.inf, False: np.inf}, {True: np.inf, False: np.inf}
    for lz, b in forms.items():                    # compile both paths before timing
        outs[lz] = np.zeros((len(senses), len(trees)))
        drive(kernel.run_tree, b.ci[0], b.cf[0], len(trees), senses, stack, outs[lz])
    for _ in range(max(1, repeats)):               # alternate: shared-machine noise hits both
        for lz, b in forms.items():
            best_steps[lz] = min(best_steps[lz], _best_time(lambda: gpmotion.rollout(
                fig, scene, b, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt, threads=1), 1))
            best_evals[lz] = min(best_evals[lz], _best_time(lambda: drive(
                kernel.run_tree, b.ci[0], b.cf[0], len(trees), senses, stack, outs[lz]), 3))
    steps = episodes * n_steps
    evals = len(senses) * len(trees)
    prims = fam.info.primitives
    step_idx = range(0, len(senses), max(1, len(senses) // 50))    # 50 frames suffice to count
    ops = {lz: np.mean([_count_ops(b.ci[0], b.cf[0], k, senses[i], prims)
                        for i in step_idx for k in range(len(trees))]) for lz, b in forms.items()}
    return {"steps_per_s_lazy": steps / best_steps[True], "steps_per_s_eager": steps / best_steps[False],
            "tree_evals_per_s_lazy": evals / best_evals[True],
            "tree_evals_per_s_eager": evals / best_evals[False],
            "ops_per_eval_lazy": float(ops[True]), "ops_per_eval_eager": float(ops[False]),
            "conditionals": sum(tok in [p.name for p in prims if p.conditional]
                                for t in trees for tok in t),
            "same_targets": bool(np.array_equal(outs[True], outs[False]))}


def _best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _warm_start(figure: str, runs: int = 2) -> tuple[float, float]:
    """(wall, in-process) seconds of a fresh interpreter; the first run warms the cache."""
    code = _WARM_SNIPPET.format(figure=figure)
    walls, inner = [], []
    for _ in range(runs + 1):
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=dict(os.environ), timeout=600)
        wall = time.perf_counter() - t0
        if out.returncode != 0:
            raise RuntimeError(f"warm-start subprocess failed: {out.stderr.strip()[-500:]}")
        walls.append(wall)
        inner.append(float(out.stdout.strip().splitlines()[-1]))
    return min(walls[1:]), min(inner[1:])


def _gp_bench(population: int, threads: int, repeats: int, seed: int = 0,
              task_name: str = "lamp_hop") -> dict:
    """Random GP controllers (ramped half-and-half, depth 2..6) on a task (lamp_hop)."""
    import random

    from deap import gp

    from .inprocess import InProcessEvaluator
    from .families.gp import GPFamily
    from .task import get_task

    task = get_task(task_name)
    fam = GPFamily(task)
    saved = random.getstate()
    random.seed(seed)
    genomes = [[gp.PrimitiveTree(gp.genHalfAndHalf(fam.pset, 2, 6)) for _ in fam.actuators]
               for _ in range(population)]
    random.setstate(saved)
    ev = InProcessEvaluator(task, fam, threads=threads)
    ev.evaluate(genomes[:2])                      # compile / load the interpreter and kernel
    t = _best_time(lambda: ev.evaluate(genomes), repeats)
    return {"gp_evals_per_s": population / t, "gp_steps_per_s": population * task.n_steps / t,
            "gp_population": population, "gp_task": task.name, "gp_steps": task.n_steps}


def run_bench(figure: str = "lamp", seconds: float | None = None, episodes: int | None = None,
              threads: int | None = None, *, quick: bool = False, repeats: int | None = None,
              gp: bool = True, warm_start: bool = True, seed: int = 0,
              controller: str | None = None) -> dict:
    """Measure simulator throughput; returns a JSON-able dict (see the module doc)."""
    import numba

    import gpmotion
    from gpmotion.controllers import schedule

    cfg = dict(QUICK if quick else FULL)
    seconds_arg = seconds
    seconds = float(seconds if seconds is not None else cfg["seconds"])
    episodes = int(episodes if episodes is not None else cfg["episodes"])
    repeats = int(repeats if repeats is not None else cfg["repeats"])
    max_threads = numba.config.NUMBA_NUM_THREADS
    threads = int(min(threads or max_threads, max_threads))

    fig = gpmotion.load_figure(figure)
    if controller is None:                         # herman: the GP arm; others: sines
        controller = "gp" if fig.name == "herman" else "sine"
    if controller not in CONTROLLERS:
        raise ValueError(f"controller must be one of {', '.join(CONTROLLERS)}, got {controller!r}")
    tree_nodes = None
    gp_task = None
    q0 = qd0 = None
    if controller == "gp":
        if fig.name not in GP_BENCH_TASKS:
            raise ValueError(f"--controller gp needs --figure {' or '.join(GP_BENCH_TASKS)}, "
                             f"got {fig.name!r}")
        task, fam, trees = bench_gp_trees(seed, figure=fig.name)
        gp_task = task.name
        tree_nodes = [len(t) for t in trees]
        scene = task.scene()
        q0, qd0 = task.initial_state()
        ctrl = fam.encode([trees] * episodes)
        dt = task.dt
        if seconds_arg is None:
            seconds = task.seconds                 # episodes of lamp_hop length
    else:
        scene = gpmotion.make_scene()
        ctrl = schedule.sines(*sine_workload(fig, episodes, seed))
        dt = 1e-3
    n_steps = int(round(seconds / dt))

    def run(th):
        return gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,
                                threads=th)

    t0 = time.perf_counter()
    tr = run(1)                                    # compiles, or loads the cache
    first_call_s = time.perf_counter() - t0
    steps = episodes * n_steps                     # advances per episode (frames may round up)
    t1 = _best_time(lambda: run(1), repeats)
    tn = _best_time(lambda: run(threads), repeats)
    touching = tr.contact_force.sum(axis=-1) > 0
    result = {
        "figure": fig.name,
        "controller": controller,
        "tree_nodes": tree_nodes,
        "gp_controlled": ([fig.actuator_names[a] for a in fam.actuators]
                          if controller == "gp" else None),
        "gp_controller_task": gp_task,
        "dimensions": fig.dimensions,
        "links": int(len(fig.model.parent)),
        "dofs": int(fig.nv),
        "contacts": int(len(fig.model.cp_link)),
        "episodes": episodes,
        "steps": steps,
        "steps_per_episode": steps // episodes,
        "dt": dt,
        "steps_per_s": steps / t1,
        "steps_per_s_all_threads": steps / tn,
        "threads": threads,
        "seconds_one_thread": t1,
        "seconds_all_threads": tn,
        "first_call_s": first_call_s,
        "diverged": int(tr.diverged.sum()),
        "contact_frames": float(touching.mean()),
        "airborne_frames": float((~touching).mean()),
        "numba": numba.__version__,
        "numpy": np.__version__,
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
        "quick": bool(quick),
    }
    if controller == "gp":
        result["lazy_branches"] = _lazy_vs_eager(fig, scene, fam, trees, episodes, n_steps,
                                                 q0, qd0, dt, repeats)
    if warm_start:
        result["warm_start_s"], result["warm_start_inner_s"] = _warm_start(fig.name)
    if gp and fig.name in GP_BENCH_TASKS:
        result.update(_gp_bench(cfg["gp_population"], threads, repeats, seed,
                                GP_BENCH_TASKS[fig.name][0]))
    return result


def format_report(r: dict) -> str:
    if r.get("controller") == "gp":
        what = (f"{len(r['tree_nodes'])} random GP trees in-kernel "
                f"({'/'.join(map(str, r['tree_nodes']))} nodes"
                f"{', ' + r['gp_controller_task'] if r.get('gp_controller_task') else ''})")
    else:
        what = "sine targets every step"
    lines = [f"gpmotion bench — figure {r['figure']} ({r.get('dimensions', 2)}-D, "
             f"{r.get('links', '?')} links, {r.get('contacts', '?')} contacts), {r['episodes']} episodes × "
             f"{r['steps_per_episode']} steps (dt {r['dt'] * 1e3:g} ms), {what}",
             f"  one thread        {r['steps_per_s'] / 1e6:8.3f} M steps/s",
             f"  {r['threads']} threads{' ' * (9 - len(str(r['threads'])))}"
             f"{r['steps_per_s_all_threads'] / 1e6:8.3f} M steps/s",
             f"  ground contact in {100 * r['contact_frames']:.0f}% of frames, airborne "
             f"{100 * r['airborne_frames']:.0f}%, diverged episodes {r['diverged']}"]
    lb = r.get("lazy_branches")
    if lb:
        ratio = lb["steps_per_s_lazy"] / lb["steps_per_s_eager"]
        lines.append(f"  lazy branches     {lb['steps_per_s_lazy'] / 1e6:8.3f} M steps/s vs eager "
                     f"{lb['steps_per_s_eager'] / 1e6:.3f} (x{ratio:.2f}); "
                     f"interpreter alone {lb['tree_evals_per_s_lazy'] / 1e6:.2f} vs "
                     f"{lb['tree_evals_per_s_eager'] / 1e6:.2f} M tree evals/s "
                     f"(x{lb['tree_evals_per_s_lazy'] / lb['tree_evals_per_s_eager']:.2f}), "
                     f"{lb['ops_per_eval_lazy']:.1f} vs {lb['ops_per_eval_eager']:.1f} ops per tree, "
                     f"{lb['conditionals']} conditionals, "
                     f"{'same' if lb['same_targets'] else 'DIFFERENT'} targets")
    if "warm_start_s" in r:
        lines.append(f"  warm start        {r['warm_start_s']:8.3f} s  (import + tiny rollout in a "
                     f"fresh process; {r['warm_start_inner_s']:.3f} s after interpreter start)")
    if "gp_evals_per_s" in r:
        lines.append(f"  GP on {r['gp_task']}    {r['gp_evals_per_s']:8.1f} evaluations/s "
                     f"({r['gp_steps_per_s'] / 1e6:.3f} M steps/s, population {r['gp_population']})")
    lines.append(f"  numba {r['numba']}, numpy {r['numpy']}, python {r['python']}, "
                 f"{r['cpu_count']} cpus")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="gpmotion bench", description="simulator throughput benchmark")
    p.add_argument("--figure", default="lamp", help="figure name (default: lamp)")
    p.add_argument("--controller", choices=CONTROLLERS, default=None,
                   help="what drives the joints: per-episode sines (default; herman: gp) or "
                        "random GP trees in-kernel (lamp: three ~35-node trees, lamp_hop "
                        "episodes; herman: six 20-30-node trees on the right arm, "
                        "herman_touch_nose episodes)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quick", action="store_true", help="CI-sized run (seconds, not minutes)")
    p.add_argument("--seconds", type=float, default=None, help="simulated seconds per episode")
    p.add_argument("--episodes", type=int, default=None, help="episodes per batch")
    p.add_argument("--threads", type=int, default=None, help="threads for the all-threads run")
    p.add_argument("--no-gp", action="store_true", help="skip the GP evaluation benchmark")
    p.add_argument("--no-warm-start", action="store_true", help="skip the fresh-process timing")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from .figures import figure_names
    if args.figure not in figure_names():
        print(f"gpmotion bench: unknown figure {args.figure!r}; known: {', '.join(figure_names())}",
              file=sys.stderr)
        return 2
    for name in ("seconds", "episodes", "threads"):
        v = getattr(args, name)
        if v is not None and not (np.isfinite(v) and v > 0):
            print(f"gpmotion bench: --{name} must be > 0, got {v}", file=sys.stderr)
            return 2
    if args.controller == "gp" and args.figure not in GP_BENCH_TASKS:
        print(f"gpmotion bench: --controller gp runs a task's GP trees; it needs --figure "
              f"{' or --figure '.join(GP_BENCH_TASKS)}, got {args.figure!r}", file=sys.stderr)
        return 2
    r = run_bench(args.figure, args.seconds, args.episodes, args.threads, quick=args.quick,
                  gp=not args.no_gp, warm_start=not args.no_warm_start,
                  controller=args.controller)
    print(json.dumps(r, indent=2) if args.json else format_report(r))
    return 0


if __name__ == "__main__":
    sys.exit(main())
