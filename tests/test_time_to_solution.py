"""benchmarks/time_to_solution.py: the work of a run, counted from the rollouts it makes."""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
import time_to_solution  # noqa: E402


def test_a_runs_steps_time_in_the_kernel_and_kernels_are_counted():
    """Every evaluation and the replay of the best are counted (3,000 steps each,
    fewer for one that diverged), on two threads as on one; one kernel."""
    rows = [time_to_solution.one_run("lamp_hop", 0, {"generations": 2, "population": 10},
                                     threads, artifacts=False) for threads in (1, 2)]
    for r in rows:
        assert r["generations"] == 2 and r["kernels"] == 1
        assert 0 < r["steps"] <= (r["evals"] + 1) * 3000
        assert r["steps"] > r["evals"] * 3000 * 0.9        # diverged episodes are rare
        assert 0 < r["outside"] < 1 and r["finish_s"] >= 0
    assert rows[0]["steps"] == rows[1]["steps"] and rows[0]["cost"] == rows[1]["cost"]


def test_a_run_whose_falls_are_final_counts_the_steps_it_simulated():
    """With ``falls_final=1`` a fallen episode ends at its fall: the count is what ran."""
    r = time_to_solution.one_run("lamp_hop", 0, {"generations": 2, "population": 10}, 2,
                                 artifacts=False, params={"falls_final": 1})
    assert 0 < r["steps"] < r["evals"] * 3000 * 0.9


def test_where_the_steps_went_counts_none_after_a_fall_that_ended_its_episode():
    """``--episodes``: full episodes run on after a fall; episodes that a fall ends do not."""
    search = {"generations": 2, "population": 10}
    full = time_to_solution.one_run("lamp_hop", 0, search, 2, artifacts=False, episodes=True)
    final = time_to_solution.one_run("lamp_hop", 0, search, 2, artifacts=False, episodes=True,
                                     params={"falls_final": 1})
    assert full["fell_after"] > 0 and final["fell_after"] == 0


def test_steps_to_the_bar_are_read_at_the_batch_that_reached_it():
    meter = time_to_solution.KernelMeter()
    meter.trace = [(30, 32_390), (60, 67_760), (90, 91_300)]
    assert [meter.steps_at(n) for n in (1, 30, 31, 90)] == [32_390, 32_390, 67_760, 91_300]


def test_counting_signatures_survives_a_dead_weak_proxy():
    """A process that ran other code holds weak proxies to dead objects; the
    count must step over them (isinstance on one raises ReferenceError)."""
    import weakref

    class Gone:
        pass
    obj = Gone()
    proxy = weakref.proxy(obj)
    del obj
    assert time_to_solution.jit_signatures() >= 0
    assert proxy is not None
