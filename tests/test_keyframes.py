"""The keyframes family (one file: gpmotion/families/keyframes.py) end to end:
its targets in the kernel, run / resume / replay / compare, exact CMA-ES
checkpoints as plain JSON, and the same result on a process pool and Dask."""
import json

import numpy as np
import pytest

from gpmotion.cli import main
from gpmotion.compare import compare
from gpmotion.controllers import schedule_kernel
from gpmotion.families import make_family
from gpmotion.replay import load_controller, replay_genome
from gpmotion.run import RunConfig, run
from gpmotion.task import get_task
from tests.golden_runs import record

SHORT = {"seconds": "0.3"}
RUN = ["run", "lamp_hop", "--controller", "keyframes", "--param", "seconds=0.3", "--generations",
       "4", "--population", "6", "--keys", "4", "--quiet", "--no-artifacts"]


def _cfg(**search):
    return RunConfig(task="lamp_hop", family="keyframes", seed=3, params=dict(SHORT),
                     family_options={"keys": 4},
                     search={"generations": 5, "population": 6, **search})


def test_targets_are_linear_between_evenly_spaced_keys_and_neutral_elsewhere():
    task = get_task("herman_touch_nose")                  # controls 6 of 29 actuators
    fam = make_family("keyframes", task, keys=5)
    g = fam.random(np.random.default_rng(0))
    batch = fam.encode([g])
    n_act = len(fam.neutral)
    targets, taus = np.zeros(n_act), np.zeros(n_act)
    keys_t = np.linspace(0, task.seconds, 5)
    assert np.allclose(fam.times, keys_t)
    for t in (0.0, 0.1, 0.37, 0.75, 1.2, task.seconds, task.seconds + 1):
        schedule_kernel.control(batch.ci[0], batch.cf[0], np.zeros(1), np.zeros(1), t,
                                np.zeros(1), targets, taus)
        want = fam.neutral.copy()
        want[fam.actuators] = [np.interp(t, keys_t, g[:, j]) for j in range(len(fam.actuators))]
        assert np.allclose(targets, want, atol=1e-12), t
        assert np.all(taus == fam.default_tau)
    lo, hi = fam.lo, fam.hi
    assert np.all(g >= lo) and np.all(g <= hi)


def test_cmaes_is_deterministic_and_ignores_global_numpy_random():
    fam = make_family("keyframes", get_task("lamp_hop", seconds=0.3))
    asks = []
    for outer in (1, 2):
        np.random.seed(outer)
        s = fam.make_search(7, population=6, generations=3)
        seen = []
        while not s.done:
            g = s.ask()
            np.random.rand(10)                              # other code drawing in between
            seen.append([fam.to_json(x) for x in g])
            s.tell([float(np.sum(x)) for x in g])
        asks.append(seen)
    assert asks[0] == asks[1]


def test_run_interrupted_and_resumed_is_the_uninterrupted_run(tmp_path):
    run(_cfg(), tmp_path / "full", quiet=True, artifacts=False)
    run(_cfg(), tmp_path / "part", quiet=True, artifacts=False, max_generations=2)
    assert not (tmp_path / "part" / "best.json").exists()
    state = json.loads((tmp_path / "part" / "checkpoint.json").read_text())["search"]
    assert state["format"] == "cmaes-keyframes-v1" and len(state["told"]) == 2
    run(None, tmp_path / "part", resume=True, quiet=True, artifacts=False)
    assert record(tmp_path / "part") == record(tmp_path / "full")


def test_a_checkpoint_that_does_not_replay_is_refused(tmp_path, capsys):
    out = tmp_path / "r"
    run(_cfg(), out, quiet=True, artifacts=False, max_generations=2)
    ck_path = out / "checkpoint.json"
    ck = json.loads(ck_path.read_text())
    ck["search"]["told"][0][0] += 1.0                      # another history: another mean
    ck_path.write_text(json.dumps(ck))
    assert main(["resume", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "does not replay" in err and "\n" not in err.strip()


def test_cli_run_replay_render_and_compare(tmp_path, capsys):
    out = tmp_path / "kf"
    assert main([*RUN, "--out", str(out)]) == 0
    best = json.loads((out / "best.json").read_text())
    assert best["family"] == "keyframes" and len(best["genome"]["values"]) == 4
    assert main(["replay", str(out), "--json"]) == 0
    replayed = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert replayed["cost"] == best["final_cost"]
    assert main(["render", str(out), "--trees", str(tmp_path / "t.png")]) == 2
    assert "keyframes controller has no structure to draw" in capsys.readouterr().err
    rows, _ = compare("lamp_hop", ["keyframes"], 1, 40, tmp_path / "cmp", params=SHORT,
                      quiet=True)
    assert rows[0]["controller"] == "keyframes"
    task, fam, act, genome, rec = load_controller(tmp_path / "cmp" / "best" / "keyframes-seed0.json")
    assert replay_genome(task, fam, act, genome)[1][0] == rec["final_cost"]


@pytest.mark.slow               # starts worker processes (compiling in each)
@pytest.mark.parametrize("backend", [["--workers", "2"], ["--scheduler", "local", "--workers", "2"]])
def test_same_result_on_a_pool_and_on_dask(tmp_path, backend):
    assert main([*RUN, "--out", str(tmp_path / "here")]) == 0
    assert main([*RUN, "--out", str(tmp_path / "there"), *backend]) == 0
    assert record(tmp_path / "there") == record(tmp_path / "here")


def test_fresh_scores_keep_the_last_generations_best_not_the_luckiest():
    """Robust starts (noisy costs): the best is the last generation's, and the
    search itself (its samples) is unchanged."""
    fam = make_family("keyframes", get_task("lamp_hop", seconds=0.3))

    def run_noisy(s):
        lowest, asked = [], []
        while not s.done:
            luck = -1.0 if s.generation % 2 == 0 else 1.0     # easy, hard, easy, ... starts
            g = s.ask()
            asked.append([fam.to_json(x) for x in g])
            costs = [float(np.sum(np.square(x))) * 1e-3 + luck for x in g]
            lowest.append(min(costs))
            s.tell(costs)
        return lowest, asked
    # lamp_hop's style terms are at full weight from generation 8 of 0..9: 8 (easy) and 9 share a phase
    stale, fresh = fam.make_search(7, population=6, generations=10), \
        fam.make_search(7, population=6, generations=10, fresh_scores=True)
    (lo_s, a_s), (lo_f, a_f) = run_noisy(stale), run_noisy(fresh)
    assert a_s == a_f and lo_s == lo_f
    assert stale.best_cost == lo_s[8] < lo_f[9] - 1.0 and fresh.best_cost == lo_f[9]
    assert fam.noisy_settings() == {"fresh_scores": True}
    assert fresh.config()["fresh_scores"] is True and "fresh_scores" not in stale.config()
