"""Where compiled code lives: the user's cache folder, never the package.

Two kinds of files go there.  numba's on-disk cache of every ``cache=True``
kernel (``configure_numba``, called as the package is imported, before any
kernel is compiled): left to itself numba writes ``__pycache__/*.nbi`` beside
the installed sources, and a later ``pip install -e`` that removes the
package leaves that folder behind as a namespace package that shadows the
new install.  And the code we generate (GP interpreters, rollout kernels):
numba caches only functions that live in a source file, so it is written to
a file whose name carries a hash of everything it depends on, then imported
from there.  A warm start finds both: no recompilation.

The folder is ``$GPMOTION_CACHE`` or the user cache directory
(``~/.cache/gpmotion`` on Linux), then ``<gpmotion version>/<cpu key>``: the
CPU numba compiles for (its name and features) and the versions of what is
compiled in (numba, numpy, Python), so machines sharing a home folder and
successive installs never load each other's machine code.  ``NUMBA_CACHE_DIR``,
when set, still decides where numba's own cache goes.
"""
from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import importlib.util
import os
import sys
from pathlib import Path

CACHE_ENV = "GPMOTION_CACHE"


def cache_root() -> Path:
    """``$GPMOTION_CACHE`` or the user cache directory for gpmotion."""
    root = os.environ.get(CACHE_ENV)
    if root:
        return Path(root).expanduser()
    try:
        import platformdirs
    except ImportError:          # a dependency; the XDG default where it is missing
        return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "gpmotion"
    return Path(platformdirs.user_cache_dir("gpmotion", appauthor=False))


@functools.lru_cache(maxsize=None)
def _compile_target() -> tuple[str, str]:
    """(CPU name, CPU features) numba compiles for: its settings, else the host's.

    The host is read from /proc/cpuinfo where there is one (cheap: ``import
    gpmotion`` does this before anything else), else asked of LLVM."""
    name, features = os.environ.get("NUMBA_CPU_NAME"), os.environ.get("NUMBA_CPU_FEATURES")
    if name is not None and features is not None:
        return name, features
    host = _proc_cpuinfo()
    if host is None:
        import llvmlite.binding as llvm
        try:
            host = llvm.get_host_cpu_name(), llvm.get_host_cpu_features().flatten()
        except RuntimeError:           # features unknown on this platform
            host = llvm.get_host_cpu_name(), ""
    return name or host[0], host[1] if features is None else features


def _proc_cpuinfo() -> tuple[str, str] | None:
    """(model name, flags) of the first processor listed in /proc/cpuinfo."""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return None
    fields = {}
    for line in text.split("\n\n")[0].splitlines():
        key, _, value = line.partition(":")
        fields[key.strip()] = value.strip()
    if "flags" not in fields:
        return None
    return fields.get("model name", "cpu"), fields["flags"]


@functools.lru_cache(maxsize=None)
def cpu_key() -> str:
    """``<cpu name>-<hash>``: the machine code's target and the versions compiled in."""
    import platform
    from importlib.metadata import PackageNotFoundError, version
    name, features = _compile_target()
    versions = []
    for dist in ("numba", "llvmlite", "numpy"):
        try:
            versions.append(version(dist))
        except PackageNotFoundError:
            versions.append("")
    safe = "".join(c if c.isalnum() or c in "-." else "_" for c in name.split("@")[0].strip())
    return f"{safe[:40]}-{digest(name, features, platform.python_version(), *versions)[:12]}"


def machine_dir() -> Path:
    """``<root>/<gpmotion version>/<cpu key>``: everything compiled for this install."""
    from .version import __version__
    return cache_root() / __version__ / cpu_key()


def configure_numba() -> None:
    """Point numba's on-disk cache at ``machine_dir()/numba`` unless the user set
    ``NUMBA_CACHE_DIR``.  Called before any kernel module is imported: numba fixes
    a function's cache folder when it is decorated.  The environment carries it
    to worker processes (numba re-reads it there); ``_OURS`` marks a value set
    here, so a child with its own cache root or version sets its own."""
    given = os.environ.get("NUMBA_CACHE_DIR")
    if not given or given == os.environ.get(_OURS):
        given = str(machine_dir() / "numba")
        os.environ["NUMBA_CACHE_DIR"] = os.environ[_OURS] = given
    config = getattr(sys.modules.get("numba"), "config", None)
    if config is not None:                    # numba imported first: its config too
        config.CACHE_DIR = given


_OURS = "GPMOTION_NUMBA_CACHE_DIR"


_COLD: list = []          # listeners told before a kernel compiles for the first time


@contextlib.contextmanager
def on_cold_compile(listener):
    """While in the block, ``listener(path)`` is called before the generated kernel
    module at ``path`` is first imported when numba's cache holds no index for it:
    its compilation is about to take minutes (a run says so)."""
    _COLD.append(listener)
    try:
        yield listener
    finally:
        _COLD.remove(listener)


def numba_indexed(path: str | Path) -> bool:
    """Whether numba's cache has an index (``<module>.<function>-<line>.*.nbi``)
    for a function of the module file at ``path``: compiled here before."""
    root = os.environ.get("NUMBA_CACHE_DIR") or str(machine_dir() / "numba")
    return any(Path(root).glob(f"*/{Path(path).stem}.*.nbi"))


def announce_compile(path: str | Path) -> None:
    """Tell the listeners (:func:`on_cold_compile`) when ``path`` compiles cold."""
    if _COLD and not numba_indexed(path):
        for listener in list(_COLD):
            listener(path)


def cache_dir() -> Path:
    """Generated kernel modules: ``machine_dir()/kernels``, created on demand."""
    path = machine_dir() / "kernels"
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
