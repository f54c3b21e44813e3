"""Pictures of evolved GP trees: one panel per tree (per joint), drawn top-down.

Trees are *token lists* (the genome format of ``best.json``): prefix order of
primitive names, terminal (sense) names and numbers (constants).  A token's
arity comes from the primitive registry (``gpmotion.gp.primitives.get(name)
.arity``); a sense name or a number has arity 0.  Parsing is structural: a
string that is not a registered primitive is taken as a sense name (it must
be an identifier); a list that is empty, has leftover tokens after a complete
tree, misses arguments, or holds anything but strings and finite real
numbers is a ``ValueError``.

Layout (no graphviz): a tidy top-down tree — leaves evenly spaced left to
right in prefix order, each parent centred over its first and last child,
one row per depth.  Labels: primitive symbols (``+ - * %``, ``iflte``,
``sin``, ``|x|``…, from ``Primitive.symbol``), sense names, constants to 3
significant digits.

Large trees: a tree of more than ``max_nodes`` (default 120) tokens is cut
at depth ``max_depth`` (default 8; the root is depth 0) — or shallower, the
deepest cut that leaves at most ``max_nodes`` nodes drawn: each subtree rooted
at the cut depth becomes one grey ``…`` node labelled with the number of
tokens it hides (``…12``), and the panel title says "shown of total, cut below
depth d".  Panel widths follow the number of leaves; font and node size shrink
with it (down to 4 pt); leaf labels are rotated under their nodes, so long
sense names do not collide.  Trees of hundreds of nodes still render whole
when ``max_nodes`` is raised, just small.

Uses matplotlib's object API on an Agg canvas (no pyplot state, no screen)
and writes through :func:`gpmotion.records.atomic_output`: a crash never
leaves a half-written picture.
"""
from __future__ import annotations

import math
import numbers
from typing import Sequence

import networkx as nx
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from gpmotion.gp import primitives as registry
from gpmotion.records import atomic_output

MAX_NODES = 120           # trees above this many nodes are cut below MAX_DEPTH
MAX_DEPTH = 8
ELLIPSIS = "…"
KIND_COLOURS = {"primitive": "#9ecae1", "sense": "#a1d99b", "const": "#fdd0a2",
                "ellipsis": "#d9d9d9"}


def _parse(tokens) -> list[tuple[str, str, int]]:
    """Token list -> [(kind, label, arity)] in prefix order; ValueError when malformed."""
    if isinstance(tokens, (str, bytes)) or not isinstance(tokens, Sequence):
        raise ValueError(f"a tree must be a list of tokens, got {type(tokens).__name__}")
    if len(tokens) == 0:
        raise ValueError("empty token list")
    registry.load_builtin()
    known = set(registry.names())
    out = []
    open_slots = 1
    for i, tok in enumerate(tokens):
        if open_slots == 0:
            raise ValueError(f"extra tokens after a complete tree at position {i}: {tok!r}")
        if isinstance(tok, str):
            if tok in known:
                p = registry.get(tok)
                out.append(("primitive", p.symbol, p.arity))
            elif tok.isidentifier():
                out.append(("sense", tok, 0))
            else:
                shown = tok if len(tok) <= 40 else tok[:40] + "..."
                raise ValueError(f"bad token {shown!r} at position {i} "
                                 "(not a primitive, not a sense name)")
        elif isinstance(tok, numbers.Real) and not isinstance(tok, bool):
            if not math.isfinite(tok):
                raise ValueError(f"non-finite constant {tok!r} at position {i}")
            out.append(("const", f"{float(tok):.3g}", 0))
        else:
            raise ValueError(f"bad token {tok!r} at position {i} (need a name or a number)")
        open_slots += out[-1][2] - 1
    if open_slots:
        raise ValueError(f"incomplete tree: {open_slots} argument(s) missing")
    return out


def tree_graph(tokens, max_depth: int | None = None) -> nx.DiGraph:
    """A ``networkx.DiGraph`` of one tree: node i is token i (prefix order), edges parent→child.

    Node attributes: ``label``, ``kind`` (primitive, sense, const, ellipsis),
    ``depth``; edge attribute ``order`` (argument position).  Without
    ``max_depth`` the graph has one node per token and ``len(tokens) − 1``
    edges.  With ``max_depth`` every subtree rooted at that depth becomes one
    ``ellipsis`` node (attribute ``hidden``: how many tokens it stands for)
    and deeper tokens are left out.
    """
    parsed = _parse(tokens)
    n = len(parsed)
    parent, depth, order = [-1] * n, [0] * n, [0] * n
    stack: list[list[int]] = []           # [token index, arguments still to come]
    for i, (_, _, arity) in enumerate(parsed):
        if stack:
            top = stack[-1]
            parent[i], depth[i] = top[0], depth[top[0]] + 1
            order[i] = parsed[top[0]][2] - top[1]
            top[1] -= 1
            if top[1] == 0:
                stack.pop()
        if arity:
            stack.append([i, arity])
    size = [1] * n
    for i in range(n - 1, 0, -1):
        size[parent[i]] += size[i]
    g = nx.DiGraph()
    for i, (kind, label, arity) in enumerate(parsed):
        if max_depth is not None and depth[i] > max_depth:
            continue
        if max_depth is not None and depth[i] == max_depth and arity:
            g.add_node(i, label=f"{ELLIPSIS}{size[i]}", kind="ellipsis", depth=depth[i],
                       hidden=size[i])
        else:
            g.add_node(i, label=label, kind=kind, depth=depth[i])
        if parent[i] >= 0:
            g.add_edge(parent[i], i, order=order[i])
    return g


def tidy_layout(g: nx.DiGraph, root: int = 0) -> dict[int, tuple[float, float]]:
    """Top-down positions: leaves at x = 0, 1, 2… in order, parents centred over children.

    y = −depth.  Children are taken in their ``order`` (argument position).
    """
    pos: dict[int, tuple[float, float]] = {}
    next_leaf = 0.0
    # iterative post-order: a parent is placed after all its children
    todo = [(root, 0, False)]
    while todo:
        node, depth, done = todo.pop()
        kids = sorted(g.successors(node), key=lambda c: g.edges[node, c]["order"])
        if not kids:
            pos[node] = (next_leaf, -float(depth))
            next_leaf += 1.0
        elif done:
            pos[node] = (0.5 * (pos[kids[0]][0] + pos[kids[-1]][0]), -float(depth))
        else:
            todo.append((node, depth, True))
            todo.extend((c, depth + 1, False) for c in reversed(kids))
    return pos


def _cut_depth(tokens, n_tokens: int, max_nodes: int, max_depth: int) -> int | None:
    """None when the tree is drawn whole; else the depth below which it is cut."""
    if n_tokens <= max_nodes:
        return None
    d = max_depth
    while d > 1 and tree_graph(tokens, d).number_of_nodes() > max_nodes:
        d -= 1
    return d


def plot_trees(path, trees, titles: Sequence[str] | None = None, *, suptitle: str | None = None,
               max_nodes: int = MAX_NODES, max_depth: int = MAX_DEPTH, dpi: int = 100) -> None:
    """Draw token-list ``trees`` (one panel each, ``titles`` e.g. joint names) to a PNG at ``path``.

    Trees above ``max_nodes`` nodes are cut (see the module doc).  Raises
    ValueError on a malformed tree or mismatched titles; the file at ``path``
    is replaced atomically, or left untouched on error.
    """
    if isinstance(trees, (str, bytes)) or not isinstance(trees, Sequence) or not trees:
        raise ValueError("plot_trees needs a non-empty list of trees (token lists)")
    trees = list(trees)
    titles = [f"tree {k}" for k in range(len(trees))] if titles is None else [str(t) for t in titles]
    if len(titles) != len(trees):
        raise ValueError(f"{len(titles)} titles for {len(trees)} trees")
    if max_depth < 1 or max_nodes < 1:
        raise ValueError("max_depth and max_nodes must be >= 1")
    panels = []
    for k, tokens in enumerate(trees):
        try:
            n_tokens = len(_parse(tokens))
        except ValueError as exc:
            raise ValueError(f"tree {k} ({titles[k]}): {exc}") from None
        cut = _cut_depth(tokens, n_tokens, max_nodes, max_depth)
        g = tree_graph(tokens, cut)
        leaves = [n for n in g if g.out_degree(n) == 0]
        depth = max(d for _, d in g.nodes(data="depth"))
        panels.append(dict(g=g, n_tokens=n_tokens, cut=cut, leaves=leaves, depth=depth,
                           title=titles[k]))

    ncols = min(len(panels), 3)
    nrows = math.ceil(len(panels) / ncols)
    col_leaves = [max([max(3, len(panels[k]["leaves"])) for k in range(c, len(panels), ncols)])
                  for c in range(ncols)]
    width = min(40.0, max(6.0, 0.3 * sum(col_leaves) + 0.8 * ncols))
    per_leaf_pt = min(width * 72.0 * c / sum(col_leaves) / max(c, 1) for c in col_leaves)
    font = max(4.0, min(9.0, 0.55 * per_leaf_pt))
    node_d = max(5.0, min(26.0, 0.8 * per_leaf_pt))            # node diameter, points
    row_in = 0.55                                               # inches per depth level
    longest = max(len(str(p["g"].nodes[n]["label"])) for p in panels for n in p["leaves"])
    label_in = 0.62 * font * longest / 72.0 + 0.15              # rotated leaf labels below
    depth_max = max(p["depth"] for p in panels)
    row_h = row_in * (depth_max + 1) + label_in + 0.5
    height = min(40.0, nrows * row_h + (0.4 if suptitle else 0.0))
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(nrows, ncols, width_ratios=col_leaves)
    for k, pnl in enumerate(panels):
        g = pnl["g"]
        ax = fig.add_subplot(grid[k // ncols, k % ncols])
        pos = tidy_layout(g)
        leaf_set = set(pnl["leaves"])
        inner = {n: d["label"] for n, d in g.nodes(data=True) if n not in leaf_set}
        colours = [KIND_COLOURS[d["kind"]] for _, d in g.nodes(data=True)]
        nx.draw_networkx(g, pos, ax=ax, labels=inner, node_color=colours,
                         node_size=node_d ** 2, font_size=font, arrows=False,
                         edge_color="#888888", width=0.8)
        drop = 0.5 * node_d / 72.0 / row_in + 0.05              # half a node, in depth units
        for n in pnl["leaves"]:                                 # leaf labels: rotated, below
            x, y = pos[n]
            ax.text(x, y - drop, g.nodes[n]["label"], rotation=90, ha="center", va="top",
                    fontsize=font)
        shown, total = g.number_of_nodes(), pnl["n_tokens"]
        note = (f"{total} nodes" if pnl["cut"] is None else
                f"{shown} of {total} nodes, cut below depth {pnl['cut']}")
        ax.set_title(f"{pnl['title']}  ({note})", fontsize=10)
        ax.set_axis_off()
        xs = [q[0] for q in pos.values()]
        ax.set_xlim(min(xs) - 0.7, max(xs) + 0.7)
        ax.set_ylim(-depth_max - drop - label_in / row_in, 0.5)
    if suptitle:
        fig.suptitle(suptitle)
    fig.tight_layout()
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)
