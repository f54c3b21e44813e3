"""`gpmotion study run`: every search through the run loop, one ledger row per
configuration × seed × start, resumable after SIGKILL at any instant with the
same rows; a changed spec is refused; tables re-judge from kept measures."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpmotion.cli import main
from gpmotion.study import load_directory
from gpmotion.study.ledger import RESULTS, read_rows
from gpmotion.study.table import summarize, wilson

SPEC = """
[study]
name = "small"
title = "a small study"
tune_seeds = [0]
report_seeds = [100]

[defaults]
task = "starman_travel"
family = "bsr-time"
params = {{ seconds = 0.3 }}
search = {{ n_working = 4, n_generations = {gens}, reseed_every = 50 }}

[configurations.gait]
judge = "gait"
params = {{ w_contact_distance = 2.0 }}
expect = ["shuffle", "periodic shuffle"]

[configurations.task]
judge = "task"
starts = 2
"""
TIMING = ("wall_s", "cpu_s")


def spec(tmp_path, gens=3, name="spec.toml"):
    p = tmp_path / name
    p.write_text(SPEC.format(gens=gens))
    return p


def untimed(rows):
    return sorted(({k: v for k, v in r.items() if k not in TIMING} for r in rows),
                  key=lambda r: (r["config"], r["seed"], r["start"]))


def controllers(d):
    return {p.name: p.read_text() for p in sorted((d / "controllers").iterdir())}


def test_a_study_runs_every_job_once_and_a_rerun_adds_nothing(tmp_path, capsys):
    s, out = spec(tmp_path), tmp_path / "out"
    assert main(["study", "run", str(s), "--out", str(out), "--quiet"]) == 0
    rows = read_rows(out)
    assert sorted((r["config"], r["seed"], r["start"]) for r in rows) == [
        ("gait", 0, 0), ("gait", 100, 0), ("task", 0, 0), ("task", 0, 1),
        ("task", 100, 0), ("task", 100, 1)]
    by = {(r["config"], r["seed"], r["start"]): r for r in rows}
    assert by[("task", 0, 1)]["search_seed"] == 1 and by[("task", 100, 1)]["search_seed"] == 201
    assert by[("gait", 0, 0)]["seeds"] == "tune" and by[("gait", 100, 0)]["seeds"] == "report"
    for r in rows:
        assert (out / r["controller"]).is_file()
        assert r["evaluations"] == 4 * 4 and r["versions"]["task"].startswith("starman_travel-v")
        assert "gait_turns" in r["measures"] and "task_success" in r["measures"]
    before = (out / RESULTS).read_bytes()
    assert main(["study", "run", str(s), "--out", str(out), "--quiet"]) == 0
    assert (out / RESULTS).read_bytes() == before


def test_configs_runs_a_subset_whose_rows_a_full_run_completes(tmp_path, capsys):
    out, full = tmp_path / "out", tmp_path / "full"
    assert main(["study", "run", str(spec(tmp_path)), "--out", str(out), "--quiet",
                 "--configs", "nope"]) == 2
    assert "no configuration nope" in capsys.readouterr().err and not out.exists()
    assert main(["study", "run", str(spec(tmp_path)), "--out", str(out), "--quiet",
                 "--configs", "gait"]) == 0
    assert {r["config"] for r in read_rows(out)} == {"gait"}
    assert main(["study", "run", str(spec(tmp_path)), "--out", str(out), "--quiet"]) == 0
    assert main(["study", "run", str(spec(tmp_path)), "--out", str(full), "--quiet"]) == 0
    assert untimed(read_rows(out)) == untimed(read_rows(full))


def test_a_changed_spec_is_refused_in_an_existing_directory(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["study", "run", str(spec(tmp_path)), "--out", str(out), "--quiet",
                 "--seeds", "0"]) == 0
    before = (out / RESULTS).read_bytes()
    assert main(["study", "run", str(spec(tmp_path, gens=4, name="b.toml")), "--out", str(out),
                 "--quiet"]) == 2
    assert "another spec" in capsys.readouterr().err
    assert (out / RESULTS).read_bytes() == before


def test_tables_rejudge_from_kept_measures_and_report_only_report_seeds(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["study", "run", str(spec(tmp_path)), "--out", str(out), "--quiet"]) == 0
    sp, rows = load_directory(out)
    rep = summarize(sp, rows, "report")
    assert [r["runs"] for r in rep["rows"]] == [1, 1]          # one seed; best of the 2 starts
    assert all("interval95" in r for r in rep["rows"] if r["tested"])
    tune = summarize(sp, rows, "tune")
    assert not any("interval95" in r for r in tune["rows"])
    both = summarize(sp, rows, "report", judge="task")          # the gait rows under the task test
    gait_row = next(r for r in rows if r["config"] == "gait" and r["seed"] == 100)
    assert both["rows"][0]["success"] == int(gait_row["measures"]["task_success"])
    capsys.readouterr()
    assert main(["study", "table", str(out), "--judge", "gait", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert {r["judge"] for r in doc["rows"]} == {"gait"}
    assert main(["study", "table", str(out), "--judge", "nope"]) == 2


def test_a_table_caption_names_the_seeds_its_rows_cover():
    from gpmotion.study.table import markdown
    row = {"label": "c", "runs": 2, "evaluations": [10], "counts": {"solved": 2},
           "success": 2, "tested": 2, "expect": [], "interval95": [0.34, 1.0],
           "seeds": [100, 101], "cost_median": 0.1, "cost_q25": 0.1, "cost_q75": 0.1}
    summary = {"study": "s", "seeds": "report", "seed_list": [100, 101, 102, 103],
               "quick": False, "rows": [row]}
    assert markdown(summary).rstrip().endswith("report seeds 100–101 (2 of the spec's 4: 100–103)")
    summary["seed_list"] = [100, 101]
    assert markdown(summary).rstrip().endswith("report seeds 100–101")


def test_wilson_interval():
    lo, hi = wilson(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)
    assert wilson(0, 10)[0] == 0.0 and wilson(10, 10)[1] == pytest.approx(1.0)


def test_a_torn_last_row_is_dropped_and_made_again(tmp_path):
    s, out = spec(tmp_path), tmp_path / "out"
    assert main(["study", "run", str(s), "--out", str(out), "--quiet", "--seeds", "0"]) == 0
    whole = (out / RESULTS).read_bytes()
    lines = whole.splitlines(keepends=True)
    (out / RESULTS).write_bytes(b"".join(lines[:-1]) + lines[-1][:25])   # killed mid-write
    assert len(read_rows(out)) == len(lines) - 1                          # readers skip it
    assert main(["study", "run", str(s), "--out", str(out), "--quiet", "--seeds", "0"]) == 0
    assert untimed(read_rows(out)) == untimed([json.loads(x) for x in lines])


def _gpm(*args):
    return subprocess.Popen([sys.executable, "-m", "gpmotion.cli", *map(str, args)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "GPMOTION_CHECKPOINT_EVERY": "0.05"})


def test_sigkill_at_any_moment_then_rerun_gives_the_uninterrupted_rows(tmp_path):
    s = spec(tmp_path, gens=150)
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    assert main(["study", "run", str(s), "--out", str(ref), "--quiet"]) == 0
    kills, delays = 0, [0.8, 1.7, 0.4, 2.5, 1.1, 0.6, 3.0, 1.4]
    for delay in delays:                     # each invocation killed after `delay` seconds
        proc = _gpm("study", "run", s, "--out", killed, "--quiet")
        try:
            proc.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            kills += 1
        if proc.returncode == 0:
            break
    assert kills >= 2, "the study finished before it could be killed twice"
    assert main(["study", "run", str(s), "--out", str(killed), "--quiet"]) == 0
    assert untimed(read_rows(killed)) == untimed(read_rows(ref))
    assert controllers(killed) == controllers(ref)


def test_two_workers_give_the_serial_rows(tmp_path):
    s = spec(tmp_path)
    assert main(["study", "run", str(s), "--out", str(tmp_path / "serial"), "--quiet"]) == 0
    assert main(["study", "run", str(s), "--out", str(tmp_path / "pool"), "--quiet",
                 "--workers", "2"]) == 0
    assert untimed(read_rows(tmp_path / "pool")) == untimed(read_rows(tmp_path / "serial"))
    assert controllers(tmp_path / "pool") == controllers(tmp_path / "serial")


def test_sigterm_checkpoints_and_names_the_study_command(tmp_path):
    s, out = spec(tmp_path, gens=400), tmp_path / "out"
    proc = _gpm("study", "run", s, "--out", out, "--quiet")
    t0 = time.time()
    while not list(out.glob("runs/*/checkpoint.json")):
        assert time.time() - t0 < 300, "no search ever checkpointed"
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=300)
    if proc.returncode == 0:
        pytest.skip("the study finished before the signal arrived")
    assert proc.returncode == 143 and "gpmotion study run" in err, err
    assert main(["study", "run", str(s), "--out", str(out), "--quiet"]) == 0


def _children(pid: int) -> set[int]:
    kids = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    return {int(k) for k in kids}


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"
    except FileNotFoundError:
        return False


def test_sigterm_with_workers_stops_them_and_the_rerun_completes(tmp_path):
    s, out = spec(tmp_path, gens=400), tmp_path / "out"
    proc = _gpm("study", "run", s, "--out", out, "--quiet", "--workers", "2")
    t0 = time.time()
    while len(list(out.glob("runs/*/checkpoint.json"))) < 2:
        assert time.time() - t0 < 300, "the workers never checkpointed"
        time.sleep(0.05)
    kids = _children(proc.pid)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 143 and "gpmotion study run" in err, err
    assert "Traceback" not in err, err
    t0 = time.time()
    while any(_alive(k) for k in kids):                 # no search left running unseen
        assert time.time() - t0 < 60, "a worker outlived its study"
        time.sleep(0.1)
    assert main(["study", "run", str(s), "--out", str(out), "--quiet"]) == 0
    assert len(read_rows(out)) == 6                     # 2 seeds × (1 + 2 starts)
