"""The import graph of gpmotion: no circles, and no layer imports one above it.

Module-level imports only (an import inside a function runs later, when every
module is loaded, and cannot close a circle at import time).  Layers, lowest
first: ``records`` (safe JSON I/O and the error types) and ``cache`` import
nothing of gpmotion; the simulator (``sim``, ``model``, ``figures``) and the
in-kernel controller protocol (``controllers``: ``ControllerBatch``, the
schedule kernel the episode loop runs by default) know nothing of GP, BSR,
tasks or searches; ``gp`` holds the representation and its operators; the
harness (evaluation, families, searches, runs, the CLI) sits above them.
"""
import ast
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
        for node in ast.parse(path.read_text()).body:          # module level only
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
      "gpmotion.run", "gpmotion.cli", "gpmotion.compose", "gpmotion.records", "gpmotion.toolbox")),
    (("gpmotion.gp",),
     ("gpmotion.families", "gpmotion.search", "gpmotion.evaluation", "gpmotion.evaluators",
      "gpmotion.inprocess", "gpmotion.run", "gpmotion.cli", "gpmotion.records", "gpmotion.toolbox",
      "gpmotion.compose")),
    (("gpmotion.search",), ("gpmotion.run", "gpmotion.cli", "gpmotion.compare", "gpmotion.rundir")),
]


def _in(module: str, group) -> bool:
    return any(module == p or module.startswith(p + ".") for p in group)


@pytest.mark.parametrize("low,high", FORBIDDEN, ids=["leaves", "sim", "gp", "search"])
def test_no_layer_imports_one_above_it(low, high):
    g = import_graph()
    bad = [(a, b) for a, b in g.edges if _in(a, low) and _in(b, high)]
    assert not bad, f"upward imports: {bad}"
