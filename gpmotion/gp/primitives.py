"""Registry of GP primitives: one small plugin file declares each one.

Why a registry: the GP interpreter is *generated* from whatever is registered
(see :mod:`gpmotion.gp.interpreter`), so adding a primitive is one file in
``primitives/`` (or in a user's ``--plugins DIR``) and no edit to a kernel.

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
"""
from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import keyword
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from gpmotion.cache import digest

CLAMP = 1e6  # magnitude cap of every interpreter value (documented above)


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

    @property
    def copy_name(self) -> str:
        return f"prim_{self.name}"


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


def register(name: str, func: Callable, arity: int, symbol: str | None = None) -> Primitive:
    """Register ``func`` as primitive ``name``; a duplicate from another file is an error."""
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
    prim = Primitive(name, arity, symbol or name, func, source, imports, file)
    _REGISTRY[name] = prim
    return prim


def primitive(name: str, arity: int, symbol: str | None = None):
    """Decorator form of :func:`register`; returns the function unchanged."""
    def deco(func):
        prim = register(name, func, arity, symbol)
        func.__gpmotion_primitive__ = prim
        return func
    return deco


def unregister(name: str) -> None:
    """Remove a primitive (tests and interactive sessions)."""
    _REGISTRY.pop(name, None)


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


def load_builtin() -> None:
    """Import every module of the installed ``gpmotion.primitives`` package."""
    import pkgutil
    package = importlib.import_module(_BUILTIN_PACKAGE)
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
        if not info.name.startswith("_"):
            importlib.import_module(f"{_BUILTIN_PACKAGE}.{info.name}")


def load_plugins(folder: str | Path) -> list[str]:
    """Import every ``*.py`` file in ``folder``; return names newly registered."""
    folder = Path(folder).resolve()
    if not folder.is_dir():
        raise ValueError(f"plugin folder not found: {folder}")
    before = set(_REGISTRY)
    builtin = importlib.import_module(_BUILTIN_PACKAGE)
    if any(Path(p).resolve() == folder for p in builtin.__path__):
        load_builtin()
    else:
        tag = digest(str(folder))
        for path in sorted(folder.glob("*.py")):
            if path.name.startswith("_"):
                continue
            modname = f"gpmotion_plugin_{tag}_{path.stem}"
            if modname in sys.modules:
                continue
            spec = importlib.util.spec_from_file_location(modname, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[modname] = module
            try:
                spec.loader.exec_module(module)
            except Exception:
                del sys.modules[modname]
                raise
    return sorted(set(_REGISTRY) - before)
