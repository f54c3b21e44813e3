"""Process-pool workers live and die with their run: no orphans after SIGKILL/SIGTERM,
no worker tracebacks on Ctrl-C, and no more workers than the machine can use."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpmotion.evaluators import ProcessPoolEvaluator, usable_workers
from gpmotion.families import make_family
from gpmotion.task import get_task

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc (Linux)")

ARGS = ["run", "lamp_hop", "--controller", "bsr-time", "--param", "seconds=0.3", "--working", "8",
        "--generations", "400", "--workers", "2", "--no-artifacts"]


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (pool workers, the resource tracker)."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(d.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _start(tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "gpmotion.cli", *ARGS, "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120:           # pool started and a generation checkpointed
        kids = _children(proc.pid)
        if (out / "checkpoint.json").exists() and len(kids) >= 2:
            return proc, kids, out
        time.sleep(0.1)
    proc.kill()
    raise AssertionError("the run did not start its pool")


def _all_gone(pids, timeout=10.0) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if not any(_alive(p) for p in pids):
            return True
        time.sleep(0.1)
    return False


@pytest.mark.parametrize("sig", [signal.SIGKILL, pytest.param(signal.SIGTERM, marks=pytest.mark.slow)])
def test_killed_run_leaves_no_workers(tmp_path, sig):
    proc, kids, _ = _start(tmp_path)
    try:
        os.kill(proc.pid, sig)
        proc.communicate(timeout=60)
        assert _all_gone(kids), f"orphaned workers after {sig.name}: {[p for p in kids if _alive(p)]}"
    finally:
        for p in kids:
            if _alive(p):
                os.kill(p, signal.SIGKILL)


@pytest.mark.slow
def test_ctrl_c_prints_no_worker_tracebacks(tmp_path):
    proc, kids, out = _start(tmp_path)
    os.killpg(proc.pid, signal.SIGINT)            # a terminal's Ctrl-C: the whole process group
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "gpmotion resume" in err
    assert _all_gone(kids)


def test_workers_are_capped_at_the_machine(capsys):
    task = get_task("lamp_hop", seconds=0.3)
    fam = make_family("bsr-time", task)
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    ev = ProcessPoolEvaluator(task, fam, workers=1000)
    assert ev.workers == min(1000, cpus) and ev.requested_workers == 1000
    if cpus < 1000:
        assert f"--workers 1000: using {cpus}" in capsys.readouterr().err
    assert usable_workers(1000, n=3) == min(3, cpus)
    ev.close()
