"""Messages that name what happened: a lost scheduler is not reported as "no
workers", and a stopped run's resume hint names where the run directory is now."""
import os
import signal
import threading

from gpmotion import evaluators
from gpmotion.cli import main
from gpmotion.rundir import RunDir


class _GoneClient:
    status = "connecting"                  # the scheduler went away: reconnecting

    def scheduler_info(self):
        return {"workers": {}}             # stale: says nothing about the workers


def test_no_workers_message_is_not_said_when_the_scheduler_is_gone(capsys):
    ev = evaluators.DaskEvaluator.__new__(evaluators.DaskEvaluator)
    ev._client, ev._idle_said, ev.scheduler = _GoneClient(), False, "tcp://127.0.0.1:1"
    ev._report_idle()
    assert "no Dask workers" not in capsys.readouterr().err


def test_rundir_knows_its_current_path(tmp_path):
    rd = RunDir.create(tmp_path / "a")
    os.rename(tmp_path / "a", tmp_path / "b")
    assert rd.current_path == tmp_path / "b"
    rd.close()


def test_sigterm_hint_names_the_renamed_directory(tmp_path, capsys):
    out, moved = tmp_path / "a", tmp_path / "b"

    def rename_then_term():
        import time
        while not (out / "checkpoint.json").exists():
            time.sleep(0.01)
        os.rename(out, moved)
        os.kill(os.getpid(), signal.SIGTERM)
    t = threading.Thread(target=rename_then_term, daemon=True)
    os.environ["GPMOTION_CHECKPOINT_EVERY"] = "0"
    try:
        t.start()
        code = main(["run", "lamp_hop", "--param", "seconds=0.3", "--population", "8",
                     "--generations", "100000", "--quiet", "--no-artifacts", "--out", str(out)])
    finally:
        del os.environ["GPMOTION_CHECKPOINT_EVERY"]
    t.join()
    err = capsys.readouterr().err
    assert code == 143
    assert f"gpmotion resume {moved}" in err, err
