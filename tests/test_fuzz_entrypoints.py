"""Generated bad input over every entry point, with a fixed seed.

Each case is a command line (options of run, resume, replay, render, export,
robustness, compose, compare, study) over a file that is mangled: a run's
config.json, checkpoint.json, log.csv, best.json; a composite, a compose
script, a figure TOML, a study spec; or a FIFO or a directory in its place.
A case is refused with one ``gpmotion: error:`` line and exit code 2 (0
tracebacks, 0 wrongly accepted), leaves every byte that was on disk as it was,
and finishes under a timeout (0 hangs).  The few mutations that leave the input
valid are accepted, and say why (``_VALID``).

The cases call ``gpmotion.cli.main`` in this process (an alarm is the
timeout); a fixed sample of them also runs as ``python -m gpmotion`` in a
process of its own, the real entry point.  The named tests first are the bugs
the generated cases found, each a focused case of its own.
"""
import argparse
import contextlib
import io
import json
import os
import random
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from gpmotion.cli import main
from tests.cli_checks import one_line_error
from tests.test_composite import write_controller
from tests.test_rundir_layer import hashes, no_hang

SEED = 20261205
TIMEOUT_S = 60
GP = ["--param", "seconds=0.3", "--population", "8", "--quiet", "--no-artifacts"]
WEIRD = [-1, 0, 1_000_000_000, 1e308, -0.5, "bogus", "", "../../x", None, True, [], {},
         [1, 2], {"a": 1}, "x" * 5000, "\u0000", 2**70]
SCRIPT = ("phase one = dcm_x * (dtime ~= 0.5)\nphase two = max_t(cm_z)\n"
          "total = (1 + one) * (1 + two)\n")
STUDY = Path(__file__).parents[1] / "gpmotion" / "studies" / "gp-vs-bsr" / "spec.toml"
STAGED = STUDY.parents[1] / "creatures" / "spec.toml"      # rex-sequence: walk, turn, walk2


def _compose_argv(world, out, *extra):
    return ["compose", world / "good.motion", "--controllers", world / "a.json",
            world / "b.json", "--rounds", "1", "--arrays", "2", "--mutations", "1",
            "--no-artifacts", "--quiet", "--out", out, *extra]


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz")
    run = d / "run"
    assert main(["run", "lamp_hop", *GP, "--generations", "4", "--out", str(run)]) == 0
    write_controller(d / "a.json")
    write_controller(d / "b.json", family="bsr-time", seed=1)
    (d / "good.motion").write_text(SCRIPT)
    assert main([str(a) for a in _compose_argv(d, d / "comp")]) == 0
    shutil.copy(STUDY, d / "study.toml")
    shutil.copy(STAGED, d / "staged.toml")
    return d


def _copy(src: Path, tmp: Path) -> Path:
    dst = tmp / src.name
    shutil.copytree(src, dst)
    return dst


def _edit_json(path: Path, change) -> None:
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def _resume_refused(run: Path, capsys, *needles):
    before = hashes(run)
    with no_hang(TIMEOUT_S):
        assert main(["resume", str(run), "--quiet"]) == 2
    one_line_error(capsys, *needles)
    assert hashes(run) == before


# ------------------------------------------------------------------ found by the cases

def test_a_figure_root_that_is_not_a_table_is_one_line(capsys, tmp_path):
    f = tmp_path / "v.toml"
    f.write_text('extends = "lamp"\nroot = 5\n')
    assert main(["run", "lamp_hop", *GP, "--figure", str(f), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "root")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("key,value", [("actuation", {}), ("actuation", "bogus"),
                                       ("options", 0), ("options", []), ("params", [])])
def test_a_best_json_with_a_falsy_or_foreign_value_is_refused(world, tmp_path, capsys,
                                                               key, value):
    """0, [] or {} once read as "absent" (the default actuation, no options)."""
    best = tmp_path / "best.json"
    shutil.copy(world / "run" / "best.json", best)
    _edit_json(best, lambda d: d.__setitem__(key, value))
    assert main(["replay", str(best)]) == 2
    one_line_error(capsys, key)


def test_a_best_json_without_actuation_replays_with_the_default(world, tmp_path):
    best = tmp_path / "best.json"
    shutil.copy(world / "run" / "best.json", best)
    _edit_json(best, lambda d: d.__setitem__("actuation", None))
    assert main(["replay", str(best)]) == 0


def test_a_checkpoint_with_an_unknown_key_is_refused(world, tmp_path, capsys):
    run = _copy(world / "run", tmp_path)
    _edit_json(run / "checkpoint.json", lambda d: d.__setitem__("unknown_1", 1))
    _resume_refused(run, capsys, "unknown_1")


@pytest.mark.parametrize("where", ["search", "search.parents", "search.best",
                                   "search.generation_best[0]", "search.history[-1]",
                                   "search.final_best"])
def test_an_unknown_key_nested_in_the_search_state_is_refused(world, tmp_path, capsys, where):
    """A GP search state is checked at every level, not only the checkpoint's top."""
    run = _copy(world / "run", tmp_path)

    def plant(doc):
        node = doc
        for part in where.replace("[", ".").replace("]", "").split("."):
            node = node[int(part)] if part.lstrip("-").isdigit() else node[part]
        assert isinstance(node, dict)
        node["nested_bogus"] = 1
    _edit_json(run / "checkpoint.json", plant)
    _resume_refused(run, capsys, "nested_bogus", where.split("[")[0])


@pytest.mark.parametrize("change,needle", [
    (lambda d: d["run"]["family_options"].__setitem__("bogus", 1), "bogus"),
    (lambda d: d.__setitem__("bogus_top", 1), "bogus_top")])
def test_a_config_with_an_unknown_key_is_refused_before_any_checkpoint(world, tmp_path, capsys,
                                                                        change, needle):
    """With no checkpoint no digest binds config.json: its own keys must be checked."""
    run = _copy(world / "run", tmp_path)
    (run / "checkpoint.json").unlink()
    (run / "best.json").unlink()
    _edit_json(run / "config.json", change)
    _resume_refused(run, capsys, needle)


@pytest.mark.parametrize("where", ["parents", "best"])
def test_a_checkpoint_with_a_mangled_phase_is_refused(world, tmp_path, capsys, where):
    run = _copy(world / "run", tmp_path)
    _edit_json(run / "checkpoint.json", lambda d: d["search"][where].__setitem__("phase", {}))
    _resume_refused(run, capsys, f"{where}.phase")


@pytest.mark.parametrize("row", [1, 3])
def test_a_mangled_log_row_before_the_checkpoint_is_refused(world, tmp_path, capsys, row):
    run = _copy(world / "run", tmp_path)
    lines = (run / "log.csv").read_text().splitlines(keepends=True)
    lines[row] = "9,9,9\n"
    (run / "log.csv").write_text("".join(lines))
    _resume_refused(run, capsys, "log.csv", f"row {row}")


def test_a_log_row_going_back_is_refused(world, tmp_path, capsys):
    run = _copy(world / "run", tmp_path)
    lines = (run / "log.csv").read_text().splitlines(keepends=True)
    lines[1], lines[2] = lines[2], lines[1]
    (run / "log.csv").write_text("".join(lines))
    _resume_refused(run, capsys, "log.csv", "goes back")


@pytest.mark.parametrize("change,needle", [
    (lambda d: d.__setitem__("unknown_1", 1), "unknown_1"),
    (lambda d: d["search"].__setitem__("best", -0.5), "best"),
    (lambda d: d["search"].__setitem__("best", [0.1, 0.2, 0.3]), "best")])
def test_a_mangled_compose_checkpoint_is_refused(world, tmp_path, capsys, change, needle):
    comp = _copy(world / "comp", tmp_path)
    _edit_json(comp / "checkpoint.json", change)
    before = hashes(comp)
    assert main([str(a) for a in _compose_argv(world, comp, "--resume")]) == 2
    one_line_error(capsys, needle)
    assert hashes(comp) == before


# ------------------------------------------------------------------ studies

def _study(tmp_path, old, new) -> Path:
    text = STUDY.read_text()
    assert old in text
    (tmp_path / "s.toml").write_text(text.replace(old, new, 1))
    return tmp_path / "s.toml"


@pytest.mark.parametrize("old,new,needle", [
    ('family = "gp"', 'family = "gp"\nfigure = "bogus:starman"', "bogus:starman"),
    ('family = "gp"', 'family = "gp"\nfigure = 3', "figure"),
    ('family = "gp"', 'family = "gp"\nfigure = { extends = "lamp", name = "v", root = 5 }',
     "root"),
    ('family = "gp"', 'family = "gp"\nfigure = { extends = "nope", name = "v" }', "nope"),
    ('family = "gp"', 'family = "gp"\noptions = { bogus = 1 }', "bogus"),
    ('family = "bsr-time"', 'family = "bsr-time"\noptions = { population = 8 }', "population"),
    ('name = "gp-vs-bsr"', 'name = "../../../escape"', "study.name"),
    ('name = "gp-vs-bsr"', 'name = "a/b"', "study.name"),
    ('[configurations.gp]', '[configurations."../x"]', "configurations"),
    ('budget = 3000', 'budget = -1', "budget"),          # checked under --quick's budget too
    ('budget = 3000', 'budget = 1000000000000', "budget"),
])
def test_a_bad_study_spec_is_one_line_and_writes_nothing(tmp_path, capsys, old, new, needle):
    s = _study(tmp_path, old, new)
    with no_hang(TIMEOUT_S):
        assert main(["study", "run", str(s), "--out", str(tmp_path / "o"), "--quick",
                     "--quiet"]) == 2
    one_line_error(capsys, needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


# references in a spec: a figure variant's ``extends`` (a registered figure) and a
# task's ``after`` (earlier stages; a spec chains them with stages, never by name)
_GP_CONF, _TURN = 'family = "gp"\n', 'name = "turn"\n'
REF_EDITS = [
    ("study", _GP_CONF, 'figure = { extends = "v", name = "v" }', "extends"),     # itself
    ("study", _GP_CONF, 'figure = { extends = "lamp", name = "lamp" }', "own"),   # its base's name
    ("study", _GP_CONF, 'figure = { extends = "starman", name = "lamp" }', "own"),
    ("study", _GP_CONF, 'figure = { extends = "", name = "v" }', "extends"),
    ("study", _GP_CONF, 'figure = { extends = "../lamp", name = "v" }', "extends"),
    ("study", _GP_CONF, 'figure = { extends = "gpmotion/figures/lamp.toml", name = "v" }',
     "extends"),
    ("study", _GP_CONF, 'figure = { extends = "starman_damped", name = "v" }', "extends"),
    ("study", _GP_CONF, 'figure = { extends = ["lamp"], name = "v" }', "extends"),
    ("study", _GP_CONF, 'figure = { extends = "lamp", name = "v", bodies = { extends = "v" } }',
     "bodies"),
    ("study", _GP_CONF, 'params = { after = "x.json" }', "after"),
    ("staged", _TURN, 'params = { after = "turn" }', "after"),                   # itself
    ("staged", _TURN, 'params = { after = "walk2" }', "after"),                  # a later stage
    ("staged", _TURN, 'params = { after = "turn.json,walk.json" }', "after"),
    ("staged", _TURN, 'after = "walk"', "after"),
    ("staged", 'name = "walk2"\n', 'name = "walk"', "two stages"),
]


def _ref_spec(world, tmp: Path, which: str, anchor: str, edit: str) -> Path:
    text = (world / f"{which}.toml").read_text()
    assert anchor in text
    new = edit + "\n" if edit.startswith("name =") else anchor + edit + "\n"  # a rename
    (tmp / "s.toml").write_text(text.replace(anchor, new, 1))
    return tmp / "s.toml"


@pytest.mark.parametrize("which,anchor,edit,needle", REF_EDITS,
                         ids=[f"{i}-{w}" for i, (w, *_) in enumerate(REF_EDITS)])
def test_a_bad_reference_in_a_study_spec_is_one_line_and_writes_nothing(
        world, tmp_path, capsys, which, anchor, edit, needle):
    s = _ref_spec(world, tmp_path, which, anchor, edit)
    with no_hang(TIMEOUT_S):
        assert main(["study", "run", str(s), "--out", str(tmp_path / "o"), "--quick",
                     "--quiet"]) == 2
    one_line_error(capsys, needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_figures_extending_each_other_in_a_loop_are_one_line(world, tmp_path, capsys,
                                                             monkeypatch):
    """A loop can only come from registered figures (a plugin's); the spec's variant
    that starts from one is refused, naming the loop."""
    from gpmotion import figures
    monkeypatch.setitem(figures._REGISTRY, "loop_a", {"extends": "loop_b", "name": "loop_a"})
    monkeypatch.setitem(figures._REGISTRY, "loop_b", {"extends": "loop_a", "name": "loop_b"})
    s = _ref_spec(world, tmp_path, "study", _GP_CONF,
                  'figure = { extends = "loop_a", name = "v" }')
    with no_hang(TIMEOUT_S):
        assert main(["study", "run", str(s), "--out", str(tmp_path / "o"), "--quick",
                     "--quiet"]) == 2
    one_line_error(capsys, "loop")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_every_shipped_study_names_only_known_family_options():
    from gpmotion.study import shipped_names, spec_path
    from gpmotion.study.spec import load
    for name in shipped_names():
        load(spec_path(name))


# ------------------------------------------------------------------ generators

def _mutate_json(rng, doc, depth=0):
    """A copy of ``doc`` with one value (at a random path) replaced or removed."""
    doc = json.loads(json.dumps(doc))
    node, keys = doc, []
    while isinstance(node, dict) and node and (depth == 0 or rng.random() < 0.6):
        k = rng.choice(sorted(node))
        keys.append(k)
        if not isinstance(node[k], dict) or rng.random() < 0.4:
            break
        node = node[k]
        depth += 1
    if not keys:
        return doc, "$"
    parent = doc
    for k in keys[:-1]:
        parent = parent[k]
    old = parent[keys[-1]]
    choice = rng.random()
    if choice < 0.15:
        del parent[keys[-1]]
    elif choice < 0.25:
        parent["unknown_" + str(rng.randrange(99))] = 1
    else:
        new = rng.choice([w for w in WEIRD if json.dumps(w) != json.dumps(old)])
        parent[keys[-1]] = new
    return doc, ".".join(keys)


def _changed(rng, doc):
    for _ in range(10):
        new, where = _mutate_json(rng, doc)
        if json.dumps(new, sort_keys=True) != json.dumps(doc, sort_keys=True):
            return new, where
    raise AssertionError("no mutation changed the document")


def _garbage(rng) -> bytes:
    kinds = [b"", b"\xff\xfe\x00binary", b"{", b"[]", b'{"format": "gpmotion-best"}',
             b"null", b"{" * 5000, b'{"a": NaN}', os.urandom(64)]
    return rng.choice(kinds)


BAD_RUN_OPTIONS = [
    ["--population", "1"], ["--population", "1000000000"], ["--generations", "0"],
    ["--seed", "-1"], ["--workers", "-2"], ["--threads", "0"], ["--primitives", "add,,sub"],
    ["--primitives", ""], ["--out", ""], ["--param", "nokey"], ["--param", "seconds=-1"],
    ["--param", "bogus=1"], ["--controller", "nope"], ["--rules", "0"],
    ["--erc-range", "2,1"], ["--p-mutation", "2"], ["--seeds", "0"], ["--figure", "nofile"],
    ["--figure", "bogus:starman"], ["--preset", "nope"], ["--robust-starts", "-1"],
    ["--perturb", "x=1"], ["--scheduler", "bogus"], ["--max-size", "0"],
    ["--tau", "1"], ["--islands", "0"], ["--selection", "nope"]]
BAD_OTHER = [
    ["compare", "lamp_hop", "--controllers", ""], ["compare", "lamp_hop", "--seeds", "0"],
    ["compare", "lamp_hop", "--controllers", "gp", "--budget", "1"],
    ["compare", "nope_task"], ["replay", "/nonexistent/best.json"],
    ["export", "/nonexistent", "--bvh", "x.bvh"], ["render", "--figure", "nope"],
    ["render", "--figure", "lamp", "--seconds", "-1"], ["show", "nope"],
    ["resume", "/nonexistent/run"], ["robustness", "/nonexistent.json"]]
STUDY_EDITS = [
    ('name = "gp-vs-bsr"', 'name = "../../../escape"'),
    ('name = "gp-vs-bsr"', 'name = "a/b"'), ('name = "gp-vs-bsr"', 'name = ""'),
    ('family = "gp"', 'family = "nope"'), ('task = "lamp_hop"', 'task = "nope"'),
    ('budget = 3000', 'budget = -1'), ('budget = 3000', 'budget = 1000000000000'),
    ('[configurations.gp]', '[configurations."../x"]'),
    ('family = "gp"', 'family = "gp"\noptions = { bogus = 1 }'),
    ('family = "gp"', 'family = "gp"\nfigure = "bogus:starman"'),
    ('tune_seeds = [0, 1, 2, 3, 4]', 'tune_seeds = [-1]'),
    ('[study]', '[study]\ngravty = 1'), ('judge = "task"', 'judge = "nope"')]
FIGURES = [
    'extends = "lamp"\ngravty = -1.0\n', 'extends = "nope"\n', "name = 3\n",
    'name = "x"\n[[bodies]]\nname = "a"\nmass = -1\n', "[[[", 'extends = "lamp"\n'
    '[[bodies]]\nname = "nobody"\n', 'extends = "lamp"\nroot = 5\n',
    'extends = "lamp"\n[ground]\nfriction = "x"\n', "\x00\xff"]
SCRIPT_TOKENS = ["phase", "one", "two", "=", "total", "*", "+", "(", ")", "max_t", "dcm_x",
                 "~=", "0.5", "\n", "#", "x", "1e999", "-", "/", ",", "dtime"]


def _cases():
    rng = random.Random(SEED)
    out = []
    for _ in range(60):
        out.append(("run-option", {"argv": ["run", "lamp_hop", *GP, "--generations", "1",
                                            *rng.choice(BAD_RUN_OPTIONS)]}))
    for _ in range(30):
        out.append(("other-option", {"argv": rng.choice(BAD_OTHER)}))
    for kind, n in (("config", 70), ("checkpoint", 60), ("log", 20)):
        out += [(kind, {"seed": rng.randrange(2**31)}) for _ in range(n)]
    for _ in range(45):
        out.append(("best", {"seed": rng.randrange(2**31),
                             "cmd": rng.choice(["replay", "export", "render", "robustness"])}))
    for kind, n in (("figure", 30), ("script", 35), ("composite", 25), ("compose-dir", 20),
                    ("study", 30)):
        out += [(kind, {"seed": rng.randrange(2**31)}) for _ in range(n)]
    for name in ("config.json", "checkpoint.json", "log.csv", "best.json"):
        for special in ("fifo", "dir"):
            out.append(("special", {"name": name, "what": special}))
    refs = random.Random(SEED + 2)                    # after the rest: their cases unchanged
    out += [("study-ref", {"seed": refs.randrange(2**31)}) for _ in range(30)]
    return out


CASES = _cases()


def test_the_suite_has_at_least_400_cases():
    assert len(CASES) >= 400


# ------------------------------------------------------------------ a case's input

@dataclass
class Case:
    argv: list
    watched: Path | None             # every file under it must be left as it was
    valid: str = ""                  # why the input is valid (then it is accepted)
    left_nothing: list = field(default_factory=list)    # paths that must not appear


def _valid_best(key, value) -> str:
    """The mutations of best.json that leave a valid record."""
    if key == "actuation" and value is None:
        return "a null actuation is the family's default"
    return ""


def prepare(world: Path, tmp: Path, kind: str, case: dict) -> Case:
    """Write the case's mangled input under ``tmp``; the command that reads it."""
    rng = random.Random(case.get("seed", 0))
    if kind in ("run-option", "other-option"):
        return Case(case["argv"], tmp, left_nothing=[tmp / "runs", tmp / "o"])
    if kind in ("config", "checkpoint"):
        run = _copy(world / "run", tmp)
        path = run / f"{kind}.json"
        doc = json.loads(path.read_text())
        if kind == "checkpoint":
            doc.pop("elapsed_s")              # the one field any number may take
            new, _ = _changed(rng, doc)
            new["elapsed_s"] = 1.0
        else:
            new, _ = _changed(rng, doc)
        path.write_bytes(json.dumps(new).encode() if rng.random() > 0.1 else _garbage(rng))
        return Case(["resume", run, "--quiet"], run)
    if kind == "log":
        run = _copy(world / "run", tmp)
        lines = (run / "log.csv").read_text().splitlines(keepends=True)
        cut = rng.randrange(0, len(lines) - 1)
        (run / "log.csv").write_text("".join(lines[:cut]) if rng.random() < 0.5 else
                                     "".join(lines[:cut] + ["9,9,9\n"] + lines[cut + 1:]))
        return Case(["resume", run, "--quiet"], run)
    if kind == "best":
        d = tmp / "c"
        d.mkdir()
        doc = json.loads((world / "run" / "best.json").read_text())
        key = rng.choice(["format", "version", "task", "family", "genome", "params", "options",
                          "actuation", "plugins"])
        value = rng.choice([w for w in WEIRD if json.dumps(w) != json.dumps(doc.get(key))])
        if key == "params":
            value = {"seconds": rng.choice([-1, "x", 1e9, None]),
                     **({"bogus": 1} if rng.random() < .5 else {})}
        doc[key] = value
        empty = rng.random() <= 0.1
        (d / "best.json").write_text("" if empty else json.dumps(doc))
        extra = {"export": ["--bvh", tmp / "x.bvh"], "render": ["-o", tmp / "x.png"]}
        return Case([case["cmd"], d / "best.json", *extra.get(case["cmd"], [])], d,
                    valid="" if empty else _valid_best(key, value))
    if kind == "figure":
        f = tmp / "v.toml"
        body = rng.choice(FIGURES)
        f.write_bytes(body.encode("utf-8", "surrogateescape") if rng.random() < .9
                      else b"\xff\xfe\x00")
        return Case(["run", "lamp_hop", *GP, "--figure", f, "--out", tmp / "o"], tmp,
                    left_nothing=[tmp / "o"])
    if kind == "script":
        text = " ".join(rng.choice(SCRIPT_TOKENS) for _ in range(rng.randrange(0, 30)))
        (tmp / "s.motion").write_text(text)
        return Case(["compose", tmp / "s.motion", "--controllers", world / "a.json",
                     world / "b.json", "--no-search"], tmp)
    if kind == "composite":
        doc = _fix_paths(json.loads((world / "comp" / "careless.json").read_text()),
                         world / "comp")
        new, _ = _changed(rng, doc)
        (tmp / "c.json").write_text(json.dumps(new))
        return Case(["compose", world / "good.motion", "--composite", tmp / "c.json",
                     "--no-search"], tmp)
    if kind == "compose-dir":
        comp = _copy(world / "comp", tmp)
        path = comp / rng.choice(["config.json", "checkpoint.json"])
        new, _ = _changed(rng, json.loads(path.read_text()))
        path.write_bytes(json.dumps(new).encode() if rng.random() > 0.1 else _garbage(rng))
        return Case(_compose_argv(world, comp, "--resume"), comp)
    if kind == "study":
        old, new = rng.choice(STUDY_EDITS)
        (tmp / "s.toml").write_text((world / "study.toml").read_text().replace(old, new))
        return Case(["study", "run", tmp / "s.toml", "--out", tmp / "o", "--quick", "--quiet"],
                    tmp, left_nothing=[tmp / "o"])
    if kind == "study-ref":
        return _ref_case(world, tmp, rng)
    if kind == "special":
        run = _copy(world / "run", tmp)
        target = run / case["name"]
        target.unlink()
        os.mkfifo(target) if case["what"] == "fifo" else target.mkdir()
        argv = ["replay", target] if case["name"] == "best.json" else ["resume", run, "--quiet"]
        return Case(argv, run)
    raise AssertionError(kind)


# bad references: names that are not a registered figure (itself, a path, a
# near miss, another study's variant, not text) and any ``after`` in a spec
BAD_EXTENDS = ['"v"', '""', '"../lamp"', '"lamp/"', '" lamp"', '"LAMP"', '"lamp.toml"',
               '"starman_damped"', '"/etc/passwd"', '"lamp\\u0000"', "3", "[]", "{}",
               "true", '"x"']
BAD_AFTER = ['"walk"', '"turn"', '"walk2"', '""', '"turn.json"', '"a.json,b.json"',
             '"../walk.json"', "1", "true", '"/etc/passwd"']


def _ref_case(world, tmp: Path, rng) -> Case:
    if rng.random() < 0.5:
        name = rng.choice(['"v"', '"lamp"', '"starman"'])      # a registered name: refused too
        edit = f"figure = {{ extends = {rng.choice(BAD_EXTENDS)}, name = {name} }}"
        spec = _ref_spec(world, tmp, "study", _GP_CONF, edit)
    else:
        anchor = rng.choice([_TURN, 'name = "walk"\n', 'name = "walk2"\n'])
        spec = _ref_spec(world, tmp, "staged", anchor, f"params = {{ after = "
                                                       f"{rng.choice(BAD_AFTER)} }}")
    return Case(["study", "run", spec, "--out", tmp / "o", "--quick", "--quiet"], tmp,
                left_nothing=[tmp / "o"])


def _fix_paths(doc, base: Path):
    """A composite's parts named by absolute path (it is copied elsewhere)."""
    for ph in doc.get("phases", []):
        if isinstance(ph, dict) and isinstance(ph.get("controller"), str):
            ph["controller"] = str((base / ph["controller"]).resolve())
    return doc


# ------------------------------------------------------------------ running a case

def _check(c: Case, code, text: str, before: dict, parser_said: bool = False):
    shown = [str(a) for a in c.argv]
    if c.valid:
        assert code == 0, f"valid input ({c.valid}) refused: {shown}\n{text[-500:]}"
    elif parser_said:            # argparse's own refusal: usage + one error line, exit 2
        assert code == 2, f"{shown}: argparse exit {code}"
    else:
        assert code == 2, f"wrongly accepted (exit {code}): {shown}\n{text[-500:]}"
        assert text.startswith("gpmotion: error:") and "\n" not in text, f"{shown}: {text[-800:]}"
    if c.watched is not None:
        after = {k: v for k, v in hashes(c.watched).items() if not k.endswith("/.lock")}
        before = {k: v for k, v in before.items() if not k.endswith("/.lock")}  # a pid
        lost = {k: v for k, v in before.items() if after.get(k) != v}
        assert not lost, f"{shown} changed or removed {sorted(lost)}"
        if not c.valid:
            assert set(after) <= set(before), f"{shown} refused, but wrote {set(after) - set(before)}"
    for p in c.left_nothing:
        assert not p.exists(), f"{shown} left {p} behind"


@pytest.mark.parametrize("kind,case", CASES, ids=[f"{i}-{k}" for i, (k, _) in enumerate(CASES)])
def test_entry_point_refuses_cleanly(world, tmp_path, kind, case):
    c = prepare(world, tmp_path, kind, case)
    before = hashes(c.watched) if c.watched is not None else {}
    err, cwd, parser_said = io.StringIO(), os.getcwd(), False
    os.chdir(tmp_path)
    try:
        with no_hang(TIMEOUT_S), contextlib.redirect_stderr(err), \
                contextlib.redirect_stdout(io.StringIO()):
            try:
                code = main([str(a) for a in c.argv])
            except SystemExit as e:
                code, parser_said = e.code, True
            except argparse.ArgumentError:      # the same, where argparse does not exit
                code, parser_said = 2, True
    finally:
        os.chdir(cwd)
    _check(c, code, err.getvalue().strip(), before, parser_said)


# the real entry point: a fixed sample of the file cases, each its own process
FILE_KINDS = ("config", "checkpoint", "log", "best", "figure", "script", "composite",
              "compose-dir", "study", "special")
SAMPLE = sorted(random.Random(SEED + 1).sample(
    [i for i, (k, _) in enumerate(CASES) if k in FILE_KINDS], 10))


@pytest.mark.parametrize("i", SAMPLE, ids=[f"{i}-{CASES[i][0]}" for i in SAMPLE])
def test_entry_point_as_a_process(world, tmp_path, i):
    kind, case = CASES[i]
    c = prepare(world, tmp_path, kind, case)
    before = hashes(c.watched) if c.watched is not None else {}
    proc = subprocess.run([sys.executable, "-m", "gpmotion", *map(str, c.argv)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=TIMEOUT_S * 2)
    _check(c, proc.returncode, proc.stderr.strip(), before)
