"""What a run prints: banner (actuation, phase schedule), ETA, best under final weights."""
import numpy as np

from gpmotion.cli import main
from gpmotion.evaluation import Evaluation
from gpmotion.run import Progress


def ev(n=4):
    return Evaluation(np.arange(n, dtype=float), np.zeros(n, bool), np.zeros(n, bool), {})


def test_first_eta_waits_for_a_measured_pace():
    p = Progress(4000)
    assert p.eta(1, 100.0) == "eta …"          # the first generation includes compiling
    assert p.eta(3, 100.1) == "eta …"
    assert p.eta(4, 101.0) == "eta …"          # 3 generations but under 2 s
    assert p.eta(11, 102.0) == f"eta {2.0 / 10 * 3989:,.0f}s"


def test_progress_line_shows_the_log_rows_bests_by_their_names(capsys):
    p = Progress(10, every=0)
    p.update(1, ev(), 0.5, {"best_so_far": 0.25, "gen_median": 1.5, "best_final": 4.25})
    p.update(2, ev(), 0.4, {"best_so_far": 0.2, "gen_median": 1.5, "best_final": ""})
    err = capsys.readouterr().err.splitlines()
    assert "best so far 0.2500 (median 1.5000)  best final 4.2500" in err[0]
    assert "best so far 0.2000 (median 1.5000)  best final –" in err[1]


def test_banner_names_actuation_and_phase_schedule(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--param", "seconds=0.3",
                 "--population", "8", "--generations", "11", "--no-artifacts"]) == 0
    err = capsys.readouterr().err
    assert "actuation: pd, gp's default · trees give target angles ·" in err
    assert "style terms phase in over generations: late 2→5" in err
    assert "eta 116" not in err
    assert main(["run", "starman_travel", "--controller", "bsr-time", "--actuation", "pd",
                 "--out", str(tmp_path / "s"), "--param", "seconds=0.3", "--working", "2",
                 "--generations", "3", "--no-artifacts"]) == 0
    err = capsys.readouterr().err
    assert "actuation: pd ·" in err and "all at full weight" in err


def test_banner_names_a_figure_variant_not_its_whole_spec(tmp_path, capsys):
    assert main(["run", "starman_travel", "--controller", "bsr-time", "--figure", "starman_auslander",
                 "--out", str(tmp_path / "s"), "--param", "seconds=0.3", "--working", "2",
                 "--generations", "1", "--no-artifacts"]) == 0
    head = capsys.readouterr().err.splitlines()[0]
    assert "'figure': 'starman_auslander (variant)'" in head
    assert "segment" not in head and len(head) < 200
