"""Registry of GP primitives: one small plugin file declares each one.

Why a registry: the GP interpreter is *generated* from the primitives a
primitive set names (see :mod:`gpmotion.gp.interpreter`), so adding a
primitive is one file in ``primitives/`` (or in a user's ``--plugins DIR``)
and no edit to a kernel.  Registering a primitive puts it in no set: a task
names its set (``Task.primitives``, default :data:`STANDARD`) and a run may
name another (``--primitives``), so a new primitive changes no existing run.

A primitive is pure scalar, numba-compatible code declared at module level::

    from gpmotion.gp.primitives import primitive

    @primitive("add", arity=2, symbol="+")
    def add(a, b):
        return a + b

The interpreter *copies the function's source text* into its own module, so
a primitive may use builtins and names the plugin file imports at module
level (``import math``); other module globals are not copied.
:func:`gpmotion.check.check_primitive` compiles exactly that copy, so a
primitive that breaks the rule fails the check with a clear message.

Numeric semantics (shared by the interpreter, the DEAP primitive set and the
plain reference): every value on the interpreter's stack is finite and lies
in ``[-CLAMP, CLAMP]`` -- each sense pushed and each primitive result passes
through :func:`clamp` (NaN -> 0.0, otherwise saturate to +-1e6).

Conditionals: a primitive declares ``select`` -- which of its arguments
choose (``select=2``: the first two; or a tuple of positions) -- and must
return one of its other (branch) arguments *unchanged*, picked by the
selectors alone::

    @primitive("iflte", arity=4, select=2)
    def iflte(a, b, c, d):
        return c if a <= b else d

The interpreter then evaluates only the branch taken (jumps over the
others in the bytecode), so an untaken branch costs nothing.  It finds the
branch by calling the function with the branch arguments replaced by their
indices 0.0, 1.0, ...; :func:`register` checks the selector rule on sample
values.
"""
from __future__ import annotations

import ast
import importlib
import inspect
import keyword
import math
import textwrap
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

CLAMP = 1e6  # magnitude cap of every interpreter value (documented above)

# The standard GP function set, in opcode order: every shipped primitive but
# the paper's ``ifpos`` (sorted, as the default set was when it was "every
# registered primitive", so runs recorded then replay and resume unchanged).
STANDARD = ("abs", "add", "cos", "div", "iflte", "mul", "sin", "sub")


def clamp(v: float) -> float:
    """The interpreter's value rule in plain Python: NaN -> 0, else saturate."""
    v = float(v)
    if v != v:
        return 0.0
    return min(max(v, -CLAMP), CLAMP)


@dataclass(frozen=True)
class Primitive:
    """One registered primitive; ``source`` is the text the interpreter copies."""
    name: str
    arity: int
    symbol: str
    func: Callable
    source: str          # decorator-free, renamed copy: ``def prim_<name>(...)``
    imports: str         # module-level import lines of the plugin file
    file: str
    select: tuple[int, ...] = ()   # selector argument positions; () = not a conditional

    @property
    def copy_name(self) -> str:
        return f"prim_{self.name}"

    @property
    def conditional(self) -> bool:
        return bool(self.select)

    @property
    def branches(self) -> tuple[int, ...]:
        """Argument positions of the branches (a conditional evaluates one)."""
        return tuple(i for i in range(self.arity) if i not in self.select) if self.select else ()


_REGISTRY: dict[str, Primitive] = {}
MAX_ARITY = 4
_BUILTIN_PACKAGE = "gpmotion.primitives"


def _copy_source(name: str, func: Callable) -> tuple[str, str]:
    """Return (renamed decorator-free def source, module-level import lines)."""
    try:
        text = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError) as exc:
        raise ValueError(f"primitive {name!r}: source text unavailable ({exc}); "
                         "define it with 'def' in a .py file") from exc
    tree = ast.parse(text)
    defs = [n for n in tree.body if isinstance(n, ast.FunctionDef)]
    if not defs:
        raise ValueError(f"primitive {name!r}: must be a plain 'def' function")
    fn = defs[0]
    fn.decorator_list = []
    fn.name = f"prim_{name}"
    imports = []
    try:
        mod_tree = ast.parse(Path(inspect.getsourcefile(func)).read_text())
        for node in mod_tree.body:
            if isinstance(node, ast.Import) and not any(
                    a.name.split(".")[0] == "gpmotion" for a in node.names):
                imports.append(ast.unparse(node))
            elif (isinstance(node, ast.ImportFrom) and node.level == 0
                  and (node.module or "").split(".")[0] not in ("gpmotion", "__future__")):
                imports.append(ast.unparse(node))
    except (OSError, TypeError, SyntaxError):
        pass
    return ast.unparse(fn) + "\n", "\n".join(imports)


def _select_positions(name: str, select, arity: int) -> tuple[int, ...]:
    """``select`` (None, a leading count or positions) -> sorted positions."""
    if select is None:
        return ()
    if isinstance(select, bool):
        raise ValueError(f"primitive {name!r}: select must be a count or positions, got {select!r}")
    pos = tuple(range(select)) if isinstance(select, int) else tuple(select)
    if (not pos or not all(isinstance(i, int) and not isinstance(i, bool) for i in pos)
            or len(set(pos)) != len(pos) or not all(0 <= i < arity for i in pos)
            or len(pos) >= arity):
        raise ValueError(f"primitive {name!r}: select must name 1..{arity - 1} distinct argument "
                         f"positions in 0..{arity - 1} (the rest are branches), got {select!r}")
    return tuple(sorted(pos))


# selector samples: ties, signs, zero, the clamp
_SELECT_SAMPLES = (0.0, 1.0, -1.0, 0.5, -0.5, 1e-9, 2.0, 1e6, -1e6)


def branch_index(prim: Primitive, selectors) -> float:
    """What the interpreter computes: the function with branch k replaced by k."""
    args = [0.0] * prim.arity
    for i, v in zip(prim.select, selectors):
        args[i] = float(v)
    for k, i in enumerate(prim.branches):
        args[i] = float(k)
    return prim.func(*args)


def _check_selector(prim: Primitive) -> None:
    """A conditional returns one branch argument unchanged, chosen by its selectors."""
    import itertools
    m = len(prim.select)
    samples = _SELECT_SAMPLES if m <= 2 else _SELECT_SAMPLES[:4]
    for sel in itertools.product(samples, repeat=m):
        k = branch_index(prim, sel)
        ok = (isinstance(k, (int, float)) and math.isfinite(k) and k == int(k)
              and 0 <= k < len(prim.branches))
        if ok:
            args = [0.0] * prim.arity
            for i, v in zip(prim.select, sel):
                args[i] = v
            values = [3.25 + 7.5 * j for j in range(len(prim.branches))]
            for i, v in zip(prim.branches, values):
                args[i] = v
            ok = prim.func(*args) == values[int(k)]
        if not ok:
            raise ValueError(f"conditional primitive {prim.name!r}: with selectors {sel} it does not "
                             "return one of its branch arguments unchanged, chosen by the selectors "
                             f"alone (select={prim.select})")


def register(name: str, func: Callable, arity: int, symbol: str | None = None, *,
             select=None, default=None) -> Primitive:
    """Register ``func`` as primitive ``name``; a duplicate from another file is an error.

    ``select``: see the module doc (conditionals).  ``default`` is deprecated
    and has no effect: no primitive joins a set by being registered."""
    if default is not None:
        warnings.warn(f"primitive {name!r}: default= is deprecated and has no effect (a task "
                      "names its primitive set: Task.primitives)", DeprecationWarning, stacklevel=3)
    if not (isinstance(name, str) and name.isidentifier() and not keyword.iskeyword(name)):
        raise ValueError(f"primitive name {name!r} must be a Python identifier")
    if not isinstance(arity, int) or not 1 <= arity <= MAX_ARITY:
        raise ValueError(f"primitive {name!r}: arity must be an int in 1..{MAX_ARITY}, got {arity!r} "
                         "(the interpreter's stack holds depth-17 trees of at most 4-argument nodes)")
    file = str(Path(inspect.getsourcefile(func) or "<unknown>").resolve())
    old = _REGISTRY.get(name)
    if old is not None:
        if old.file == file:          # same file imported again: keep the first
            return old
        raise ValueError(f"duplicate primitive {name!r}: defined in {old.file} "
                         f"and in {file}")
    source, imports = _copy_source(name, func)
    prim = Primitive(name, arity, symbol or name, func, source, imports, file,
                     _select_positions(name, select, arity))
    if prim.conditional:
        _check_selector(prim)
    _REGISTRY[name] = prim
    return prim


def primitive(name: str, arity: int, symbol: str | None = None, *, select=None,
              default=None):
    """Decorator form of :func:`register`; returns the function unchanged."""
    def deco(func):
        prim = register(name, func, arity, symbol, select=select, default=default)
        func.__gpmotion_primitive__ = prim
        return func
    return deco


def get(name: str) -> Primitive:
    try:
        return _REGISTRY[name]
    except KeyError:
        from gpmotion.names import did_you_mean
        raise ValueError(f"unknown primitive {name!r}{did_you_mean(name, names())}; known: "
                         f"{', '.join(names()) or '(none loaded)'} (a plugin's primitives are "
                         "known once its folder is loaded: --plugins DIR, or "
                         "gpmotion.load_plugins(DIR))") from None


def names() -> list[str]:
    """Registered names, sorted (a stable opcode order)."""
    return sorted(_REGISTRY)


def builtin_names() -> tuple[str, ...]:
    """The installed primitives (``gpmotion.primitives``): :data:`STANDARD`'s, in
    its order, then the others sorted.  Every GP kernel dispatches these, whatever
    a task's function set, so tasks and presets drawing on them share one kernel."""
    load_builtin()
    package = Path(importlib.import_module(_BUILTIN_PACKAGE).__file__).resolve().parent
    found = {n for n, p in _REGISTRY.items() if Path(p.file).parent == package}
    return tuple(n for n in STANDARD if n in found) + tuple(sorted(found - set(STANDARD)))


def load_builtin() -> None:
    """Import every module of the installed ``gpmotion.primitives`` package."""
    import pkgutil
    package = importlib.import_module(_BUILTIN_PACKAGE)
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
        if not info.name.startswith("_"):
            importlib.import_module(f"{_BUILTIN_PACKAGE}.{info.name}")
