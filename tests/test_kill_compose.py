"""`gpmotion compose`'s directory is a run directory like `gpmotion run`'s: one
writer, no link followed, no FIFO waited on, resumable from any instant (a real
SIGKILL included) to the uninterrupted result, one line ending in its log."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpmotion.cli import main
from gpmotion.rundir import RunDir
from tests.cli_checks import one_line_error
from tests.test_composite import write_controller
from tests.test_rundir_layer import hashes, no_hang

SEARCH = ["--arrays", "2", "--mutations", "1", "--no-artifacts", "--quiet"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("compose")
    write_controller(d / "a.json")
    write_controller(d / "b.json", family="bsr-time", seed=1)
    (d / "good.motion").write_text("phase one = dcm_x * (dtime ~= 0.5)\nphase two = max_t(cm_z)\n"
                                   "total = (1 + one) * (1 + two)\n")
    return d


def argv(files, out, rounds=3, *extra):
    return ["compose", str(files / "good.motion"), "--controllers", str(files / "a.json"),
            str(files / "b.json"), "--rounds", str(rounds), *SEARCH, "--out", str(out), *extra]


def test_a_live_compose_directory_is_locked(files, tmp_path, capsys):
    out = tmp_path / "c"
    assert main(argv(files, out, 1)) == 0
    before = hashes(out)
    holder = RunDir.create(out, resume=True)
    try:
        assert main(argv(files, out, 1, "--resume")) == 2
        one_line_error(capsys, "in use")
    finally:
        holder.close()
    assert hashes(out) == before


def test_a_log_symlink_in_a_compose_directory_is_not_followed(files, tmp_path, capsys):
    out = tmp_path / "c"
    assert main(argv(files, out, 3)) == 0
    ck = json.loads((out / "checkpoint.json").read_text())
    ck["search"]["round"] = 1               # as if killed after round 1: resume appends
    (out / "checkpoint.json").write_text(json.dumps(ck))
    outside = tmp_path / "outside.csv"
    outside.write_text((out / "log.csv").read_text())
    (out / "log.csv").unlink()
    os.symlink(outside, out / "log.csv")
    kept = outside.read_bytes()
    assert main(argv(files, out, 3, "--resume")) == 2
    one_line_error(capsys, "log.csv")
    assert outside.read_bytes() == kept


def test_compose_killed_before_its_first_checkpoint_resumes(files, tmp_path, capsys):
    ref, out = tmp_path / "ref", tmp_path / "c"
    assert main(argv(files, ref, 2)) == 0
    assert main(argv(files, out, 2)) == 0
    for name in ("checkpoint.json", "composite.json", "result.json"):
        (out / name).unlink()
    (out / ".log.csv.123.abcd.tmp").write_text("left by a killed writer")
    assert main(argv(files, out, 2, "--resume")) == 0
    assert (out / "result.json").read_bytes() == (ref / "result.json").read_bytes()
    assert (out / "log.csv").read_bytes() == (ref / "log.csv").read_bytes()
    assert not list(out.glob(".*.tmp"))


def test_compose_log_has_one_line_ending(files, tmp_path):
    out = tmp_path / "c"
    assert main(argv(files, out, 2)) == 0
    data = (out / "log.csv").read_bytes()
    assert b"\r" not in data and data.count(b"\n") == 3


def test_compose_resume_with_a_bad_checkpoint_changes_nothing(files, tmp_path, capsys):
    out = tmp_path / "c"
    assert main(argv(files, out, 3)) == 0
    ck = json.loads((out / "checkpoint.json").read_text())
    ck["search"]["round"] = 7               # rows of the log end at round 3
    (out / "checkpoint.json").write_text(json.dumps(ck))
    before = hashes(out)
    assert main(argv(files, out, 3, "--resume")) == 2
    one_line_error(capsys, "log.csv")
    assert hashes(out) == before


def test_fifo_script_and_part_are_refused(files, tmp_path, capsys):
    os.mkfifo(tmp_path / "s.motion")
    with no_hang():
        assert main(["compose", str(tmp_path / "s.motion"), "--controllers",
                     str(files / "a.json"), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "s.motion")
    os.mkfifo(tmp_path / "p.json")
    with no_hang():
        assert main(["compose", str(files / "good.motion"), "--controllers",
                     str(files / "a.json"), str(tmp_path / "p.json"),
                     "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "p.json")
    assert not (tmp_path / "o").exists()


def test_compose_negative_seed_is_one_line(files, tmp_path, capsys):
    assert main(argv(files, tmp_path / "o", 1, "--seed=-1")) == 2
    one_line_error(capsys, "--seed")


def test_compose_empty_out_is_refused(files, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv(files, "", 1)) == 2
    one_line_error(capsys, "--out")
    assert not (tmp_path / "runs").exists()


def _wait_for_line(path: Path, lines: int, proc, timeout=300):
    t0 = time.time()
    while not (path.exists() and path.read_bytes().count(b"\n") >= lines):
        assert proc.poll() is None, "finished before the kill"
        assert time.time() - t0 < timeout, f"{path} never reached {lines} lines"
        time.sleep(0.002)


@pytest.mark.parametrize("event", ["config", "log_row"])
def test_compose_sigkilled_resumes_to_the_uninterrupted_result(files, tmp_path, event):
    """SIGKILL at a file-system event: config.json written (before any round), or
    the first log row appended (checkpoint maybe not yet); resume gives the
    result of a search never interrupted."""
    ref, out = tmp_path / "ref", tmp_path / "killed"
    assert main(argv(files, ref, 40)) == 0
    proc = subprocess.Popen([sys.executable, "-m", "gpmotion.cli", *argv(files, out, 40)[0:]],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        if event == "config":
            _wait_for_line(out / "config.json", 1, proc)
        else:
            _wait_for_line(out / "log.csv", 2, proc)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait()
    assert not (out / "result.json").exists()
    assert main(argv(files, out, 40, "--resume")) == 0
    assert (out / "result.json").read_bytes() == (ref / "result.json").read_bytes()
    assert (out / "log.csv").read_bytes() == (ref / "log.csv").read_bytes()
