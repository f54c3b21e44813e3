"""Run directories: one writer, no symlink followed, records bound to one run,
hand-edited inputs refused with one line."""
import errno
import json
import os
import shutil

import pytest

from gpmotion import records, rundir
from gpmotion.cli import main
from gpmotion.records import FormatError, RunDirError
from gpmotion.records import display_path
from gpmotion.rundir import RunDir
from tests.cli_checks import refused, refused_before_the_directory

GP = ["--param", "seconds=0.3", "--population", "8", "--generations", "3", "--quiet",
      "--no-artifacts"]
SERIAL = ["--controller", "bsr-time", "--param", "seconds=0.3", "--working", "4",
          "--generations", "12", "--quiet", "--no-artifacts"]


# ------------------------------------------------------------------ the lock

def test_second_writer_in_the_same_process_is_refused(tmp_path):
    d = tmp_path / "r"
    first = RunDir.create(d)
    with pytest.raises(RunDirError, match="in use by another gpmotion process"):
        RunDir.create(d, resume=True)
    with pytest.raises(RunDirError, match="in use"):
        RunDir.create(d, force=True)            # would move a live run aside
    first.log_row({"generation": 0})
    first.close()
    again = RunDir.create(d, resume=True)       # released: the next writer gets it
    again.close()


def test_writes_go_through_the_locked_directory_not_its_name(tmp_path):
    d = tmp_path / "r"
    rd = RunDir.create(d)
    os.rename(d, tmp_path / "moved")
    d.mkdir()                                   # a newcomer at the old name
    rd.write_best({"x": 1})
    rd.log_row({"generation": 0})
    rd.close()
    assert sorted(p.name for p in d.iterdir()) == []
    assert (tmp_path / "moved" / "best.json").exists()
    assert (tmp_path / "moved" / "log.csv").exists()


def test_temp_files_of_a_killed_writer_are_removed_by_the_next(tmp_path):
    d = tmp_path / "r"
    RunDir.create(d).close()
    (d / ".checkpoint.json.123.abcd1234.tmp").write_text("x" * 1000)
    (d / "keep.txt").write_text("mine")
    RunDir.create(d, resume=True).close()
    assert sorted(p.name for p in d.iterdir()) == [".lock", "keep.txt"]


# ------------------------------------------------------------------ symlinks

@pytest.fixture
def outside(tmp_path):
    f = tmp_path / "outside.txt"
    f.write_text("x" * 42)
    return f


def planted(tmp_path, outside, name):
    """A new run directory (and its path) whose file ``name`` is a symbolic link to ``outside``."""
    d = tmp_path / "r"
    rd = RunDir.create(d)
    os.symlink(outside, d / name)
    return rd, d


def test_planted_lock_symlink_is_not_followed(tmp_path, outside):
    d = tmp_path / "r"
    d.mkdir()
    os.symlink(outside, d / ".lock")
    with pytest.raises(RunDirError, match="symbolic link"):
        RunDir.create(d, resume=True)
    assert outside.read_text() == "x" * 42


def test_write_probe_truncates_nothing(tmp_path, outside):
    """A planted `.write-test.PID` link let the probe empty a file outside."""
    d = tmp_path / "r"
    d.mkdir()
    os.symlink(outside, d / f".write-test.{os.getpid()}")
    RunDir.create(d, resume=True).close()
    assert outside.read_text() == "x" * 42


def test_planted_log_symlink_is_neither_appended_nor_trimmed(tmp_path, outside):
    rd, d = planted(tmp_path, outside, "log.csv")
    with pytest.raises(OSError, match="symbolic link"):
        rd.log_row({"generation": 0})
    with pytest.raises(FormatError, match="symbolic link"):
        rd.trim_log(0)
    with pytest.raises(FormatError, match="symbolic link"):
        rd.read_log()
    os.unlink(d / "log.csv")
    os.link(outside, d / "log.csv")             # a hard link is refused too
    with pytest.raises(RunDirError, match="link"):
        rd.log_row({"generation": 0})
    rd.close()
    assert outside.read_text() == "x" * 42


def test_json_records_replace_a_symlink_never_its_target(tmp_path, outside):
    rd, d = planted(tmp_path, outside, "checkpoint.json")
    with pytest.raises(FormatError, match="symbolic link"):
        rd.load_checkpoint()
    rd.save_checkpoint({"generation": 1})
    rd.close()
    assert outside.read_text() == "x" * 42
    assert not (d / "checkpoint.json").is_symlink()


def test_run_refuses_a_planted_config_symlink(tmp_path, outside, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), *GP]) == 0
    os.replace(out / "config.json", tmp_path / "config.json")
    os.symlink(tmp_path / "config.json", out / "config.json")
    refused(capsys, ["resume", str(out), "--quiet"], "symbolic link")


# ------------------------------------------------------------------ disk full

def test_disk_full_names_the_file(tmp_path, monkeypatch):
    rd = RunDir.create(tmp_path / "r")

    def full(*a):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(rundir.os, "write", full)
    with pytest.raises(OSError, match=r"log\.csv.*No space"):
        rd.log_row({"generation": 0})
    monkeypatch.undo()
    monkeypatch.setattr(records.os, "fsync", full)
    with pytest.raises(OSError, match=r"checkpoint\.json.*No space") as err:
        rd.save_checkpoint({"generation": 1})
    assert "/proc/self" not in str(err.value)
    monkeypatch.undo()
    rd.close()
    assert [p for p in (tmp_path / "r").iterdir() if p.name.endswith(".tmp")] == []


def test_display_path_hides_the_descriptor(tmp_path):
    rd = RunDir.create(tmp_path / "r")
    assert display_path(rd.file("best.json")) == tmp_path / "r" / "best.json"
    rd.close()


# ------------------------------------------------------------------ identity

@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """Two finished tiny GP runs with different seeds."""
    base = tmp_path_factory.mktemp("runs")
    for seed in ("0", "1"):
        assert main(["run", "lamp_hop", "--out", str(base / seed), "--seed", seed, *GP]) == 0
    return base


def _copy(finished, tmp_path, name="0"):
    dst = tmp_path / "run"
    shutil.copytree(finished / name, dst)
    return dst


def _edit(path, fn):
    doc = json.loads(path.read_text())
    fn(doc)
    path.write_text(json.dumps(doc))


def test_checkpoint_of_another_run_is_refused(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    (run / "best.json").unlink()
    shutil.copy(finished / "1" / "checkpoint.json", run / "checkpoint.json")
    refused(capsys, ["resume", str(run), "--quiet"], "another run")


def test_edited_config_is_refused(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    _edit(run / "config.json", lambda d: d["run"]["search"].update(population=10))
    refused(capsys, ["resume", str(run), "--quiet"], "config.json")


def test_checkpoint_search_settings_never_override_config(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    _edit(run / "checkpoint.json", lambda d: d["search"]["config"].update(population=12))
    refused(capsys, ["resume", str(run), "--quiet"], "population")


@pytest.mark.parametrize("value", [-5, 10**400, "7", 2.5, None])
def test_absurd_evaluations_are_refused_and_the_log_kept(finished, tmp_path, capsys, value):
    run = _copy(finished, tmp_path)
    log = (run / "log.csv").read_text()
    text = (run / "checkpoint.json").read_text()
    doc = json.loads(text)
    doc["evaluations"] = value
    raw = json.dumps(doc).replace(str(10**400), "1e400")    # a float literal JSON turns into inf
    (run / "checkpoint.json").write_text(raw)
    refused(capsys, ["resume", str(run), "--quiet"], "evaluations")
    assert (run / "log.csv").read_text() == log


@pytest.mark.parametrize("edit, needle", [
    (lambda d: d["run"].update(params=["seconds", 0.3]), "run.params"),
    (lambda d: d["run"]["search"].update(bogus=1), "bogus"),
    (lambda d: d["run"].update(search=[1, 2]), "run.search"),
    (lambda d: d.pop("run"), "no 'run' section"),
    (lambda d: d["run"].update(seed="0"), "run.seed"),
    (lambda d: d["run"].update(seed=True), "run.seed"),
    (lambda d: d["run"].update(zzz=1), "unknown key"),
    (lambda d: d.pop("run_id"), "run_id"),
    (lambda d: d["run"]["search"].update(population="many"), "population"),
])
def test_hand_edited_config_gives_one_line(finished, tmp_path, capsys, edit, needle):
    run = _copy(finished, tmp_path)
    _edit(run / "config.json", edit)
    refused(capsys, ["resume", str(run), "--quiet"], needle)


# ------------------------------------------------------------------ bad input first

def test_series_with_a_bad_second_value_writes_nothing(tmp_path, capsys):
    out = tmp_path / "s"
    refused_before_the_directory(capsys, ["run", "lamp_hop", "--out", str(out), "--param", "distance=0.3,99",
                                          *GP[2:]], out, "distance")


@pytest.mark.parametrize("param, needle", [("w_max_height=1e308", "w_max_height"),
                                           ("seconds=1e-9", "seconds")])
def test_unbounded_task_parameters_refused(tmp_path, capsys, param, needle):
    out = tmp_path / "o"
    refused_before_the_directory(capsys, ["run", "starman_travel", "--controller", "bsr-time",
                                          "--param", param, "--out", str(out)], out, needle)


def test_costs_stay_finite_under_a_huge_weight(tmp_path):
    out = tmp_path / "o"
    assert main(["run", "starman_travel", *SERIAL, "--param", "w_max_height=-1e6",
                 "--out", str(out)]) == 0
    assert json.loads((out / "checkpoint.json").read_text())["format"] == "gpmotion-checkpoint"


def test_population_2_runs(tmp_path):
    out = tmp_path / "o"
    assert main(["run", "lamp_hop", "--out", str(out), "--population", "2",
                 "--param", "seconds=0.3", "--generations", "2", "--quiet",
                 "--no-artifacts"]) == 0


def test_absurd_rule_count_refused_before_the_directory(tmp_path, capsys):
    out = tmp_path / "o"
    refused_before_the_directory(capsys, ["run", "starman_travel", "--controller", "bsr-time",
                                          "--rules", "10000000", "--out", str(out)], out, "--rules")


def test_best_json_of_a_diverged_run_says_so(tmp_path, monkeypatch):
    import gpmotion.replay as replay

    real = replay.replay_genome

    def diverged(*a, **k):                  # as if every step of the best had blown up
        traj, costs, measures, ok = real(*a, **k)
        traj.diverged[:] = True
        return traj, costs * 0 + 1e6, measures, ok & False
    monkeypatch.setattr(replay, "replay_genome", diverged)
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), *GP]) == 0
    rec = json.loads((out / "best.json").read_text())
    assert rec["diverged"] is True and rec["success"] is False
    monkeypatch.undo()
    out2 = tmp_path / "r2"
    assert main(["run", "lamp_hop", "--out", str(out2), *GP]) == 0
    assert json.loads((out2 / "best.json").read_text())["diverged"] is False
