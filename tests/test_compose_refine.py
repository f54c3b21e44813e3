"""Refining a phase's controller inside its composite (the paper's
future work): the climb never gets worse, is deterministic and resumable;
variants of one phase run exactly as their own composites; the refined
controller is a file of its own that replays to the reported score."""
import json

import numpy as np
import pytest

from gpmotion.compose import composite as C
from gpmotion.compose import refine as R
from gpmotion.compose import script as S
from gpmotion.cli.compose import main
from gpmotion.replay import load_controller
from tests.test_composite import write_controller

SCRIPT = "phase one = dcm_x\nphase two = dcm_x\ntotal = one + two\n"


class _Line:
    """A toy family: a genome is one number; mutate steps it by N(0, 1)."""
    name = "toy"

    def copy(self, g):
        return float(g)

    def mutate(self, g, rng, extra=None):
        return g + float(rng.standard_normal())

    def to_json(self, g):
        return {"x": g}

    def from_json(self, d):
        return float(d["x"])


def _climb(state=None, stop=None):
    c = R.PhaseRefinement(_Line(), 0.0, rounds=12, mutants=4, seed=7)
    if state is not None:
        c.load_state_dict(json.loads(json.dumps(state)))
    trace = []
    while not c.done and c.round != stop:
        c.tell([-abs(x - 3.0) for x in c.ask()])
        trace.append(c.best_score)
    return c, trace


def test_the_climb_never_gets_worse_and_resumes_exactly():
    whole, trace = _climb()
    assert whole.start_score == -3.0 and np.all(np.diff(trace) >= 0) and whole.best_score > -0.5
    assert whole.evaluations == 1 + 12 * 4 and whole.accepted >= 1
    part, _ = _climb(stop=5)
    resumed, _ = _climb(state=part.state_dict())
    assert resumed.best == whole.best and resumed.best_score == whole.best_score
    c = R.PhaseRefinement(_Line(), 0.0, rounds=2, mutants=4)
    assert c.ask() == [0.0]                     # round -1: the incumbent, scored once
    c.tell([-3.0])
    assert len(c.ask()) == 4
    with pytest.raises(ValueError, match="expected 4 scores"):
        c.tell([0.0])
    with pytest.raises(ValueError, match="rounds must be an integer"):
        R.PhaseRefinement(_Line(), 0.0, rounds=0)


@pytest.fixture(scope="module")
def comp(tmp_path_factory):
    d = tmp_path_factory.mktemp("refine")
    paths = [write_controller(d / "a.json", seconds=0.5),
             write_controller(d / "b.json", family="bsr-time", seed=1, seconds=0.5)]
    return C.from_controllers(paths, names=["one", "two"])


def test_a_phase_variant_runs_as_its_own_composite(comp):
    part = comp.parts[1]
    rng = np.random.default_rng(0)
    variants = [part.genome] + [part.family.mutate(part.family.copy(part.genome), rng) for _ in range(2)]
    traj, bounds = C.run(comp, variants=(1, variants * 2))                 # repeats too
    for e, g in enumerate(variants * 2):
        alone, _ = C.run(R._with_genome(comp, 1, g))
        assert np.array_equal(traj.q[e], alone.q[0]), e
    assert not np.array_equal(traj.q[1], traj.q[2])
    with pytest.raises(C.CompositeError, match="3 phase-1 variants for 2 episodes"):
        C.run(comp, np.tile(comp.switches, (2, 1)), variants=(1, variants))


def test_refine_improves_in_order_and_saves_a_controller_that_replays(comp, tmp_path):
    script = S.parse(SCRIPT)
    new, report = R.refine(comp, script, ["two", "one"], rounds=3, mutants=4, seed=2)
    again, report2 = R.refine(comp, script, ["one", "two"], rounds=3, mutants=4, seed=2)
    assert report == report2 and list(report) == ["one", "two"]            # composite order
    assert report["one"]["after"] >= report["one"]["before"]
    assert report["two"]["before"] == report["one"]["after"]               # two starts where one ended
    assert report["two"]["evaluations"] == 1 + 3 * 4
    saved = R.save_refined(tmp_path, new, report)
    traj, bounds = C.run(saved)
    assert S.evaluate(script, traj, bounds, saved.scenes)["total"][0] == report["two"]["after"]
    task, fam, _, genome, rec = load_controller(tmp_path / "refined_two.json")
    assert fam.to_json(genome) == fam.to_json(new.parts[1].genome)
    assert rec["refined"]["from"].endswith("b.json") and "cost" not in rec and "success" not in rec
    C.save(tmp_path / "c.json", saved)
    assert C.load(tmp_path / "c.json").parts[1].source == str((tmp_path / "refined_two.json").resolve())
    with pytest.raises(C.CompositeError, match="not phases of the script"):
        R.refine(comp, script, ["three"])


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_compose_refine_on_the_command_line(comp, tmp_path, capsys):
    (tmp_path / "s.motion").write_text(SCRIPT)
    C.save(tmp_path / "careless.json", comp)
    base = [tmp_path / "s.motion", "--composite", tmp_path / "careless.json", "--arrays", "2",
            "--rounds", "1", "--mutations", "1", "--no-artifacts", "--quiet"]
    code, out, err = _run(capsys, *base, "--out", tmp_path / "r", "--refine", "two",
                          "--refine-rounds", "2", "--refine-mutants", "3")
    assert code == 0, err
    result = json.loads((tmp_path / "r" / "result.json").read_text())
    assert result["simulations"] == 1 + 2 + 1 + 2 * 3
    assert result["best"]["total"] == result["refined"]["two"]["after"] >= result["searched"]["total"]
    assert "searched:" in out and (tmp_path / "r" / "refined_two.json").exists()
    code, out2, _ = _run(capsys, *base, "--out", tmp_path / "r", "--refine", "two",
                         "--refine-rounds", "2", "--refine-mutants", "3", "--resume")
    assert code == 0 and out2 == out
    code, _, err = _run(capsys, *base, "--out", tmp_path / "r", "--resume")
    assert code == 2 and "config.json differs" in err
    for extra, words in ((["--refine-rounds", "2"], "--refine-rounds needs --refine"),
                         (["--refine", "three"], "--refine names ['three']; the script's phases: one, two"),
                         (["--refine", "one", "--no-search"], "does not apply with --no-search"),
                         (["--refine", "one", "--refine-mutants", "0"], "--refine-mutants must be in 1..10000")):
        code, _, err = _run(capsys, *base, "--out", tmp_path / "x", *extra)
        assert code == 2 and words in err and err.count("\n") == 1, (extra, err)
