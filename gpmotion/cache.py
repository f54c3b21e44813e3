"""The cache folder for generated, numba-cached kernel modules.

numba caches only functions that live in a source file, so code we generate
(GP interpreters, rollout kernels) is written to a file whose name carries a
hash of everything it depends on, then imported from there.  A warm start
finds the file and numba's on-disk cache beside it: no recompilation.
"""
from __future__ import annotations

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
