"""A register form of the GP interpreter against the stack form, on the same trees and senses.

    python benchmarks/gp_register_ab.py [--figure lamp|herman] [--episodes 4] [--repeats 31]
                                        [--population 0]

The stack interpreter (gpmotion.gp.interpreter) runs one dispatch per op,
and a third of a tree's ops push a sense or a constant.  The register form
(:func:`translate`) reads the same postfix ops once and writes one
instruction per primitive whose operands name registers: a stack slot, or a
sense (clamped) or constant loaded once per control step for all the trees
(``loads``).  Pushes then cost no dispatch; lazy branches keep their jumps
(everything still pending is written to its stack slot at a jump or a
join).  A tree the translation cannot prove well formed (stack depth,
jumps inside the tree) keeps the stack form, which gives 0.0 where its
checks fail.  Values are those of the stack form bit for bit: the same
primitive calls on the same values, the same clamps.

Timed on senses recorded from the workload of ``gpmotion bench --controller
gp`` (the trees of ``compare_mujoco.py``), every tree on every sense vector,
the two forms in turn ``--repeats`` times; prints ops and instructions per
step, the ns per step of each form (median, min-max, best), and whether the
outputs agreed bit for bit.  ``--population N`` adds N first-generation
random individuals of the task (ramped half-and-half, depth 2..6).
``--cheap-trig`` times both forms with ``sin`` and ``cos`` replaced by a
multiplication: what the interpretation itself costs.

Measured (docs/speed.md): no faster on the lamp (×0.99-1.01 on the bench
trees, ×0.73-0.89 on first-generation populations, ×0.93 without the
trigonometry), ×1.06-1.12 on herman's six arm trees: dispatching a fused or
plain push costs about what reading an operand's register index does, and
the lamp bench trees' 16 ``sin``/``cos`` calls a step take about half of the
controller's time.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from numba import njit

from gpmotion.gp.opcodes import (HEADER, OP_ARG_SENSE0, OP_JUMP, OP_PRIM0, OP_PUSH_CONST,
                                 OP_PUSH_FLAG, OP_PUSH_SENSE, STACK_CAP)
from gpmotion.gp.subgoals import MAX_SUBGOALS
from gpmotion.gp.task_senses import MAX_TASK_SENSES

WIDTH = 6          # an instruction: kind, dst, up to four operand registers


class Fallback(Exception):
    """The tree keeps the stack form."""


def translate(ci, k: int, prims):
    """Program k of a ci row -> (instructions with symbolic operands, output operand,
    deepest stack slot + 1).

    Operands: ``("slot", i)`` stack slot i, ``("s", i)`` clamped sense i,
    ``("c", i)`` constant cf[i], ``("f", i)`` controller slot STACK_CAP + i.
    Instruction kinds: ``("prim", j)``, ``("sel", j)``, ``("jump",)``, ``("move",)``.
    Raises Fallback where the stack form's run-time checks could fire."""
    h = HEADER + 3 * k
    start, n = int(ci[h + 1]), int(ci[h + 2])
    ops = [(int(ci[start + 2 * i]), int(ci[start + 2 * i + 1])) for i in range(n)]
    code: list = []
    vstack: list = []
    incoming: dict = {}          # position -> stack depth of the jumps into it
    pos_index: dict = {}         # position -> index of the next instruction emitted there
    patches: list = []           # (instruction index, target position)
    selects: list = []           # (instruction index, position, n branches)
    reachable = True
    depth_max = 0

    def materialize():
        for i, d in enumerate(vstack):
            if d != ("slot", i):
                code.append([("move",), ("slot", i), d])
                vstack[i] = ("slot", i)

    def jump_into(target, depth):
        if incoming.setdefault(target, depth) != depth:
            raise Fallback("paths join with different stack depths")

    for p in range(n + 1):
        if p in incoming:
            if reachable:
                materialize()
                if len(vstack) != incoming[p]:
                    raise Fallback("fall-through and jump disagree on the depth")
            else:
                vstack = [("slot", i) for i in range(incoming[p])]
                reachable = True
        elif not reachable:
            continue                     # never run
        pos_index[p] = len(code)
        if p == n:
            break
        op, arg = ops[p]
        depth_max = max(depth_max, len(vstack) + 1)
        if op in (OP_PUSH_SENSE, OP_PUSH_CONST, OP_PUSH_FLAG):
            if len(vstack) >= STACK_CAP:
                raise Fallback("stack overflow")
            if op == OP_PUSH_FLAG and not 0 <= arg < MAX_SUBGOALS + MAX_TASK_SENSES:
                raise Fallback("flag out of range")
            vstack.append(({OP_PUSH_SENSE: "s", OP_PUSH_CONST: "c", OP_PUSH_FLAG: "f"}[op], arg))
        elif op == OP_JUMP:
            if arg < 0 or p + 1 + arg > n:
                raise Fallback("jump out of the tree")
            materialize()
            jump_into(p + 1 + arg, len(vstack))
            patches.append((len(code), p + 1 + arg))
            code.append([("jump",)])
            reachable = False
        elif OP_PRIM0 <= op < OP_PRIM0 + len(prims):
            j = op - OP_PRIM0
            pr = prims[j]
            if arg == 0 or arg >= OP_ARG_SENSE0:
                fused = arg >= OP_ARG_SENSE0
                taken = pr.arity - 1 if fused else pr.arity
                if len(vstack) < taken or (fused and len(vstack) >= STACK_CAP):
                    raise Fallback("stack underflow")
                args = vstack[len(vstack) - taken:] + ([("s", arg - OP_ARG_SENSE0)] if fused else [])
                del vstack[len(vstack) - taken:]
                code.append([("prim", j), ("slot", len(vstack))] + args)
                vstack.append(("slot", len(vstack)))
            elif arg == 1 and pr.conditional:
                m, nb = len(pr.select), len(pr.branches)
                if len(vstack) < m:
                    raise Fallback("stack underflow")
                sel = vstack[len(vstack) - m:]
                del vstack[len(vstack) - m:]
                materialize()
                if p + nb >= n:
                    raise Fallback("branch table out of the tree")
                for s in range(nb):
                    jump_into(p + 1 + s, len(vstack))
                selects.append((len(code), p, nb))
                code.append([("sel", j)] + sel)
                reachable = False
            else:
                raise Fallback("bad operand")
        else:
            raise Fallback("bad opcode")
    if not reachable or len(vstack) != 1:
        raise Fallback("not one value at the end")
    for idx, target in patches:
        code[idx].append(("pc", pos_index[target]))
    for idx, p, nb in selects:           # the table maps one to one: skip s lands on idx + 1 + s
        if any(pos_index.get(p + 1 + s) != idx + 1 + s for s in range(nb)):
            raise Fallback("branch table does not map one to one")
    return code, vstack[0], depth_max


def encode_row(ci, prims, n_programs: int):
    """The register form of a ci row -> (int64 rc, offset of the loads), or None.

    ``rc``: [offset of the instructions, n_loads, then per program: first
    instruction, count, output register, 1 = register form / 0 = stack form],
    the instructions (WIDTH ints each: kind, destination, operands), the loads
    (kind 0 sense / 1 constant, index, register).  Registers: the stack slots
    0..STACK_CAP-1 of cstate (the loads above the deepest slot any tree uses),
    then the controller slots."""
    progs, depth = [], 0
    for k in range(n_programs):
        try:
            code, out, d = translate(ci, k, prims)
            progs.append((code, out))
            depth = max(depth, d)
        except Fallback:
            progs.append(None)
    base = max(depth, int(ci[1]))
    loads: dict = {}
    for pr in progs:
        if pr is None:
            continue
        for d in [d for ins in pr[0] for d in ins[1:]] + [pr[1]]:
            if d[0] in ("s", "c") and d not in loads:
                loads[d] = base + len(loads)
    if base + len(loads) > STACK_CAP:
        return None

    def reg(d):
        kind, i = d
        if kind in ("s", "c"):
            return loads[d]
        return STACK_CAP + i if kind == "f" else i      # slot, pc: as they are
    P = len(prims)
    head, body = [0, len(loads)], []
    for pr in progs:
        if pr is None:
            head += [0, 0, 0, 0]
            continue
        code, out = pr
        head += [len(body) // WIDTH, len(code), reg(out), 1]
        for ins in code:
            kind = ins[0]
            if kind[0] == "prim":
                row = [kind[1]] + [reg(d) for d in ins[1:]]
            elif kind[0] == "move":
                row = [2 * P + 1] + [reg(d) for d in ins[1:]]
            elif kind[0] == "sel":
                row = [P + kind[1], 0] + [reg(d) for d in ins[1:]]
            else:
                row = [2 * P, 0] + [reg(d) for d in ins[1:]]
            body += (row + [0] * WIDTH)[:WIDTH]
    head[0] = len(head)
    lo = len(head) + len(body)
    tail = [x for (kind, i), r in loads.items() for x in (0 if kind == "s" else 1, i, r)]
    return np.asarray(head + body + tail, dtype=np.int64), lo


def kernel_source(prims) -> str:
    """The register interpreter for ``prims`` (with the stack one's primitives and clamp)."""
    from gpmotion.gp.interpreter import primitive_module_source
    P = len(prims)
    arms = []
    for j, p in enumerate(prims):
        args = ", ".join(f"R[rc[i0 + {2 + a}]]" for a in range(p.arity))
        arms.append(f"        elif kind == {j}:  # {p.name}\n"
                    f"            R[rc[i0 + 1]] = _clamp({p.copy_name}({args}))\n"
                    f"            pc += 1\n")
        if p.conditional:
            call = [""] * p.arity
            for s, pos in enumerate(p.select):
                call[pos] = f"R[rc[i0 + {2 + s}]]"
            for s, pos in enumerate(p.branches):
                call[pos] = f"{float(s)!r}"
            nb = len(p.branches)
            valid = "".join(f" or r == {float(s)!r}" for s in range(1, nb))
            arms.append(f"        elif kind == {P + j}:  # select {p.name}\n"
                        f"            r = {p.copy_name}({', '.join(call)})\n"
                        f"            if not (r == 0.0{valid}):\n"
                        f"                return 0.0\n"
                        f"            jj = int(r)\n"
                        f"            pc += 1 + ({nb - 1} if jj == 0 else jj - 1)\n")
    arms.append(f"        elif kind == {2 * P}:  # jump\n"
                f"            pc = rc[i0 + 2]\n"
                f"        else:  # move\n"
                f"            R[rc[i0 + 1]] = R[rc[i0 + 2]]\n"
                f"            pc += 1\n")
    body = "".join(arms).replace("        elif", "        if", 1)
    return primitive_module_source(prims) + f'''

@njit(**JIT)
def run_program(rc, first, count, out, R):
    base = rc[0] + {WIDTH} * first
    pc = 0
    while pc < count:
        i0 = base + {WIDTH} * pc
        kind = rc[i0]
{body}    return R[out]


@njit(**JIT)
def run_loads(rc, lo, senses, cf, R):
    for i in range(rc[1]):
        kind, idx, r = rc[lo + 3 * i], rc[lo + 3 * i + 1], rc[lo + 3 * i + 2]
        R[r] = _clamp(senses[idx]) if kind == 0 else cf[idx]
'''


def main(argv=None) -> int:
    import random

    from deap import gp

    from gpmotion.bench import bench_gp_trees
    from gpmotion.cache import digest, import_file, write_module
    from gpmotion.gp.bytecode import tree_to_tokens
    from gpmotion.gp.interpreter import interpreter_source, load_interpreter

    from kernel_profile import workload

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--figure", choices=("lamp", "herman"), default="lamp")
    p.add_argument("--episodes", type=int, default=4)
    p.add_argument("--repeats", type=int, default=31)
    p.add_argument("--population", type=int, default=0)
    p.add_argument("--cheap-trig", action="store_true",
                   help="both forms with sin and cos replaced by a multiplication (timing only: "
                        "what the interpretation costs without the trigonometry)")
    a = p.parse_args(argv)
    import gpmotion
    fig, scene, ctrl, n_steps, q0, qd0, dt = workload("lamp_gp" if a.figure == "lamp" else "herman",
                                                      a.episodes)
    tr = gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,
                          record_every=1, record_senses=True, threads=1)
    senses = np.ascontiguousarray(tr.senses.reshape(-1, tr.senses.shape[-1]))
    task, fam, trees = bench_gp_trees(0, figure=a.figure)
    inds = [trees]
    if a.population:
        saved = random.getstate()
        random.seed(1)
        inds += [[tree_to_tokens(gp.PrimitiveTree(gp.genHalfAndHalf(fam.pset, 2, 6)))
                  for _ in fam.actuators] for _ in range(a.population)]
        random.setstate(saved)
        senses = senses[:: max(1, len(inds) // 2)]
    batch = fam.encode(inds)
    prims = fam.info.primitives
    cheap = (lambda t: t.replace("return math.cos(a)", "return a * 0.5")
             .replace("return math.sin(a)", "return a * 0.25")) if a.cheap_trig else (lambda t: t)
    if a.cheap_trig:
        src = cheap(interpreter_source(fam.info))
        stack_k = import_file(write_module(f"gp_cheaptrig_{digest(src)}", src))
    else:
        stack_k = load_interpreter(fam.info)
    src = cheap(kernel_source(prims))
    reg_k = import_file(write_module(f"gpreg_{digest(src)}", src))
    rows = []
    for i in range(len(inds)):
        ci = np.ascontiguousarray(batch.ci[i])
        enc = encode_row(ci, prims, int(ci[0]))
        rows.append((ci, np.ascontiguousarray(batch.cf[i]), enc))

    @njit(cache=False)
    def drive_stack(run_tree, ci, cf, n, senses, cstate, out):
        for s in range(senses.shape[0]):
            for k in range(n):
                out[s, k] = run_tree(ci, cf, k, senses[s], cstate)

    @njit(cache=False)
    def drive_reg(run_tree, run_program, run_loads, ci, cf, rc, lo, n, senses, cstate, out):
        for s in range(senses.shape[0]):
            sv = senses[s]
            run_loads(rc, lo, sv, cf, cstate)
            for k in range(n):
                h = 2 + 4 * k
                if rc[h + 3] == 1:
                    out[s, k] = run_program(rc, rc[h], rc[h + 1], rc[h + 2], cstate)
                else:
                    out[s, k] = run_tree(ci, cf, k, sv, cstate)

    n_ops = n_ins = fallbacks = 0
    for ci, cf, enc in rows:
        n = int(ci[0])
        n_ops += sum(int(ci[HEADER + 3 * k + 2]) for k in range(n))
        if enc is not None:
            rc = enc[0]
            n_ins += sum(int(rc[2 + 4 * k + 1]) if rc[2 + 4 * k + 3] else int(ci[HEADER + 3 * k + 2])
                         for k in range(n))
            fallbacks += sum(int(rc[2 + 4 * k + 3] == 0) for k in range(n))
        else:
            fallbacks += n
    cst = np.zeros(batch.cstate_size)
    outs = {}
    times = {"stack": [], "register": []}

    def run(form, store):
        t0 = time.perf_counter()
        for i, (ci, cf, enc) in enumerate(rows):
            n = int(ci[0])
            out = outs.setdefault((form, i), np.zeros((len(senses), n)))
            if form == "stack" or enc is None:
                drive_stack(stack_k.run_tree, ci, cf, n, senses, cst, out)
            else:
                drive_reg(stack_k.run_tree, reg_k.run_program, reg_k.run_loads, ci, cf, enc[0],
                          enc[1], n, senses, cst, out)
        if store:
            times[form].append((time.perf_counter() - t0) / len(senses) / len(rows) * 1e9)
    run("stack", False)
    run("register", False)
    same = all(np.array_equal(outs[("stack", i)].view(np.int64), outs[("register", i)].view(np.int64))
               for i in range(len(rows)))
    for _ in range(a.repeats):
        run("stack", True)
        run("register", True)
    print(f"{a.figure}: {len(rows)} individuals, {len(senses)} sense vectors; ops per control step "
          f"(static) {n_ops / len(rows):.1f} -> instructions {n_ins / len(rows):.1f}; "
          f"{fallbacks} trees kept the stack form; outputs bit for bit the same: {same}")
    for f, v in times.items():
        print(f"  {f:9s} ns per control step: median {statistics.median(v):7.1f} "
              f"({min(v):7.1f}-{max(v):7.1f}), best {min(v):7.1f}")
    r = [s / g for s, g in zip(times["stack"], times["register"])]
    print(f"  stack/register per repeat: median {statistics.median(r):.3f} ({min(r):.3f}-{max(r):.3f}); "
          f"bests {min(times['stack']) / min(times['register']):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
