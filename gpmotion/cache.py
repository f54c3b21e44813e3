"""The cache folder for generated, numba-cached kernel modules.

numba caches only functions that live in a source file, so code we generate
(GP interpreters, rollout kernels) is written to a file whose name carries a
hash of everything it depends on, then imported from there.  A warm start
finds the file and numba's on-disk cache beside it: no recompilation.
"""
from __future__ import annotations

import ast
import hashlib
import importlib.util
import os
import sys
from pathlib import Path


def cache_dir() -> Path:
    """``$GPMOTION_CACHE`` or ``~/.cache/gpmotion``, created on demand."""
    root = os.environ.get("GPMOTION_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "gpmotion")
    path = Path(root) / "kernels"
    path.mkdir(parents=True, exist_ok=True)
    return path


def digest(*parts: str | bytes) -> str:
    """Short stable hash of strings/bytes (file contents, versions, names)."""
    h = hashlib.sha256()
    for p in parts:
        h.update(p.encode() if isinstance(p, str) else p)
        h.update(b"\0")
    return h.hexdigest()[:16]


def file_digest(*paths: str | Path) -> str:
    return digest(*(Path(p).read_bytes() for p in paths))


def write_module(stem: str, source: str) -> Path:
    """Write ``source`` to ``<cache>/<stem>.py`` atomically unless present."""
    path = cache_dir() / f"{stem}.py"
    if not path.exists() or path.read_text() != source:
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(source)
        os.replace(tmp, path)
    return path


def import_file(path: str | Path):
    """Import a module from a file path (once per process).

    A module of the gpmotion package itself (a BSR kernel) is imported under
    its package name: numba's on-disk cache beside the file records the
    module name, and an entry written under a second name cannot be loaded
    by a process that imported the module normally (ModuleNotFoundError).
    The old alias stays registered, so entries an older version wrote load.
    """
    path = Path(path)
    name = "gpmotion_cache_" + path.stem
    package = Path(__file__).resolve().parent
    if package in path.resolve().parents:
        rel = path.resolve().relative_to(package.parent).with_suffix("")
        module = importlib.import_module(".".join(rel.parts))
        sys.modules.setdefault(name, module)
        return module
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def read_source(path: Path) -> bytes:
    """A module's source as hashed into kernel keys (one place, so tests can patch it)."""
    return Path(path).read_bytes()


def package_modules(source: str, package: str = "", root: str = "gpmotion") -> dict[str, Path]:
    """The modules of package ``root`` that ``source`` imports, directly or through
    each other: {module name: file}.  Every import statement counts, also one
    inside a function; a package's ``__init__`` counts when something is taken
    from it (``from pkg import name``, name not a submodule), not when it is
    only passed through (``from pkg import submodule``, ``pkg.sub``).

    ``package``: the package ``source`` belongs to (for its relative imports).
    Kernel keys hash these files, so a helper moved or edited anywhere along
    the chain gives a new kernel, never a stale one.
    """
    found: dict[str, Path] = {}
    todo = [(source, package)]
    while todo:
        src, pkg = todo.pop()
        for base, names in _imports(src, pkg):
            if not (base == root or base.startswith(root + ".")):
                continue
            missing = [n for n in names if not _add(f"{base}.{n}", found, todo)]
            if missing or not names:
                _add(base, found, todo)
    return found


def _add(name: str, found: dict, todo: list) -> bool:
    """Record module ``name`` (and queue its source); False when it is no module file."""
    if name in found:
        return True
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, AttributeError, ValueError):    # an attribute of a module
        return False
    if spec is None or not spec.has_location or not str(spec.origin).endswith(".py"):
        return False
    found[name] = Path(spec.origin)
    is_pkg = spec.submodule_search_locations is not None
    todo.append((found[name].read_text(), name if is_pkg else name.rpartition(".")[0]))
    return True


def _imports(source: str, package: str):
    """(module, names taken from it) of every import statement in ``source``."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            yield from ((a.name, []) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            yield base, [a.name for a in node.names]
