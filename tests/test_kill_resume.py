"""Real processes: a run killed at any instant resumes to the uninterrupted
result (GP and the serial search), one writer per run directory, SIGTERM
checkpoints like Ctrl-C, and `run --resume`/`resume` never silently change a run."""
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpmotion.cli import main
from gpmotion.rundir import RunDir

SERIAL = ["--controller", "bsr-time", "--param", "seconds=0.3", "--working", "4", "--quiet",
          "--no-artifacts"]
GP = ["--param", "seconds=0.3", "--population", "8", "--quiet", "--no-artifacts"]


def gpm(*args, env=None):
    return subprocess.Popen([sys.executable, "-m", "gpmotion.cli", *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, **(env or {})})


def wait_for(path: Path, timeout=180):
    t0 = time.time()
    while not path.exists():
        assert time.time() - t0 < timeout, f"{path} never appeared"
        time.sleep(0.01)


def log_without_time(path):
    rows = [r.split(",") for r in Path(path).read_text().splitlines()]
    keep = [i for i, name in enumerate(rows[0]) if name not in ("evals_per_s", "recent_evals_per_s", "elapsed_s")]
    return [[r[i] for i in keep] for r in rows]


def best(run):
    b = json.loads((run / "best.json").read_text())
    return b["genome"], b["cost"]


def test_serial_search_killed_resumes_to_the_uninterrupted_result(tmp_path):
    args = ["run", "starman_travel", *SERIAL, "--generations", "400"]
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    assert main([*args, "--out", str(ref)]) == 0
    proc = gpm(*args, "--out", killed, env={"GPMOTION_CHECKPOINT_EVERY": "0.05"})
    wait_for(killed / "checkpoint.json")
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (killed / "best.json").exists(), "the run ended before the kill"
    rows = len((killed / "log.csv").read_text().splitlines()) - 1
    assert 0 < rows < 400
    assert main(["resume", str(killed), "--quiet"]) == 0      # the kernel freed the lock
    assert best(ref) == best(killed)
    assert log_without_time(ref / "log.csv") == log_without_time(killed / "log.csv")
    assert json.loads((ref / "checkpoint.json").read_text())["search"] == \
        json.loads((killed / "checkpoint.json").read_text())["search"]


def test_kill_between_log_rows_and_first_checkpoint_leaves_no_duplicate(tmp_path, monkeypatch):
    """A kill after the log rows are on disk and before the first checkpoint."""
    args = ["run", "lamp_hop", *GP, "--generations", "3"]
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    assert main([*args, "--out", str(ref)]) == 0

    class Killed(BaseException):
        pass

    def die(self, state):
        raise Killed()
    monkeypatch.setattr(RunDir, "save_checkpoint", die)
    with pytest.raises(Killed):
        main([*args, "--out", str(killed)])
    monkeypatch.undo()
    assert (killed / "log.csv").exists() and not (killed / "checkpoint.json").exists()
    assert main(["resume", str(killed), "--quiet"]) == 0
    assert log_without_time(ref / "log.csv") == log_without_time(killed / "log.csv")
    assert best(ref) == best(killed)


def test_one_writer_per_run_directory_and_sigterm_checkpoints(tmp_path):
    out = tmp_path / "live"
    live = gpm("run", "lamp_hop", *GP, "--generations", "400", "--out", out,
               env={"GPMOTION_CHECKPOINT_EVERY": "0"})
    wait_for(out / "checkpoint.json")
    for argv in (["resume", out],
                 ["run", "lamp_hop", *GP, "--generations", "400", "--out", out, "--resume"],
                 ["run", "lamp_hop", *GP, "--generations", "400", "--out", out, "--force"]):
        p = gpm(*argv)
        _, err = p.communicate(timeout=300)
        assert p.returncode == 2, err
        assert err.strip().startswith("gpmotion: error:") and "in use" in err
        assert "\n" not in err.strip()
    assert live.poll() is None, "the live run must not be disturbed"
    live.send_signal(signal.SIGTERM)
    _, err = live.communicate(timeout=300)
    assert live.returncode == 143 and "gpmotion resume" in err
    gens = [int(r[0]) for r in log_without_time(out / "log.csv")[1:]]
    assert gens == list(range(len(gens))) and gens
    ck = json.loads((out / "checkpoint.json").read_text())
    assert ck["log_rows"] == len(gens)
    assert not list(out.glob("*.bak-*")) and not list(tmp_path.glob("live.bak-*"))
    RunDir.create(out, resume=True).close()     # free again


def test_two_simultaneous_starts_one_wins(tmp_path):
    out = tmp_path / "r"
    procs = [gpm("run", "lamp_hop", *GP, "--generations", "3", "--out", out) for _ in range(2)]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    codes = sorted(rc for rc, _ in results)
    assert codes == [0, 2], results
    err = next(e for rc, e in results if rc == 2)
    assert "in use" in err or "not empty" in err
    gens = [int(r[0]) for r in log_without_time(out / "log.csv")[1:]]
    assert gens == [0, 1, 2]


# ------------------------------------------------- finished runs, extended

@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    base = tmp_path_factory.mktemp("done")
    assert main(["run", "lamp_hop", *GP, "--generations", "3", "--out", str(base / "gp")]) == 0
    assert main(["run", "starman_travel", *SERIAL, "--generations", "10",
                 "--out", str(base / "serial")]) == 0
    return base


@pytest.mark.parametrize("extra, needle", [
    (["--generations", "5"], "--generations differs"),
    (["--param", "seconds=0.4"], "--param seconds differs"),
    (["--population", "10"], "--population differs"),
    (["--seed", "3"], "--seed differs"),
])
def test_run_resume_with_other_settings_is_refused(finished, tmp_path, capsys, extra, needle):
    run = tmp_path / "gp"
    shutil.copytree(finished / "gp", run)
    argv = ["run", "lamp_hop", *GP, "--generations", "3", "--out", str(run), "--resume"]
    for i, a in enumerate(extra[::2]):
        j = argv.index(a) if a in argv else None
        if j is not None:
            argv[j + 1] = extra[2 * i + 1]
        else:
            argv += [a, extra[2 * i + 1]]
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and needle in err and "\n" not in err
    if "generations" in needle:
        assert "--extend-generations" in err


def test_run_resume_with_the_same_settings_is_fine(finished, tmp_path):
    run = tmp_path / "gp"
    shutil.copytree(finished / "gp", run)
    assert main(["run", "lamp_hop", *GP, "--generations", "3", "--out", str(run),
                 "--resume"]) == 0


@pytest.mark.parametrize("kind, n0", [("gp", 3), ("serial", 10)])
def test_extend_generations_is_explicit_and_deterministic(finished, tmp_path, kind, n0):
    a, b = tmp_path / "a", tmp_path / "b"
    for d in (a, b):
        shutil.copytree(finished / kind, d)
        assert main(["resume", str(d), "--extend-generations", "2", "--quiet"]) == 0
    assert best(a) == best(b)
    gens = [int(r[0]) for r in log_without_time(a / "log.csv")[1:]]
    last = n0 + 1 if kind == "gp" else n0 + 2   # serial: row 0 is the initial working set
    assert gens == list(range(last + 1))
    assert log_without_time(a / "log.csv") == log_without_time(b / "log.csv")
    doc = json.loads((a / "config.json").read_text())
    assert doc["extended_generations"] == n0 + 2
    ck = json.loads((a / "checkpoint.json").read_text())
    assert ck["search"]["generation"] == n0 + 2
    # the extension is recorded: a plain resume of the extended run has nothing left to do
    assert main(["resume", str(a), "--quiet"]) == 0
    assert best(a) == best(b)


def test_resume_of_a_series_folder_points_at_its_runs(tmp_path, capsys):
    out = tmp_path / "series"
    assert main(["run", "lamp_hop", *GP, "--generations", "1", "--param", "distance=0.3,0.4",
                 "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["resume", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "series" in err and "distance=0.3" in err and "distance=0.4" in err
