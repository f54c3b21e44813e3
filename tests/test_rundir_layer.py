"""One run-directory layer for every writer: the lock is on the directory, a FIFO
never blocks a reader, a resume checks everything before it changes anything,
and every refusal leaves every file byte-identical."""
import contextlib
import hashlib
import json
import os
import shutil
import signal
from pathlib import Path

import pytest

from gpmotion.cli import main
from gpmotion.records import FormatError, RunDirError
from gpmotion.rundir import RunDir
from tests.cli_checks import one_line_error

GP = ["--param", "seconds=0.3", "--population", "8", "--quiet", "--no-artifacts"]


def hashes(folder: Path) -> dict:
    """Every file under ``folder`` (links as their target text) by its sha256."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_symlink():
            out[str(p)] = "link:" + os.readlink(p)
        elif p.is_file():
            out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


class Hung(BaseException):
    """Not an Exception: the CLI's error path must not turn it into an error line."""


@contextlib.contextmanager
def no_hang(seconds=60):
    """Fail (not hang) when the body blocks, e.g. on a FIFO."""
    def on_alarm(*_):
        raise Hung("blocked")
    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "done"
    assert main(["run", "lamp_hop", *GP, "--generations", "6", "--out", str(out)]) == 0
    return out


@pytest.fixture
def run_dir(finished, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(finished, d)
    return d


def refused_unchanged(capsys, argv, folder, *needles):
    before = hashes(folder)
    capsys.readouterr()
    with no_hang():
        assert main([str(a) for a in argv]) == 2
    err = one_line_error(capsys, *needles)
    assert hashes(folder) == before, "a refused operation changed a file"
    return err


def edit(path: Path, **changes):
    doc = json.loads(path.read_text())
    for k, v in changes.items():
        if v is None:
            doc.pop(k, None)
        else:
            doc[k] = v
    path.write_text(json.dumps(doc))


# ------------------------------------------------------------ 4. the lock

def test_deleting_the_lock_file_does_not_unlock(tmp_path):
    d = tmp_path / "r"
    first = RunDir.create(d)
    os.unlink(d / ".lock")
    with pytest.raises(RunDirError, match="in use"):
        RunDir.create(d, resume=True)
    first.close()
    RunDir.create(d, resume=True).close()


# ------------------------------------------------------------ 3. FIFOs never block

def _fifo(path: Path):
    if path.exists():
        path.unlink()
    os.mkfifo(path)


@pytest.mark.parametrize("name", ["config.json", "checkpoint.json", "log.csv"])
def test_resume_with_a_fifo_run_file_is_refused(run_dir, capsys, name):
    _fifo(run_dir / name)
    refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, name)


@pytest.mark.parametrize("cmd", [["replay"], ["export", "--bvh", "x.bvh"],
                                 ["render", "-o", "x.png"]])
def test_readers_of_a_fifo_best_json_are_refused(run_dir, capsys, cmd, tmp_path):
    _fifo(run_dir / "best.json")
    refused_unchanged(capsys, [cmd[0], run_dir / "best.json", *cmd[1:]], run_dir, "best.json")


def test_robustness_of_a_fifo_best_json_is_refused(run_dir, capsys):
    _fifo(run_dir / "best.json")
    refused_unchanged(capsys, ["robustness", run_dir / "best.json"], run_dir, "best.json")


def test_read_regular_refuses_fifo_and_directory(tmp_path):
    from gpmotion.records import read_regular
    os.mkfifo(tmp_path / "f")
    with no_hang(), pytest.raises(FormatError, match="not a regular file"):
        read_regular(tmp_path / "f")
    with pytest.raises(FormatError, match="a directory"):
        read_regular(tmp_path)


def test_a_directory_in_place_of_config_names_the_file(run_dir, capsys):
    (run_dir / "config.json").unlink()
    (run_dir / "config.json").mkdir()
    err = refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, "config.json")
    assert "Errno" not in err


# ------------------------------------------------------------ 2. check, then change

def test_log_rows_1_is_refused_before_the_log_is_trimmed(run_dir, capsys):
    edit(run_dir / "checkpoint.json", log_rows=1)
    refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, "log_rows")


def test_log_rows_0_is_refused(run_dir, capsys):
    edit(run_dir / "checkpoint.json", log_rows=0)
    refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, "log_rows")


def _unfinished_without_checkpoint(run_dir):
    (run_dir / "checkpoint.json").unlink()
    (run_dir / "best.json").unlink()


@pytest.mark.parametrize("key,value", [("actuation", "bogus"), ("threads", 0),
                                       ("workers", -1)])
def test_bad_config_without_checkpoint_changes_nothing(run_dir, capsys, key, value):
    _unfinished_without_checkpoint(run_dir)
    doc = json.loads((run_dir / "config.json").read_text())
    doc["run"][key] = value
    (run_dir / "config.json").write_text(json.dumps(doc))
    refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, key)


def test_population_beyond_the_cli_cap_is_refused(run_dir, capsys):
    doc = json.loads((run_dir / "config.json").read_text())
    doc["run"]["search"]["population"] = 1_000_000_000
    (run_dir / "config.json").write_text(json.dumps(doc))
    refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, "population")


def test_a_finished_run_without_its_checkpoint_is_not_restarted(run_dir, capsys):
    (run_dir / "checkpoint.json").unlink()
    refused_unchanged(capsys, ["resume", run_dir, "--quiet"], run_dir, "checkpoint")


def test_a_failed_extension_records_nothing(run_dir, capsys):
    for _ in range(3):
        refused_unchanged(capsys, ["resume", run_dir, "--quiet", "--extend-generations", "2",
                                   "--scheduler", "bogus"], run_dir, "scheduler")
    assert "extended_generations" not in json.loads((run_dir / "config.json").read_text())


def test_resume_before_the_first_checkpoint_still_works(run_dir, capsys):
    _unfinished_without_checkpoint(run_dir)
    assert main(["resume", str(run_dir), "--quiet"]) == 0
    assert (run_dir / "best.json").exists()


# ------------------------------------------------------------ 6. bounds and names

def test_plain_name():
    from gpmotion.rundir import plain_name
    assert plain_name("arm_reach-2", "study name") == "arm_reach-2"
    for bad in ("", "a/b", "..", "../../../escape", ".hidden", "x" * 300, "a\0b", "a\\b"):
        with pytest.raises(ValueError, match="study name"):
            plain_name(bad, "study name")


def test_primitives_with_an_empty_name_are_refused(capsys, tmp_path):
    assert main(["run", "lamp_hop", "--primitives", "add,,sub", "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "--primitives")
    assert not (tmp_path / "o").exists()


def test_an_empty_out_is_refused(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "lamp_hop", *GP, "--generations", "1", "--out", ""]) == 2
    one_line_error(capsys, "--out")
    assert not list(tmp_path.iterdir())


def test_figure_toml_with_an_unknown_top_level_key_is_refused(capsys, tmp_path):
    f = tmp_path / "v.toml"
    f.write_text('extends = "lamp"\ngravty = -1.0\n')
    assert main(["run", "lamp_hop", *GP, "--figure", str(f), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "gravty")


# ------------------------------------------------------------ 7. tracebacks

def test_compare_with_no_controllers(capsys, tmp_path):
    assert main(["compare", "lamp_hop", "--controllers", "", "--out", str(tmp_path / "c")]) == 2
    one_line_error(capsys, "--controllers")


def test_a_binary_figure_file(capsys, tmp_path):
    f = tmp_path / "bin.toml"
    f.write_bytes(b"\x00\x01\xff\xfe")
    assert main(["run", "lamp_hop", *GP, "--figure", str(f), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "bin.toml")
