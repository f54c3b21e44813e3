"""Untrusted controller and checkpoint files: any input gives a clear ValueError
(FormatError), never another exception, never code execution."""
import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gpmotion.families import make_family
from gpmotion.records import FormatError
from gpmotion.search.adapters import make_search
from gpmotion.task import get_task

TASK = get_task("lamp_hop", seconds=0.3)
FAMILIES = {name: make_family(name, TASK) for name in ("gp", "bsr-sense", "bsr-time")}
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
    search = make_search(FAMILIES[family], seed=0, **({"population": 6, "generations": 2}
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
        except (ValueError, KeyError, TypeError, IndexError, AttributeError):
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
