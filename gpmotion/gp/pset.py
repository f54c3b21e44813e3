"""Build the DEAP primitive set for a task from the primitive registry.

Why the DEAP set's functions are *clamped wrappers*: ``deap.gp.compile(tree,
pset)`` is then an exact Python twin of the njit interpreter (every primitive
result goes through :func:`gpmotion.gp.primitives.clamp`); only the inputs
need the same clamp, which :func:`compile_reference` applies.

Terminals are the pset's arguments renamed to sense names (``px``, ``vx``,
``angle_shoulder``, ``t``...); each maps to an index of the raw sense vector
the rollout passes to ``control``.  Constants are one ephemeral random
constant (ERC), uniform in ``erc_range``, named uniquely per pset so that
rebuilding a pset in one process never collides in DEAP.
"""
from __future__ import annotations

import functools
import random
from dataclasses import dataclass
from typing import Callable, Sequence

from deap import gp

from gpmotion.cache import digest
from gpmotion.gp import primitives as registry
from gpmotion.gp.subgoals import MAX_SUBGOALS


@dataclass(frozen=True)
class PsetInfo:
    """A DEAP primitive set plus what bytecode and interpreter need to agree on."""
    pset: gp.PrimitiveSet
    primitive_names: tuple[str, ...]   # the function set (what trees are built from)
    terminal_names: tuple[str, ...]    # pset arguments, in order (senses, subgoal flags,
    #                                    task senses)
    sense_indices: tuple[int, ...]     # terminal k reads senses[i], i = sense_indices[k];
    #                                    i < 0: controller slot -1 - i (subgoal flag j
    #                                    in slot j, task sense j in MAX_SUBGOALS + j)
    erc_name: str
    erc_range: tuple[float, float]
    hash: str                          # primitive names + sources + terminals
    flag_names: tuple[str, ...] = ()   # subgoal terminals (after the senses)
    task_sense_names: tuple[str, ...] = ()   # task senses (the last ones; gp.task_senses)
    # what the kernel dispatches: opcode OP_PRIM0 + k <-> opcode_names[k] (the installed
    # primitives, then the set's others: one kernel for every set drawn from them)
    opcode_names: tuple[str, ...] = ()

    @property
    def primitives(self) -> list[registry.Primitive]:
        """The kernel's primitives, in opcode order (a superset of the function set)."""
        return [registry.get(n) for n in self.opcode_names or self.primitive_names]

    @property
    def function_set(self) -> list[registry.Primitive]:
        """The primitives trees are built from, in the set's order."""
        return [registry.get(n) for n in self.primitive_names]


def _clamped(func: Callable) -> Callable:
    @functools.wraps(func)
    def wrapper(*args):
        return registry.clamp(func(*args))
    return wrapper


_ERC_FUNCS: dict[str, Callable] = {}   # one function object per ERC name (DEAP checks identity)


def pset_hash(primitive_names: Sequence[str], terminal_names: Sequence[str],
              sense_indices: Sequence[int] = (), erc_range=(-1.0, 1.0)) -> str:
    prims = [registry.get(n) for n in primitive_names]
    return digest(*(f"{p.name}/{p.arity}\n{p.source}" for p in prims), "|",
                  *terminal_names, "|", *map(str, sense_indices), "|",
                  repr(tuple(map(float, erc_range))))


def build_pset(terminal_names: Sequence[str], primitive_names: Sequence[str] | None = None,
               *, sense_names: Sequence[str] | None = None,
               erc_range: tuple[float, float] = (-1.0, 1.0), name: str = "MAIN",
               flag_names: Sequence[str] = (), task_sense_names: Sequence[str] = ()) -> PsetInfo:
    """Primitive set over ``primitive_names`` in that order (opcode order;
    default :data:`gpmotion.gp.primitives.STANDARD`) and terminals.

    ``sense_names`` is the full raw sense vector layout (``Figure.sense_names``);
    when omitted, terminal k reads ``senses[k]``.  ``flag_names``: subgoal
    terminals appended after the senses (gpmotion.gp.subgoals);
    ``task_sense_names``: task senses after them (gpmotion.gp.task_senses).
    """
    registry.load_builtin()
    prim_names = tuple(registry.STANDARD if primitive_names is None else primitive_names)
    for n in prim_names:
        registry.get(n)                       # clear error for unknown names
    if len(set(prim_names)) != len(prim_names):
        raise ValueError(f"repeated primitive names in {prim_names}")
    flags = tuple(flag_names) + tuple(task_sense_names)      # the controller's slots
    terms = tuple(terminal_names) + flags
    if len(terms) == len(flags):
        raise ValueError("a primitive set needs at least one terminal (sense) name")
    for t in terms:
        if not t.isidentifier() or t in prim_names or t.startswith("ERC_"):
            raise ValueError(f"bad terminal name {t!r} (identifier, not a primitive name)")
    if len(set(terms)) != len(terms):
        raise ValueError(f"repeated terminal names in {terms}")
    if sense_names is None:
        idx = tuple(range(len(terms) - len(flags)))
    else:
        sense_names = list(sense_names)
        missing = [t for t in terms[:len(terms) - len(flags)] if t not in sense_names]
        if missing:
            raise ValueError(f"terminals {missing} are not senses of this figure "
                             f"(senses: {', '.join(sense_names)})")
        idx = tuple(sense_names.index(t) for t in terms[:len(terms) - len(flags)])
    idx += tuple(-1 - j for j in range(len(flag_names)))
    idx += tuple(-1 - MAX_SUBGOALS - j for j in range(len(task_sense_names)))
    lo, hi = float(erc_range[0]), float(erc_range[1])
    h = pset_hash(prim_names, terms, idx, (lo, hi))

    pset = gp.PrimitiveSet(name, len(terms))
    for n in prim_names:
        p = registry.get(n)
        pset.addPrimitive(_clamped(p.func), p.arity, name=p.name)
    erc_name = f"ERC_{h}"
    func = _ERC_FUNCS.setdefault(erc_name, functools.partial(random.uniform, lo, hi))
    pset.addEphemeralConstant(erc_name, func)
    pset.renameArguments(**{f"ARG{i}": t for i, t in enumerate(terms)})
    builtin = registry.builtin_names()
    opcodes = builtin + tuple(n for n in prim_names if n not in builtin)
    return PsetInfo(pset, prim_names, terms, idx, erc_name, (lo, hi), h, tuple(flag_names),
                    tuple(task_sense_names), opcodes)


def compile_reference(tree, info: PsetInfo) -> Callable:
    """``deap.gp.compile`` with the interpreter's semantics: f(senses, flags=(),
    task_values=()) -> float (``flags``: the subgoal flags' values,
    ``task_values`` the task senses'; missing ones read 0.0)."""
    f = gp.compile(tree, info.pset)
    idx = info.sense_indices

    def run(senses, flags=(), task_values=()):
        slots = [0.0] * (MAX_SUBGOALS + len(info.task_sense_names))
        slots[:len(flags)] = map(float, flags)
        slots[MAX_SUBGOALS:MAX_SUBGOALS + len(task_values)] = map(float, task_values)
        return registry.clamp(f(*(registry.clamp(senses[i]) if i >= 0 else slots[-1 - i]
                                  for i in idx)))
    return run
