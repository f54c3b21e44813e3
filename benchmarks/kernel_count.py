"""Which generated kernels a command compiles or loads: the main job, the test suite, anything.

    python benchmarks/kernel_count.py [--log FILE] -- COMMAND [ARG ...]
    python benchmarks/kernel_count.py -- gpmotion run lamp_hop --generations 2
    python benchmarks/kernel_count.py -- python -m pytest -q

Runs COMMAND with a ``sitecustomize`` first on PYTHONPATH that logs every
generated module gpmotion imports from its cache folder (every process the
command starts and that inherits the environment: pytest-xdist workers,
process pools, Dask workers on this machine), then prints the distinct ones
by kind:

* ``rollout``: rollout kernels (:mod:`gpmotion.sim.kernels`), each named by
  its controller module and backend;
* ``gp``: GP interpreters (:mod:`gpmotion.gp.interpreter`), by their
  primitives (a fast-trig form is its own);
* ``prim``: one-primitive modules :func:`gpmotion.check.check_primitive`
  compiles to check a primitive file.

A process started with an environment of its own (a test's fresh virtual
environment, ``env={...}``) is not seen by the log; what any process wrote
to this environment's cache folder is, so the files the command added there
are listed too (on an empty cache, ``GPMOTION_CACHE=$(mktemp -d)``: every
module it compiled).  The package's own numba functions (BSR kernels, the
simulator's steps) are compiled into the rollout kernels that call them and
are not counted apart.  Exit status: the command's.
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

HOOK = '''\
# Written by benchmarks/kernel_count.py: log gpmotion's generated modules as they load.
import importlib.util as _util, os as _os
_spec = _util.spec_from_file_location
def _logged(name, location=None, *args, **kwargs):
    if str(name).startswith("gpmotion_cache_") and _os.environ.get("GPMOTION_KERNEL_LOG"):
        with open(_os.environ["GPMOTION_KERNEL_LOG"], "a") as f:
            f.write(str(location) + "\\n")
    return _spec(name, location, *args, **kwargs)
_util.spec_from_file_location = _logged
'''


def describe(path: Path) -> tuple[str, str]:
    """(kind, what it is) of one generated module file."""
    kind = path.name.split("_")[0]
    text = path.read_text() if path.exists() else ""
    if kind == "rollout":
        # the controller: a file by path (a generated GP interpreter), or a package module by name
        ctrl = re.search(r"import_file\('([^']+)'\)", text)
        by_name = re.search(r"^import gpmotion\.[\w.]*?(\w+) as _controller$", text, re.M)
        backend = re.search(r"from gpmotion\.sim\.(\w+) import JIT", text)
        name = Path(ctrl.group(1)).name if ctrl else f"{by_name.group(1)}.py" if by_name else "?"
        if ctrl and name.startswith("gp_"):
            name = "GP interpreter (" + describe(Path(ctrl.group(1)))[1] + ")"
        return kind, f"{name} on {backend.group(1) if backend else '?'}"
    if kind == "gp":
        return kind, _primitives(path) + (" [fast trig]" if "_ft_sin" in text else "")
    return kind, path.name


def _primitives(path: Path) -> str:
    m = re.search(r"^primitives: (.*)$", path.read_text(), re.M) if path.exists() else None
    return m.group(1) if m else "?"


def summary(log: Path) -> str:
    # by file name (a hash of the source): a copy in another cache folder (a test's
    # own, e.g. run with numba's JIT off) is the same kernel
    found = {Path(line).name: Path(line) for line in log.read_text().split()} if log.exists() else {}
    return listing("generated modules loaded", [found[name] for name in sorted(found)])


def listing(title: str, paths: list[Path]) -> str:
    kinds = Counter()
    lines = []
    for p in paths:
        kind, what = describe(p)
        kinds[kind] += 1
        lines.append(f"  {kind:8} {what}")
    head = ", ".join(f"{kinds[k]} {k}" for k in ("rollout", "gp", "prim") if kinds[k]) or "none"
    return "\n".join([f"{title}: {head}"] + sorted(lines))


def cache_files() -> set[Path]:
    """The generated modules in this environment's cache folder."""
    from gpmotion.cache import machine_dir
    folder = machine_dir() / "kernels"
    return set(folder.glob("*.py")) if folder.is_dir() else set()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log", type=Path, help="keep the log of module paths here")
    ap.add_argument("command", nargs=argparse.REMAINDER, help="-- COMMAND [ARG ...]")
    args = ap.parse_args(argv)
    cmd = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not cmd:
        ap.error("give the command after --")
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "sitecustomize.py").write_text(HOOK)
        log = args.log or Path(tmp, "kernels.log")
        log.unlink(missing_ok=True)
        env = dict(os.environ, GPMOTION_KERNEL_LOG=str(log.resolve()),
                   PYTHONPATH=os.pathsep.join(filter(None, [tmp, os.environ.get("PYTHONPATH")])))
        before = cache_files()
        rc = subprocess.call(cmd, env=env)
        print(summary(log))
        print(listing("added to the cache folder", sorted(cache_files() - before)))
    return rc


if __name__ == "__main__":
    sys.exit(main())
