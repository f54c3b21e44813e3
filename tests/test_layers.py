"""The import graph of gpmotion: no circles, and no layer imports one above it.

Every import counts, the ones inside functions too: a deferred import still
ties the lower module to the upper one, so a circle or an upward edge made of
function-level imports is as much a layering fault as a module-level one.
Layers, lowest first: ``records`` (safe JSON I/O and the error types) and ``cache`` import
nothing of gpmotion; the simulator (``sim``, ``model``, ``figures``) and the
in-kernel controller protocol (``controllers``: ``ControllerBatch``, the
schedule kernel the episode loop runs by default) know nothing of GP, BSR,
tasks or searches; ``gp`` holds the representation and its operators; the
harness (evaluation, families, searches, robust starts) sits above them, then
runs, composites and studies, and the command line (``gpmotion.cli``) on top:
no module outside it sees an argparse namespace or imports it.
"""
import ast
import importlib
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

import gpmotion

ROOT = Path(gpmotion.__file__).resolve().parent


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(node: ast.ImportFrom, module: str, is_pkg: bool) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".") if is_pkg else module.split(".")[:-1]
    base = base[:len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _known(name: str, modules: set) -> str | None:
    """The gpmotion module ``name`` names, or its nearest enclosing one."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def import_graph() -> nx.DiGraph:
    files = {_module_name(p): p for p in ROOT.rglob("*.py")}
    modules = set(files)
    g = nx.DiGraph()
    g.add_nodes_from(modules)
    for mod, path in files.items():
        is_pkg = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text())):     # every import, nested too
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(node, mod, is_pkg)
                targets = [f"{base}.{a.name}" for a in node.names]
            for t in targets:
                dep = _known(t, modules)
                if dep and dep != mod and not mod.startswith(dep + "."):   # a package's own parent
                    g.add_edge(mod, dep)
    return g


def _package_inits(g):
    """Edges into a package __init__ that only re-exports are not layering: drop them."""
    return g.subgraph(n for n in g if n != "gpmotion")


def test_the_scan_sees_real_edges():
    g = import_graph()
    assert g.has_edge("gpmotion.sim.backend", "gpmotion.sim.backend_3d")
    assert g.has_edge("gpmotion.figures.spec", "gpmotion.figures.specparse")
    assert g.has_edge("gpmotion.inprocess", "gpmotion.robust")        # inside a function


def test_no_import_circles():
    g = _package_inits(import_graph())
    cycles = list(nx.simple_cycles(g))
    assert not cycles, f"import circles: {cycles[:5]}"


# a module of the left group never imports one of the right group at module level
FORBIDDEN = [
    (("gpmotion.records", "gpmotion.cache"), ("gpmotion",)),
    (("gpmotion.sim", "gpmotion.model", "gpmotion.figures", "gpmotion.controllers"),
     ("gpmotion.gp", "gpmotion.bsr", "gpmotion.task", "gpmotion.families",
      "gpmotion.search", "gpmotion.evaluation", "gpmotion.evaluators", "gpmotion.inprocess",
      "gpmotion.run", "gpmotion.cli", "gpmotion.compose", "gpmotion.toolbox")),
    (("gpmotion.gp",),
     ("gpmotion.families", "gpmotion.search", "gpmotion.evaluation", "gpmotion.evaluators",
      "gpmotion.inprocess", "gpmotion.run", "gpmotion.cli", "gpmotion.records", "gpmotion.toolbox",
      "gpmotion.compose")),
    (("gpmotion.search",), ("gpmotion.run", "gpmotion.cli", "gpmotion.compare", "gpmotion.rundir")),
    # a task is what a motion should achieve; what a family reads from it is the family's
    (("gpmotion.task",), ("gpmotion.gp", "gpmotion.bsr", "gpmotion.families", "gpmotion.search")),
    (("gpmotion.evaluation", "gpmotion.evaluators", "gpmotion.inprocess", "gpmotion.robust",
      "gpmotion.toolbox", "gpmotion.families", "gpmotion.task"),
     ("gpmotion.run", "gpmotion.cli", "gpmotion.compose", "gpmotion.compare", "gpmotion.study")),
    (("gpmotion.run", "gpmotion.compose", "gpmotion.study", "gpmotion.compare", "gpmotion.report"),
     ("gpmotion.cli",)),
]


# modules with no gpmotion imports of their own, which any layer may use
LEAVES = ("gpmotion.version",)

# the command line's own modules, and the `python -m` entry points that call it
CLI_ENTRY = ("gpmotion.cli", "gpmotion.__main__", "gpmotion.compose.__main__")


def _in(module: str, group) -> bool:
    return any(module == p or module.startswith(p + ".") for p in group)


@pytest.mark.parametrize("low,high", FORBIDDEN, ids=["leaves", "sim", "gp", "search", "task", "evaluation",
                                                    "harness"])
def test_no_layer_imports_one_above_it(low, high):
    g = import_graph()
    bad = [(a, b) for a, b in g.edges
           if _in(a, low) and _in(b, high) and a not in CLI_ENTRY and b not in LEAVES]
    assert not bad, f"upward imports: {bad}"



def test_only_the_entry_points_import_the_command_line():
    g = import_graph()
    bad = [(a, b) for a, b in g.edges if _in(b, ("gpmotion.cli",)) and not _in(a, CLI_ENTRY)]
    assert not bad, f"modules importing the CLI: {bad}"


def test_importing_the_simulator_loads_no_harness():
    """`import gpmotion` resolves its public names lazily: the simulator alone
    imports neither the harness, DEAP, Dask nor the CLI."""
    code = ("import sys, gpmotion, gpmotion.sim.rollout, gpmotion.figures\n"
            "heavy = ('deap', 'distributed', 'matplotlib', 'gpmotion.cli', 'gpmotion.run',\n"
            "         'gpmotion.search', 'gpmotion.families', 'gpmotion.evaluators')\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in heavy or m in heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout


def test_public_names_resolve():
    for name in gpmotion.__all__:
        assert getattr(gpmotion, name) is not None, name
    importlib.import_module("gpmotion.run")             # importing the module keeps the function
    assert callable(gpmotion.run) and gpmotion.run.__module__ == "gpmotion.run"
