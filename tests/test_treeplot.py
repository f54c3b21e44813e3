"""gpmotion.treeplot: pictures of GP trees (token lists) — graph, layout, PNG."""
import pytest
from PIL import Image

from gpmotion import treeplot

TREES = [
    ["add", "t", 0.123456],
    ["iflte", "angle_shoulder", -0.5, "sin", "t", "mul", "rate_elbow", 2.0],
    ["div", "sub", "com_z", 1.0, "abs", "cos", "force_head_tip"],
    ["t"],
]


@pytest.mark.parametrize("tokens", TREES)
def test_graph_has_a_node_per_token_and_an_edge_per_child(tokens):
    g = treeplot.tree_graph(tokens)
    assert g.number_of_nodes() == len(tokens)
    assert g.number_of_edges() == len(tokens) - 1
    assert [d for _, d in g.in_degree()].count(0) == 1          # one root
    pos = treeplot.tidy_layout(g)
    assert set(pos) == set(g)
    for parent, child in g.edges:                                # parents above children
        assert pos[parent][1] == pos[child][1] + 1


def test_labels_are_symbols_senses_and_3_digit_constants():
    g = treeplot.tree_graph(["div", "mul", "t", 3.14159, "abs", "px"])
    labels = [g.nodes[n]["label"] for n in sorted(g)]
    assert labels == ["%", "*", "t", "3.14", "|x|", "px"]
    assert [g.nodes[n]["kind"] for n in sorted(g)][:3] == ["primitive", "primitive", "sense"]


def test_tidy_layout_centres_parents_and_spaces_leaves():
    g = treeplot.tree_graph(["add", "mul", "t", "px", "sin", "vx"])
    pos = treeplot.tidy_layout(g)
    leaves = sorted(pos[n][0] for n in g if g.out_degree(n) == 0)
    assert leaves == [0.0, 1.0, 2.0]
    assert pos[1][0] == 0.5                                      # mul over t, px
    assert pos[0][0] == (0.5 + 2.0) / 2                          # add over mul, sin


def test_plot_writes_a_png(tmp_path):
    out = tmp_path / "trees.png"
    treeplot.plot_trees(out, TREES[:3], titles=["shoulder", "elbow", "neck"], suptitle="best")
    with Image.open(out) as im:
        im.verify()
    with Image.open(out) as im:
        w, h = im.size
        assert w >= 300 and h >= 100
        lo, hi = im.convert("L").getextrema()
        assert hi - lo > 100                                     # not blank
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]   # no temp left


def _big_tree(depth):
    """A full binary tree of add nodes: 2**(depth+1) - 1 tokens."""
    if depth == 0:
        return ["t"]
    return ["add", *_big_tree(depth - 1), *_big_tree(depth - 1)]


def test_large_trees_are_cut_and_still_render(tmp_path):
    big = _big_tree(8)                                           # 511 tokens, depth 8
    assert len(big) == 511
    cut = treeplot.tree_graph(big, max_depth=3)
    assert cut.number_of_nodes() == 15
    hidden = [d["hidden"] for _, d in cut.nodes(data=True) if d["kind"] == "ellipsis"]
    assert len(hidden) == 8 and sum(hidden) == 511 - 7
    out = tmp_path / "big.png"
    treeplot.plot_trees(out, [big, TREES[0]], titles=["big", "small"])
    with Image.open(out) as im:
        assert im.size[0] > 300
    whole = tmp_path / "whole.png"                               # uncut: small, but renders
    treeplot.plot_trees(whole, [big], max_nodes=10_000)
    assert whole.stat().st_size > 1000


@pytest.mark.parametrize("tokens", [
    [], "add t t", ["add", "t"], ["add", "t", "t", "t"], ["sin", None], ["add", "t", float("nan")],
    ["add", "t", True], ["not a name"], 42,
])
def test_malformed_token_lists_raise_value_error(tokens, tmp_path):
    with pytest.raises(ValueError):
        treeplot.tree_graph(tokens)
    out = tmp_path / "bad.png"
    with pytest.raises(ValueError):
        treeplot.plot_trees(out, [["t"], tokens])
    assert not out.exists()


def test_bad_titles_and_empty_input(tmp_path):
    with pytest.raises(ValueError, match="titles"):
        treeplot.plot_trees(tmp_path / "x.png", [["t"]], titles=["a", "b"])
    with pytest.raises(ValueError):
        treeplot.plot_trees(tmp_path / "x.png", [])


def test_existing_file_untouched_on_error(tmp_path):
    out = tmp_path / "trees.png"
    out.write_bytes(b"old")
    with pytest.raises(ValueError):
        treeplot.plot_trees(out, [["add", "t"]])
    assert out.read_bytes() == b"old"
