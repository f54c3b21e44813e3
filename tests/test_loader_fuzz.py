"""Untrusted controller and checkpoint files: any input gives a clear ValueError
(FormatError), never another exception, never code execution."""
import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gpmotion.families import family_names, make_family
from gpmotion.task import get_task

TASK = get_task("lamp_hop", seconds=0.3)
FAMILIES = {name: make_family(name, TASK) for name in family_names()}
NAMES = ["add", "sub", "mul", "div", "iflte", "sin", "cos", "abs", "px", "vx", "t", "angle_elbow",
         "os.system", "__import__", "eval", "", "ERC", "lambda"]
token = st.one_of(st.sampled_from(NAMES), st.floats(allow_nan=True, allow_infinity=True),
                  st.integers(), st.booleans(), st.none(), st.text(max_size=8))
json_value = st.recursive(st.one_of(st.none(), st.booleans(), st.floats(), st.integers(),
                                    st.text(max_size=6)),
                          lambda inner: st.lists(inner, max_size=5) |
                          st.dictionaries(st.text(max_size=6), inner, max_size=5), max_leaves=20)
genome_like = st.one_of(
    st.fixed_dictionaries({"kind": st.just("gp"),
                           "trees": st.lists(st.lists(token, max_size=30), max_size=4)}),
    st.fixed_dictionaries({"format": st.sampled_from(["bsr-sense-v1", "bsr-time-v1"]),
                           "theta0": json_value, "tau": json_value, "t_per": json_value,
                           "mu": json_value, "lam": json_value, "limits": json_value,
                           "tau_range": json_value}),
    json_value)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=genome_like, family=st.sampled_from(sorted(FAMILIES)))
def test_controller_loader_only_raises_value_errors(data, family):
    try:
        FAMILIES[family].from_json(data)
    except ValueError:
        pass


def _checkpoint_state(family):
    search = FAMILIES[family].make_search(0, **({"population": 6, "generations": 2}
                                                        if family == "gp" else
                                                        {"n_working": 4, "n_generations": 2}))
    return json.loads(json.dumps(search.state_dict())), search


def _mutations(state):
    """Plausible corruptions of a real checkpoint: dropped keys, wrong types."""
    keys = list(state)
    return st.one_of(
        st.sampled_from(keys).map(lambda k: {x: v for x, v in state.items() if x != k}),
        st.tuples(st.sampled_from(keys), json_value).map(lambda kv: {**state, kv[0]: kv[1]}),
        json_value)


@pytest.mark.parametrize("family", ["gp", "bsr-time"])
def test_checkpoint_loader_only_raises_value_errors(family):
    state, _ = _checkpoint_state(family)

    @settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(bad=_mutations(state))
    def check(bad):
        _, fresh = _checkpoint_state(family)
        try:
            fresh.load_state_dict(bad)
        except (ValueError, KeyError, TypeError, IndexError, AttributeError, OverflowError):
            pass        # the run loop turns these into one FormatError line (tested below)

    check()


def test_resume_from_a_corrupted_checkpoint_is_one_clear_line(tmp_path, capsys):
    from gpmotion.cli import main
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--param", "seconds=0.3", "--population",
                 "8", "--generations", "2", "--quiet", "--no-artifacts"]) == 0
    ck = json.loads((out / "checkpoint.json").read_text())
    ck["search"]["population"] = [["not", "a", "genome"]]
    (out / "checkpoint.json").write_text(json.dumps(ck))
    capsys.readouterr()
    assert main(["resume", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and "checkpoint" in err and "\n" not in err


# ---- whole documents: best.json, config.json, checkpoint.json ----------------------------
# Every mutation of a real run's files either loads or raises one ValueError line, and no
# plugin code ever runs (a planted folder would write a marker file if imported).

import shutil  # noqa: E402

from gpmotion.records import read_json  # noqa: E402

MARKER_CODE = "from pathlib import Path\nPath({marker!r}).write_text('ran')\n"


@pytest.fixture(scope="module")
def real_run(tmp_path_factory):
    from gpmotion.cli import main
    base = tmp_path_factory.mktemp("docs")
    out = base / "run"
    assert main(["run", "lamp_hop", "--controller", "bsr-time", "--out", str(out), "--param",
                 "seconds=0.3", "--working", "4", "--generations", "2", "--quiet",
                 "--no-artifacts"]) == 0
    evil = base / "evil"
    evil.mkdir()
    marker = base / "MARKER"
    (evil / "evil.py").write_text(MARKER_CODE.format(marker=str(marker)))
    docs = {k: json.loads((out / f"{k}.json").read_text()) for k in ("best", "config", "checkpoint")}
    return out, evil, marker, docs


def _plugin_values(evil):
    from gpmotion.plugins import folder_digest
    return st.sampled_from([str(evil), [str(evil)], ["."], [".", str(evil)], [{"name": "evil"}],
                            [{"name": "evil", "digest": folder_digest(evil)}],
                            [{"name": "evil", "digest": "0" * 64, "path": str(evil)}], [None], [[]]])


def _mutate(doc, values):
    """A real document with one key at some depth dropped or replaced."""
    paths = []

    def walk(d, prefix):
        for k, v in d.items():
            paths.append(prefix + (k,))
            if isinstance(v, dict) and len(prefix) < 2:
                walk(v, prefix + (k,))
    walk(doc, ())

    def apply(args):
        path, value, drop = args
        new = json.loads(json.dumps(doc))
        d = new
        for k in path[:-1]:
            d = d[k]
        if drop:
            d.pop(path[-1], None)
        else:
            d[path[-1]] = value
        return new
    return st.tuples(st.sampled_from(paths), values, st.booleans()).map(apply)


def _write(run_dir, dest, kind, doc):
    if dest.exists():
        shutil.rmtree(dest)
    shutil.copytree(run_dir, dest)
    (dest / f"{kind}.json").write_text(json.dumps(doc))
    return dest


def _one_line(e):
    """What the CLI prints as one clear line: a ValueError, or a KeyError carrying a sentence
    (``unknown task 'x'; known: ...``), never a bare key (``error: run``)."""
    msg = e.args[0] if isinstance(e, KeyError) and e.args else str(e)
    assert isinstance(e, (ValueError, KeyError)), f"{type(e).__name__}: {e}"
    assert isinstance(msg, str) and " " in msg and "\n" not in msg, f"{type(e).__name__}: {msg!r}"


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_whole_best_json_loads_or_is_one_line_and_runs_no_code(real_run, tmp_path, data):
    from gpmotion.replay import load_controller
    out, evil, marker, docs = real_run
    doc = data.draw(st.one_of(_mutate(docs["best"], st.one_of(json_value, _plugin_values(evil))),
                              _mutate(docs["best"], _plugin_values(evil)).map(dict)))
    d = _write(out, tmp_path / "copy", "best", doc)
    try:
        load_controller(d)
    except Exception as e:       # noqa: BLE001 - the assertion names it
        _one_line(e)
    assert not marker.exists()


@pytest.mark.parametrize("kind", ["config", "checkpoint"])
def test_whole_config_and_checkpoint_resume_or_are_one_line_and_run_no_code(real_run, tmp_path, kind):
    from gpmotion.run import run
    out, evil, marker, docs = real_run
    values = st.one_of(json_value, _plugin_values(evil))

    @settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(doc=_mutate(docs[kind], values))
    def check(doc):
        d = _write(out, tmp_path / "copy", kind, doc)
        (d / "best.json").unlink()
        try:
            run(None, d, resume=True, quiet=True, artifacts=False, max_generations=0)
        except Exception as e:   # noqa: BLE001
            _one_line(e)
        assert not marker.exists()

    check()
    assert read_json(out / "best.json", kind="best")        # the source run is untouched


@pytest.mark.parametrize("key, value", [("family_config", [None]), ("family_config", 3),
                                        ("task_config", "x"), ("task_config", {"params": [1]})])
def test_a_config_whose_recorded_settings_are_not_tables_is_one_line_on_resume(real_run, tmp_path, key, value):
    """Found by the fuzz test above (hypothesis seed 13): family_config = [None] was a TypeError."""
    from gpmotion.run import run
    out, _, _, docs = real_run
    doc = json.loads(json.dumps(docs["config"]))
    inner = doc["data"] if "data" in doc else doc
    inner[key] = value
    d = _write(out, tmp_path / "copy", "config", doc)
    with pytest.raises(ValueError) as e:
        run(None, d, resume=True, quiet=True, artifacts=False, max_generations=0)
    _one_line(e.value)
    assert key in str(e.value)
