"""DEAP trees -> postfix bytecode arrays, and trees <-> plain-data token lists.

Why bytecode: the rollout kernel runs every tree every simulation step inside
numba; a flat (opcode, operand) stream keeps that loop free of Python.

Layout of one episode's ``ci`` (int64) / ``cf`` (float64)::

    ci[0]            n_trees
    ci[1]            max stack need over the trees (<= STACK_CAP)
    ci[2]            n_flags: subgoal flags (gpmotion.gp.subgoals)
    ci[3]            1 when some tree does not give its joint's target angle
                     (a TargetLaw: rate or pi targets, gpmotion.gp.targets), else 0
    ci[4]            ci[3] == 1: offset in cf of the law block, LAW_WIDTH numbers
                     a tree: [mode code (index in TARGET_MODES), gain, a, b]
    ci[5]            m = n_task_senses (gpmotion.gp.task_senses)
    ci[6 + 3k + 0]   actuator index driven by tree k (-1: task sense k - n)
    ci[6 + 3k + 1]   start offset in ci of tree k's op stream
    ci[6 + 3k + 2]   number of ops of tree k; k < n the trees, then the m
                     task senses' programs (n = n_trees)
    ci[6 + 3(n+m) + 3j]  subgoal j: sense index, test code, index in cf of
                     its threshold
    then ops, two ints each: (opcode, operand)
        opcode 0     push clamp(senses[operand])
        opcode 1     push cf[operand]          (a constant)
        opcode 2     jump: skip the next ``operand`` ops (forward only)
        opcode 3     push controller slot ``operand``: subgoal flag j (0.0
                     or 1.0) in slot j, task sense j in slot MAX_SUBGOALS + j
        opcode 4+k   primitive k of the pset; operand 0: pop all its
                     arguments, push its result; operand 1 (conditionals
                     only): pop its selectors and go to the branch taken
                     through the jump table that follows (``_branch_layout``);
                     operand 2 + i: push clamp(senses[i]) first (a fused
                     pair: its last argument is sense i)

A zero row (padding) has n_trees = 0 and drives nothing.  ``cstate`` is the
interpreter's stack (STACK_CAP slots), MAX_SUBGOALS flag slots,
MAX_TASK_SENSES task-sense slots, then (with a law) the previous step's time, a started flag and one value per tree (rate:
the target; pi: the integral).

Tokens (the genome format, DESIGN "Formats and safety"): a tree is its
prefix list of primitive names, terminal names and numbers (constants).
Parsing checks a whitelist and caps size/depth; it never evaluates text.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from deap import gp

from gpmotion.controllers import ControllerBatch
from gpmotion.gp.interpreter import interpreter_path, load_interpreter
from gpmotion.gp.opcodes import (HEADER, OP_ARG_SENSE0, OP_JUMP,  # noqa: F401 (re-exported)
                                 OP_PRIM0, OP_PUSH_CONST, OP_PUSH_FLAG, OP_PUSH_SENSE, RATE_STATE,
                                 STACK_CAP, TARGET_MODES)
from gpmotion.gp.primitives import clamp
from gpmotion.gp.pset import PsetInfo
from gpmotion.gp.subgoals import MAX_SUBGOALS
from gpmotion.gp.task_senses import MAX_TASK_SENSES

MAX_TREE_SIZE = 512     # token/node cap for parsing genomes
MAX_TREE_DEPTH = 17     # Koza's depth limit


@dataclass(frozen=True)
class TargetLaw:
    """How each tree drives its target (one entry per tree in every field):
    ``modes[k]`` one of TARGET_MODES, with a gain and two numbers a_k, b_k:

    * ``angle``: target_k = tree_k (gain, a, b unused).
    * ``rate``: target_k += dt * gain * tree_k, held within [a_k, b_k] (the
      joint's range, so a target never winds up past a limit); the target
      starts where the caller put it (its joint's neutral angle).
    * ``pi``: target_k = tree_k + I_k with I_k += dt * gain * (tree_k -
      senses[a_k]) (a_k: the joint's angle sense), |I_k| <= b_k: the tree's
      angle reached without the PD servo's sag (a PI servo)."""
    modes: tuple[str, ...]
    gain: tuple[float, ...]
    a: tuple[float, ...]
    b: tuple[float, ...]

    def block(self) -> list[float]:
        """The law block of cf: LAW_WIDTH numbers a tree."""
        codes = [float(list(TARGET_MODES).index(m)) for m in self.modes]
        return [float(v) for row in zip(codes, self.gain, self.a, self.b) for v in row]


def is_erc(node) -> bool:
    return isinstance(node, gp.Terminal) and isinstance(type(node), gp.MetaEphemeral)


def _branch_layout(sel_frags, branch_frags, op):
    """Lazy conditional: selectors, SELECT, a jump table, then the branches.

    ``sel.. (op, 1) J_1 .. J_{n-1} B_0 J_end B_1 J_end .. B_{n-1}``: SELECT
    pops the selectors; for branch 0 it skips the whole table (falling into
    B_0), for branch j > 0 it skips j - 1 entries onto J_j, which jumps to
    B_j.  Each branch but the last then jumps past the others.  So a taken
    branch costs two ops more than itself (SELECT and one jump) and an
    untaken one nothing: never more ops than the eager form.
    """
    n = len(branch_frags)
    lens = [len(b) for b in branch_frags]
    out = [x for f in sel_frags for x in f] + [(op, 1)]
    for k in range(1, n):
        out.append((OP_JUMP, (n - 1 - k) + sum(lens[:k]) + k))
    for j, b in enumerate(branch_frags):
        out += b
        if j < n - 1:
            out.append((OP_JUMP, sum(lens[j + 1:]) + n - 2 - j))
    return out


def compile_tree(tree, info: PsetInfo, lazy: bool = True, fold: bool = False,
                 fuse: bool = True, fast_trig: bool = False
                 ) -> tuple[list[tuple[int, int]], list[float], int]:
    """One tree -> (ops [(opcode, operand)], constants, max stack need).

    ``lazy``: conditional primitives evaluate only the branch taken (jumps);
    otherwise every argument is evaluated (the same value: primitives are pure).
    ``fold``: a subtree that reads no state (constants only) becomes one
    constant, computed by the generated kernel itself (:func:`_fold`), so the
    tree's value is bitwise the one the unfolded ops give.  The stack cap is
    checked on the unfolded need: folding never admits a tree.  Off by
    default: evolved lamp trees hold few constant subtrees (0.5 % of their
    ops, ``benchmarks/gp_op_stats.py``) and no rollout got measurably faster
    (``benchmarks/gp_fold_fuse.py``).  ``fuse``: a
    primitive whose last argument is a sense reads it itself (operand
    OP_ARG_SENSE0 + sense), one op for the pair.  ``fast_trig``: fold with
    the kernel that runs the tree (gpmotion.gp.interpreter).
    """
    in_set = set(info.primitive_names)
    prim_op = {p.name: (OP_PRIM0 + k, p) for k, p in enumerate(info.primitives)
               if p.name in in_set}
    term_sense = dict(zip(info.terminal_names, info.sense_indices))
    nodes = list(tree)
    if not nodes:
        raise ValueError("empty tree")
    # prefix -> postfix: walk nodes right to left; a primitive closes its children.
    # pending: stack of (ops, stack need unfolded, stack need, reads no state);
    # a constant op carries its value for now
    pending: list[tuple[list, int, int, bool]] = []
    for node in reversed(nodes):
        if isinstance(node, gp.Primitive):
            if node.name not in prim_op:
                raise ValueError(f"primitive {node.name!r} is not in this primitive set")
            if len(pending) < node.arity:
                raise ValueError("malformed tree (missing arguments)")
            op, p = prim_op[node.name]
            children = [pending.pop() for _ in range(node.arity)]
            ops, raw, need = _node_ops(op, p, children, lazy, fuse)
            const = all(c[3] for c in children)
            if fold and const and raw <= STACK_CAP:
                ops, need = [(OP_PUSH_CONST, _fold(info, ops, fast_trig))], 1
            pending.append((ops, raw, need, const))
        elif is_erc(node):
            pending.append(([(OP_PUSH_CONST, clamp(float(node.value)))], 1, 1, True))
        elif isinstance(node, gp.Terminal) and node.value in term_sense:
            i = term_sense[node.value]                 # < 0: subgoal flag -1 - i
            pending.append(([(OP_PUSH_SENSE, i) if i >= 0 else (OP_PUSH_FLAG, -1 - i)],
                            1, 1, False))
        else:
            raise ValueError(f"terminal {getattr(node, 'name', node)!r} is not in this primitive set")
    if len(pending) != 1:
        raise ValueError("malformed tree (not exactly one root)")
    frag, raw, need, _ = pending[0]
    if raw > STACK_CAP:
        need = raw
    if need > STACK_CAP:
        raise ValueError(f"tree needs a stack of {need} > {STACK_CAP}; "
                         "lower the depth limit")
    ops: list[tuple[int, int]] = []
    consts: list[float] = []
    for op, arg in frag:
        if op == OP_PUSH_CONST:
            ops.append((op, len(consts)))
            consts.append(arg)
        else:
            ops.append((op, arg))
    return ops, consts, need


def _node_ops(op: int, p, children, lazy: bool, fuse: bool):
    """A primitive over its children's fragments -> (ops, unfolded need, need)."""
    if lazy and p.conditional:
        sel = [children[i] for i in p.select]
        br = [children[i] for i in p.branches]
        ops = _branch_layout([c[0] for c in sel], [c[0] for c in br], op)
        needs = [max(max(i + c[k] for i, c in enumerate(sel)), max(c[k] for c in br))
                 for k in (1, 2)]
    else:
        ops = [x for ch in children for x in ch[0]] + [(op, 0)]
        if fuse and len(children[-1][0]) == 1 and ops[-2][0] == OP_PUSH_SENSE:
            ops[-2:] = [(op, OP_ARG_SENSE0 + ops[-2][1])]
        needs = [max(i + c[k] for i, c in enumerate(children)) for k in (1, 2)]
    return ops, needs[0], needs[1]


def _fold(info: PsetInfo, frag, fast_trig: bool = False) -> float:
    """The value of a fragment that reads no state, from the generated
    kernel's own ``run_tree`` (the same compiled float64 operations, clamp
    and protected primitives as at run time: no second implementation)."""
    consts = [arg for op, arg in frag if op == OP_PUSH_CONST]
    ci, k = [1, 0, 0, 0, 0, 0, -1, HEADER + 3, len(frag)], 0
    for op, arg in frag:
        ci += [op, k if op == OP_PUSH_CONST else arg]
        k += op == OP_PUSH_CONST
    run_tree = _kernel(info, fast_trig).run_tree
    return float(run_tree(np.asarray(ci, dtype=np.int64), np.asarray(consts + [0.0]),
                          0, _NO_SENSES, np.zeros(STACK_CAP)))


_NO_SENSES = np.zeros(1)
_KERNELS: dict = {}


def _kernel(info: PsetInfo, fast_trig: bool = False):
    """The generated interpreter module for ``info``'s primitives (imported once)."""
    key = (tuple(p.source for p in info.primitives), fast_trig)
    if key not in _KERNELS:
        _KERNELS[key] = load_interpreter(info, fast_trig)
    return _KERNELS[key]


def encode_trees(trees: Sequence, info: PsetInfo, actuator_indices: Sequence[int],
                 lazy: bool = True, subgoals: Sequence[tuple[int, int, float]] = (),
                 law: TargetLaw | None = None, task_programs: Sequence = (),
                 fold: bool = False, fuse: bool = True, fast_trig: bool = False):
    """A list of trees (one per actuator) -> (ci int64[:], cf float64[:]).

    ``subgoals``: (sense index, test code, threshold) per subgoal flag of
    ``info`` (:func:`gpmotion.gp.subgoals.subgoal_table`), in its order;
    ``law``: how the trees drive their targets (None: as angles);
    ``task_programs``: (ops, constants, stack need) per task sense of
    ``info`` (:func:`gpmotion.gp.task_senses.compile_formula`), in its order."""
    if len(trees) != len(actuator_indices):
        raise ValueError(f"{len(trees)} trees but {len(actuator_indices)} actuator indices")
    if len(subgoals) != len(info.flag_names):
        raise ValueError(f"{len(subgoals)} subgoal tests for {len(info.flag_names)} subgoal terminals")
    if len(task_programs) != len(info.task_sense_names) or len(task_programs) > MAX_TASK_SENSES:
        raise ValueError(f"{len(task_programs)} task sense programs for "
                         f"{len(info.task_sense_names)} task senses")
    n = len(trees)
    compiled = [_compiled(t, info, lazy, fold, fuse, fast_trig) for t in trees]
    programs = compiled + [tuple(p) for p in task_programs]
    ci = ([n, max((c[2] for c in programs), default=0), len(subgoals), 0, 0, len(task_programs)]
          + [0] * (3 * len(programs)))
    cf: list[float] = []
    if law is not None:
        if not len(law.modes) == len(law.gain) == len(law.a) == len(law.b) == n:
            raise ValueError(f"target law: {len(law.modes)} joint entries for {n} trees")
        ci[3:5] = [1, len(cf)]
        cf += law.block()
    for sense, code, threshold in subgoals:
        ci += [int(sense), int(code), len(cf)]
        cf.append(float(threshold))
    acts = list(actuator_indices) + [-1] * len(task_programs)
    for k, ((ops, consts, _), act) in enumerate(zip(programs, acts)):
        ci[HEADER + 3 * k: HEADER + 3 * k + 3] = [int(act), len(ci), len(ops)]
        base = len(cf)
        for op, arg in ops:
            ci += [op, arg + base if op == OP_PUSH_CONST else arg]
        cf += consts
    return np.asarray(ci, dtype=np.int64), np.asarray(cf, dtype=np.float64)


# compile_tree's results by token list: a GP generation re-encodes every
# individual, but crossover and mutation change one tree of an individual
# and reproduction none, so most trees were compiled before (herman: ~1 s of
# Python per generation).  Keyed on the exact tokens (repr keeps -0.0 apart
# from 0.0) and what maps them to opcodes; cleared when it grows large.  A
# DEAP tree is keyed by its tokens too (the lamp's 300 individuals: 70 ms ->
# 20 ms a generation, benchmarks/gp_encode_cache.py).
_COMPILED: dict = {}
_COMPILED_MAX = 100_000


def _compiled(t, info: PsetInfo, lazy: bool, fold: bool = False, fuse: bool = True,
              fast_trig: bool = False):
    fast_trig = fold and fast_trig          # only folding runs the kernel
    is_tree = isinstance(t, gp.PrimitiveTree)
    tokens = tree_to_tokens(t) if is_tree else list(t)
    key = (info.hash, info.sense_indices, lazy, fold, fuse, fast_trig, repr(tokens))
    hit = _COMPILED.get(key)
    if hit is None:
        if len(_COMPILED) >= _COMPILED_MAX:
            _COMPILED.clear()
        tree = t if is_tree else tokens_to_tree(t, info)
        hit = _COMPILED[key] = compile_tree(tree, info, lazy, fold, fuse, fast_trig)
    return hit


def encode_batch(individuals: Sequence[Sequence], info: PsetInfo,
                 actuator_indices: Sequence[int], module: str | None = None,
                 lazy: bool = True, subgoals=(), law: TargetLaw | None = None,
                 task_programs=(), fold: bool = False, fuse: bool = True,
                 fast_trig: bool = False) -> ControllerBatch:
    """Individuals (each a list of trees or token lists) -> a rectangular batch.

    ``module`` defaults to the generated interpreter for ``info`` (with the
    fast sine and cosine when ``fast_trig``); ``lazy`` ``fold`` and ``fuse``
    as in :func:`compile_tree` (the other forms are for benchmarks and
    tests); ``law`` and ``task_programs`` as in :func:`encode_trees`.
    """
    if module is None:
        module = str(interpreter_path(info, fast_trig))
    rows = [encode_trees(ind, info, actuator_indices, lazy, subgoals, law, task_programs, fold,
                         fuse, fast_trig)
            for ind in individuals]
    li = max([len(r[0]) for r in rows] + [HEADER])
    lf = max([len(r[1]) for r in rows] + [1])
    ci = np.zeros((len(rows), li), dtype=np.int64)
    cf = np.zeros((len(rows), lf), dtype=np.float64)
    for i, (a, b) in enumerate(rows):
        ci[i, :len(a)] = a
        cf[i, :len(b)] = b
    n_trees = max([len(ind) for ind in individuals] + [0])
    return ControllerBatch(module=str(module), ci=ci, cf=cf,
                           cstate_size=STACK_CAP + MAX_SUBGOALS + MAX_TASK_SENSES + RATE_STATE
                           + n_trees)


# ---------------------------------------------------------------- tokens

def tree_to_tokens(tree) -> list:
    """Prefix token list: primitive names, terminal names, floats for constants."""
    out = []
    for node in tree:
        if isinstance(node, gp.Primitive):
            out.append(node.name)
        elif is_erc(node):
            out.append(float(node.value))
        else:
            out.append(node.value)
    return out


def tokens_to_tree(tokens, pset, max_size: int = MAX_TREE_SIZE,
                   max_depth: int = MAX_TREE_DEPTH) -> gp.PrimitiveTree:
    """Parse a token list against the pset's whitelist; ValueError on bad input."""
    info = pset if isinstance(pset, PsetInfo) else None
    pset = info.pset if info else pset
    if not isinstance(tokens, (list, tuple)):
        raise ValueError(f"a tree must be a list of tokens, got {type(tokens).__name__}")
    if not tokens:
        raise ValueError("empty token list")
    if len(tokens) > max_size:
        raise ValueError(f"tree has {len(tokens)} tokens > size cap {max_size}")
    prims = {p.name: p for ps in pset.primitives.values() for p in ps}
    args = set(pset.arguments)
    ercs = [t for ts in pset.terminals.values() for t in ts if isinstance(t, gp.MetaEphemeral)]
    nodes = []
    open_slots = [1]         # unfilled argument slots per open level (depth = len - 1)
    for i, tok in enumerate(tokens):
        if not open_slots:
            raise ValueError(f"extra tokens after a complete tree at position {i}: {tok!r}")
        depth = len(open_slots) - 1
        if depth > max_depth:
            raise ValueError(f"tree deeper than depth cap {max_depth}")
        open_slots[-1] -= 1
        if isinstance(tok, str):
            if tok in prims:
                nodes.append(prims[tok])
                open_slots.append(prims[tok].arity)
            elif tok in args:
                nodes.append(pset.mapping[tok])
            else:
                shown = tok if len(tok) <= 40 else tok[:40] + "..."
                raise ValueError(f"unknown token {shown!r} at position {i}; known primitives: "
                                 f"{', '.join(sorted(prims))}; terminals: {', '.join(pset.arguments)}")
        elif isinstance(tok, numbers.Real) and not isinstance(tok, bool):
            if not math.isfinite(tok):
                raise ValueError(f"non-finite constant {tok!r} at position {i}")
            if not ercs:
                raise ValueError("this primitive set has no constants")
            node = ercs[0].__new__(ercs[0])
            node.value = float(tok)
            nodes.append(node)
        else:
            raise ValueError(f"bad token {tok!r} at position {i} (need a name or a number)")
        while open_slots and open_slots[-1] == 0:
            open_slots.pop()
    if open_slots:
        raise ValueError("incomplete tree: a primitive is missing arguments")
    return gp.PrimitiveTree(nodes)
