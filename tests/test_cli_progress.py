"""The progress line says what it means: generations numbered as log.csv numbers them
(from 0, every family), a recent evals/s, what `solved` counts among, and a note
before a kernel compiles for the first time."""
import csv
import re

import numpy as np
import pytest

from gpmotion import cache, compile_events
from gpmotion.cli import main
from gpmotion.evaluation import Evaluation
from gpmotion.progress import Progress

LINE = re.compile(r"gen\s+(\d+)/(\d+) .* solved (\d+) of (\d+) evaluated")


def ev(n=4):
    return Evaluation(np.arange(n, dtype=float), np.zeros(n, bool), np.zeros(n, bool), {})


def test_evals_per_second_is_the_recent_rate_not_the_average_since_the_start():
    p = Progress(100)
    p.t0 = 0.0
    p._recent[0] = (0.0, 0)
    p.evals = 8
    assert p.rate(100.0) == pytest.approx(0.08)     # the first generation compiled for 100 s
    for k in range(1, 11):                          # then 100 evaluations a second
        p.evals += 100
        rate = p.rate(100.0 + k)
    assert rate == pytest.approx(100.0)


def _gens(err: str):
    return [tuple(int(x) for x in m.groups()) for m in map(LINE.search, err.splitlines()) if m]


@pytest.mark.parametrize("family, budget", [
    ("gp", ["--population", "8", "--generations", "3"]),
    ("bsr-sense", ["--working", "2", "--generations", "3"]),
])
def test_generations_are_numbered_as_the_log_numbers_them(family, budget, tmp_path, capsys):
    out = tmp_path / family
    assert main(["run", "lamp_hop", "--controller", family, "--out", str(out),
                 "--param", "seconds=0.2", "--no-artifacts", *budget]) == 0
    err = capsys.readouterr().err
    rows = list(csv.DictReader(open(out / "log.csv")))
    gens = _gens(err)
    assert gens[0][0] == 0 == int(rows[0]["generation"])       # every family counts from 0
    assert gens[-1][0] == gens[-1][1] == int(rows[-1]["generation"])
    assert f"generations 0–{rows[-1]['generation']}" in err
    assert all(k <= n for _, _, k, n in gens)


@pytest.fixture(autouse=True)
def own_timings(tmp_path, monkeypatch):
    """Compile times these tests measure go to a file of their own, never the user's."""
    path = tmp_path / "compile-seconds.json"
    monkeypatch.setattr(compile_events, "timings_path", lambda: path)
    return path


def test_a_cold_kernel_is_announced_before_it_compiles(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(cache, "numba_indexed", lambda path: False)    # as on a fresh machine
    monkeypatch.setattr("gpmotion.sim.kernels._KERNELS", {})
    assert main(["run", "lamp_hop", "--out", str(tmp_path / "r"), "--param", "seconds=0.2",
                 "--population", "4", "--generations", "1", "--no-artifacts"]) == 0
    err = capsys.readouterr().err
    assert "compiling the lamp kernels (minutes, the first time on this machine" in err
    assert err.index("compiling the lamp kernels") < err.index("gen ")
    assert err.index("compiling the lamp kernels") < err.index("compiled the lamp kernels: "
                                                                "the first generation took")


def test_a_warm_kernel_is_not_announced(tmp_path, capsys):
    assert main(["run", "lamp_hop", "--out", str(tmp_path / "r"), "--param", "seconds=0.2",
                 "--population", "4", "--generations", "1", "--no-artifacts"]) == 0
    assert "compiling" not in capsys.readouterr().err


def test_numba_index_files_tell_a_compiled_module(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    module = tmp_path / "kernels" / "rollout_abc.py"
    assert not cache.numba_indexed(module)
    (tmp_path / "kernels_1234").mkdir()
    (tmp_path / "kernels_1234" / "rollout_abc.rollout-12.py311.nbi").write_bytes(b"")
    assert cache.numba_indexed(module)
    heard = []
    with cache.on_cold_compile(heard.append):
        cache.announce_compile(module)                   # warm: nothing said
        cache.announce_compile(tmp_path / "rollout_new.py")
    cache.announce_compile(tmp_path / "rollout_other.py")   # nobody listening
    assert heard == [tmp_path / "rollout_new.py"]


def test_check_says_what_it_checks_while_it_runs(capsys):
    from pathlib import Path
    examples = Path(__file__).resolve().parents[1] / "examples"
    assert main(["check", "--plugins", str(examples), "--only-plugins"]) == 0
    out, err = capsys.readouterr()
    assert "checking 1 task (" in err
    assert "[1/1] checking task lamp_reach-v1 …" in err
    assert out.splitlines() == ["ok    task lamp_reach-v1"]


def test_the_compare_plot_names_its_curve_as_the_progress_line_and_log_do(monkeypatch):
    """compare plots log.csv's best_final: the progress line's 'best final', never
    'best so far' (which names the best under the current weights)."""
    import gpmotion.render as render
    from gpmotion.compare import plot_curves
    from gpmotion.task import get_task
    drawn = {}
    monkeypatch.setattr(render, "_save_png", lambda fig, path, dpi=None: drawn.update(fig=fig))
    x = np.array([10.0, 20.0])
    plot_curves("unused.png", {"gp": (x, x / 100, x / 90, x / 80)}, get_task("lamp_hop"),
                None, None, "pd")
    label = drawn["fig"].axes[0].get_ylabel()
    assert label.startswith("best final (final weights)") and "so far" not in label


def test_a_stopped_run_names_the_generation_its_log_ends_at(tmp_path, monkeypatch):
    import os
    import signal

    import importlib
    runmod = importlib.import_module("gpmotion.run")     # gpmotion.run is also the function
    from gpmotion.run import RunConfig, Stopped, run
    real = runmod._evaluator

    def interrupting(*args, **kwargs):
        ev = real(*args, **kwargs)
        evaluate = ev.evaluate

        def once(*a, **k):
            os.kill(os.getpid(), signal.SIGINT)           # Ctrl-C during generation 0
            return evaluate(*a, **k)
        ev.evaluate = once
        return ev
    monkeypatch.setattr(runmod, "_evaluator", interrupting)
    cfg = RunConfig(task="lamp_hop", params={"seconds": 0.2},
                    search={"population": 4, "generations": 3})
    with pytest.raises(Stopped, match="after generation 0;"):
        run(cfg, tmp_path / "r", quiet=True, artifacts=False)
    rows = list(csv.DictReader(open(tmp_path / "r" / "log.csv")))
    assert [r["generation"] for r in rows] == ["0"]


RATE = re.compile(r"([\d,]+) evals/s")


def test_the_log_records_the_rate_the_progress_line_shows(tmp_path, capsys):
    """log.csv's recent_evals_per_s is the progress line's evals/s (the recent rate),
    not an average since the start under a name that does not say so."""
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--param", "seconds=0.2",
                 "--population", "4", "--generations", "2", "--no-artifacts"]) == 0
    shown = [float(m.group(1).replace(",", "")) for m in
             map(RATE.search, capsys.readouterr().err.splitlines()) if m]
    rows = list(csv.DictReader(open(out / "log.csv")))
    assert "recent_evals_per_s" in rows[0] and "evals_per_s" not in rows[0]
    assert abs(float(rows[-1]["recent_evals_per_s"]) - shown[-1]) <= 0.55   # "%.0f" of it


def test_a_log_begun_by_an_older_gpmotion_keeps_its_column_and_its_meaning(tmp_path):
    """A run written before the column was renamed resumes: its header stays, and the
    rows it gains fill evals_per_s with what that column always held, the average."""
    import shutil
    from pathlib import Path
    old = tmp_path / "old"
    shutil.copytree(Path(__file__).parent / "data" / "old_run_lamp_hop", old)
    header = (old / "log.csv").read_text().splitlines()[0]
    assert "evals_per_s" in header.split(",")
    assert main(["resume", str(old), "--extend-generations", "2", "--quiet"]) == 0
    lines = (old / "log.csv").read_text().splitlines()
    assert lines[0] == header
    rows = list(csv.DictReader(lines))
    assert len(rows) == len(lines) - 1 and all(None not in r.values() for r in rows)
    assert int(rows[-1]["generation"]) == int(rows[-3]["generation"]) + 2
    for r in rows[-2:]:
        average = int(r["evaluations"]) / float(r["elapsed_s"])
        assert float(r["evals_per_s"]) == pytest.approx(average, rel=0.01, abs=0.1)


def test_the_estimate_is_the_first_generation_measured_here_last_time(own_timings, capsys):
    """No number until one was measured on this CPU model; then that number, for
    that figure and family only."""
    from gpmotion.progress import CompileNote, first_generation_done
    with cache.on_cold_compile(CompileNote("lamp", "lamp gp")) as note:
        note("rollout_a.py")
        note("rollout_b.py")                          # one note for the run's wait
        note.t0 -= 95.0                               # as if the generation took 95 s
        first_generation_done()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and "minutes, the first time on this machine" in err[0]
    assert "the first generation took 95 s" in err[1]
    assert compile_events.compile_seconds("lamp gp") == pytest.approx(95.0, abs=0.2)
    assert compile_events.compile_seconds("lamp bsr-sense") is None
    with cache.on_cold_compile(CompileNote("lamp", "lamp gp")) as note:
        note("rollout_c.py")
    assert "its first generation took 95 s here last time, compiling included" in \
        capsys.readouterr().err
    own_timings.write_text("[not a table")            # a damaged cache file: no estimate
    assert compile_events.compile_seconds("lamp gp") is None


def _cold_in_workers(tmp_path, monkeypatch):
    """Worker processes start as on a fresh machine: their numba index looks empty
    (a sitecustomize on their PYTHONPATH; this process is untouched)."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(
        "import gpmotion.cache\ngpmotion.cache.numba_indexed = lambda path: False\n")
    import os
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(site)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))


@pytest.mark.parametrize("backend", [["--workers", "2"], ["--scheduler", "local",
                                                          "--workers", "1"]],
                         ids=["process-pool", "dask"])
def test_a_cold_compile_in_the_workers_is_announced_by_the_run(tmp_path, capsys, monkeypatch,
                                                               backend):
    if backend[1] == "local":
        pytest.importorskip("distributed")
    _cold_in_workers(tmp_path, monkeypatch)
    assert main(["run", "lamp_hop", "--out", str(tmp_path / "r"), "--param", "seconds=0.2",
                 "--population", "4", "--generations", "1", "--no-artifacts", *backend]) == 0
    err = capsys.readouterr().err
    assert err.count("compiling the lamp kernels") == 1           # once, however many workers
    assert err.index("compiling the lamp kernels") < err.index("gen ")
    assert "compiled the lamp kernels: the first generation took" in err
