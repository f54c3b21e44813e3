"""The gpmotion command end to end: runs, records, replay, and bad input."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpmotion.cli import main

TINY = ["--param", "seconds=0.3", "--population", "12", "--generations", "3", "--quiet"]


def gpm(*args, cwd=None, timeout=300):
    return subprocess.run([sys.executable, "-m", "gpmotion.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=timeout)


def test_run_writes_a_complete_run_directory_and_replays(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), *TINY]) == 0
    for name in ("config.json", "log.csv", "checkpoint.json", "best.json", "curve.png",
                 "filmstrip.png", "motion.gif", "trees.png"):
        assert (out / name).stat().st_size > 0, name
    best = json.loads((out / "best.json").read_text())
    assert best["format"] == "gpmotion-best" and len(best["genome"]["trees"]) == 3
    assert {r["term"] for r in best["terms"]} >= {"distance", "late", "fell"}
    rows = (out / "log.csv").read_text().splitlines()
    assert rows[0].startswith("generation,") and len(rows) == 1 + 3
    capsys.readouterr()
    assert main(["replay", str(out)]) == 0
    text = capsys.readouterr().out
    assert "distance" in text and "(main)" in text and "cost" in text


def test_same_seed_same_run(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["run", "lamp_hop", "--out", str(a), "--no-artifacts", *TINY]) == 0
    assert main(["run", "lamp_hop", "--out", str(b), "--no-artifacts", *TINY]) == 0
    ja, jb = (json.loads((d / "best.json").read_text()) for d in (a, b))
    assert ja["genome"] == jb["genome"] and ja["cost"] == jb["cost"]


def _log_without_time(path):
    rows = [r.split(",") for r in Path(path).read_text().splitlines()]
    keep = [i for i, name in enumerate(rows[0]) if name not in ("evals_per_s", "recent_evals_per_s", "elapsed_s")]
    return [[r[i] for i in keep] for r in rows]


def test_killed_run_resumes_to_the_uninterrupted_result(tmp_path):
    args = ["--param", "seconds=0.3", "--population", "16", "--generations", "8", "--quiet",
            "--no-artifacts"]
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    assert main(["run", "lamp_hop", "--out", str(ref), *args]) == 0
    proc = subprocess.Popen([sys.executable, "-m", "gpmotion.cli", "run", "lamp_hop", "--out",
                             str(killed), *args],
                            env={**os.environ, "GPMOTION_CHECKPOINT_EVERY": "0"})
    log = killed / "log.csv"
    t0 = time.time()
    while time.time() - t0 < 120:
        if log.exists() and len(log.read_text().splitlines()) >= 4:    # header + 3 generations
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (killed / "best.json").exists()
    assert main(["resume", str(killed), "--quiet"]) == 0
    a, b = (json.loads((d / "best.json").read_text()) for d in (ref, killed))
    assert a["genome"] == b["genome"] and a["cost"] == b["cost"]
    assert _log_without_time(ref / "log.csv") == _log_without_time(killed / "log.csv")


def test_ctrl_c_checkpoints_and_exits_cleanly(tmp_path):
    out = tmp_path / "r"
    proc = subprocess.Popen([sys.executable, "-m", "gpmotion.cli", "run", "lamp_hop", "--out",
                             str(out), "--param", "seconds=0.3", "--population", "16",
                             "--generations", "200", "--quiet", "--no-artifacts"],
                            stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "GPMOTION_CHECKPOINT_EVERY": "0"})
    t0 = time.time()
    while time.time() - t0 < 120 and not (out / "checkpoint.json").exists():
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert "resume" in err
    ck = json.loads((out / "checkpoint.json").read_text())
    assert ck["format"] == "gpmotion-checkpoint"


@pytest.mark.parametrize("argv, needle", [
    (["run", "no_such_task"], "unknown task"),
    (["run", "lamp_hop", "--generations", "-3"], "--generations"),
    (["run", "lamp_hop", "--param", "seconds=nan"], "finite"),
    (["run", "lamp_hop", "--param", "distance=1e9"], "distance"),
    (["run", "lamp_hop", "--param", "bogus=1"], "unknown parameter"),
    (["run", "lamp_hop", "--controller", "nn"], "unknown controller"),
    (["render", "--figure", "nope"], "unknown figure"),
    (["run", "lamp_hop", "--p-creep", "0.5"], "p_creep"),
    (["run", "lamp_hop", "--islands", "0"], "--islands"),
    (["run", "lamp_hop", "--islands", "200"], "islands"),
    (["compare", "lamp_hop", "--controllers", "gp,xx"], "unknown"),
])
def test_bad_input_is_one_line_and_exit_2(argv, needle, tmp_path, capsys):
    assert main(argv + ["--out", str(tmp_path / "o")] if argv[0] in ("run", "compare") else argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and needle in err and "\n" not in err
    assert not (tmp_path / "o").exists()            # nothing written for a bad config


def test_existing_run_directory_is_never_overwritten(tmp_path, capsys):
    out = tmp_path / "r"
    out.mkdir()
    (out / "precious.txt").write_text("keep me")
    assert main(["run", "lamp_hop", "--out", str(out), *TINY]) == 2
    assert "--force" in capsys.readouterr().err
    assert (out / "precious.txt").read_text() == "keep me"


def _tampered(tmp_path, edit):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--no-artifacts", *TINY]) == 0
    path = out / "best.json"
    path.write_text(edit(path.read_text()))
    return path


def _edit_tree(text, tree):
    rec = json.loads(text)
    rec["genome"]["trees"][0] = tree
    return json.dumps(rec)


@pytest.mark.parametrize("edit, needle", [
    (lambda s: s[: len(s) // 2], "best.json"),
    (lambda s: _edit_tree(s, ["os.system", "px"]), "os.system"),
    (lambda s: _edit_tree(s, ["add", "px"]), "missing arguments"),
    (lambda s: _edit_tree(s, ["sin"] * 40 + ["px"]), "depth"),
    (lambda s: _edit_tree(s, ["__import__"]), "__import__"),
    (lambda s: s.replace('"gpmotion-best"', '"gpmotion-checkpoint"'), "format"),
])
def test_malformed_controller_files_are_rejected(tmp_path, capsys, edit, needle):
    path = _tampered(tmp_path, edit)
    capsys.readouterr()
    assert main(["replay", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and needle in err and "\n" not in err


def test_wrong_number_of_trees_is_rejected(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--no-artifacts", *TINY]) == 0
    rec = json.loads((out / "best.json").read_text())
    rec["genome"]["trees"] = rec["genome"]["trees"][:2]
    (out / "bad.json").write_text(json.dumps(rec))
    capsys.readouterr()
    assert main(["replay", str(out / "bad.json")]) == 2
    assert "3 actuated joints" in capsys.readouterr().err


def test_truncated_checkpoint_is_a_clear_error(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--no-artifacts", *TINY]) == 0
    ck = out / "checkpoint.json"
    ck.write_text(ck.read_text()[:100])
    capsys.readouterr()
    assert main(["resume", str(out)]) == 2
    assert "checkpoint" in capsys.readouterr().err


def test_list_and_check_cover_every_registered_thing(capsys):
    assert main(["list"]) == 0
    text = capsys.readouterr().out
    for name in ("lamp_hop", "lamp_limbo", "starman_travel", "beryl_travel", "iflte/4", "bsr-time"):
        assert name in text


def test_render_a_figure(tmp_path):
    assert main(["render", "--figure", "starman", "--seconds", "0.5", "-o", str(tmp_path / "s.png")]) == 0
    assert (tmp_path / "s.png").stat().st_size > 1000


def test_replay_reproduces_the_logged_cost_exactly(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--no-artifacts", *TINY]) == 0
    best = json.loads((out / "best.json").read_text())
    capsys.readouterr()
    assert main(["replay", str(out), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    # the last generation is scored with every style term at full weight
    assert rep["cost"] == best["cost"] == best["final_cost"]
    assert rep["success"] == best["success"]
    log = (out / "log.csv").read_text().splitlines()
    header = log[0].split(",")
    last = dict(zip(header, log[-1].split(",")))
    assert float(last["best_so_far"]) == best["cost"]
    assert {"gen_max", "recent_evals_per_s", "failed"} <= set(header)


def test_export_writes_a_bvh_an_independent_parser_reads(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--no-artifacts", *TINY]) == 0
    bvh_path = tmp_path / "lamp.bvh"
    assert main(["export", str(out), "--bvh", str(bvh_path)]) == 0
    bvh = pytest.importorskip("bvh")
    mocap = bvh.Bvh(bvh_path.read_text())
    assert mocap.nframes == 31 and len(mocap.get_joints_names()) == 4   # 0.3 s at 100 fps
