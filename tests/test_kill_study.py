"""`gpmotion study run` killed with SIGKILL at a file-system event, then run
again, gives the rows and controllers of a study never interrupted (wall and
CPU times aside).  The events: the study directory's record written (no search
yet), a search's config.json written (before its first checkpoint), its first
checkpoint, the first controller written (its ledger row comes after it), the
first row.  Each kill lands while the study still has jobs to do."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpmotion.cli import main
from gpmotion.study.ledger import RESULTS, read_rows
from tests.test_study_run import controllers, spec, untimed

GENS = 40


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    s = spec(d, gens=GENS)
    assert main(["study", "run", str(s), "--out", str(d / "out"), "--quiet"]) == 0
    return s, d / "out"


def _lines(path: Path) -> int:
    return path.read_bytes().count(b"\n") if path.is_file() else 0


EVENTS = {
    "study-record": lambda out: (out / "study.json").is_file(),
    "search-config": lambda out: any(out.glob("runs/*/config.json")),
    "first-checkpoint": lambda out: any(out.glob("runs/*/checkpoint.json")),
    "first-controller": lambda out: any(out.glob("controllers/*")),
    "first-row": lambda out: _lines(out / RESULTS) >= 1,
}


def _kill_at(event, argv, out: Path, timeout=300):
    proc = subprocess.Popen([sys.executable, "-m", "gpmotion", *map(str, argv)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env={**os.environ, "GPMOTION_CHECKPOINT_EVERY": "0.05"})
    try:
        t0 = time.time()
        while not EVENTS[event](out):
            assert proc.poll() is None, f"ended before {event}: {proc.stderr.read()[-500:]}"
            assert time.time() - t0 < timeout, f"{event} never happened"
            time.sleep(0.001)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the study finished before the kill"


@pytest.mark.parametrize("event", list(EVENTS))
def test_study_sigkilled_at_an_event_reruns_to_the_uninterrupted_rows(reference, tmp_path,
                                                                      event):
    s, ref = reference
    out = tmp_path / "out"
    argv = ["study", "run", s, "--out", out, "--quiet"]
    _kill_at(event, argv, out)
    assert len(read_rows(out)) < len(read_rows(ref))
    assert main([str(a) for a in argv]) == 0
    assert untimed(read_rows(out)) == untimed(read_rows(ref))
    assert controllers(out) == controllers(ref)
    assert not list(out.rglob("*.tmp")), "temporary files left behind"


def test_a_controller_write_cut_by_a_kill_leaves_no_temp_file(reference, tmp_path):
    """A kill between the temp file of controllers/NAME.json and its rename."""
    s, ref = reference
    out = tmp_path / "out"
    argv = ["study", "run", str(s), "--out", str(out), "--quiet", "--seeds", "0"]
    assert main(argv) == 0
    temp = out / "controllers" / ".task-seed100.json.4242.0a1b2c3d.tmp"
    temp.write_text('{"half": ')
    assert main(argv[:-2]) == 0
    assert not temp.exists()
    assert controllers(out) == controllers(ref)


def test_a_search_killed_while_writing_its_config_is_begun_again_in_place(reference, tmp_path):
    """Only the lock and a temp file of config.json: no run yet, nothing to move aside."""
    s, ref = reference
    out = tmp_path / "out"
    argv = ["study", "run", str(s), "--out", str(out), "--quiet"]
    assert main(argv + ["--seeds", "0"]) == 0
    run = out / "runs" / "task-seed100-start0"
    run.mkdir()
    (run / ".lock").write_text("4242\n")
    (run / ".config.json.4242.0a1b2c3d.tmp").write_text('{"half": ')
    assert main(argv) == 0
    assert not list(out.rglob("*.tmp")) and not list((out / "runs").glob("*.bak-*"))
    assert untimed(read_rows(out)) == untimed(read_rows(ref))
