"""benchmarks/creatures_3d.py: a bad run path is one line and exit 2, not a traceback."""
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _bench():
    spec = importlib.util.spec_from_file_location("creatures_3d", ROOT / "benchmarks" / "creatures_3d.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_steps_of_a_missing_run_is_one_line_and_exit_2(tmp_path, capsys):
    missing = tmp_path / "nowhere" / "best.json"
    assert _bench().main(["steps", "--task", "bob_walk-v3", str(missing)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(missing) in err[0] and "Traceback" not in err[0]


def test_steps_of_a_file_that_is_not_a_record_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "best.json"
    bad.write_text("{not json")
    assert _bench().main(["steps", "--task", "bob_walk-v3", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(bad) in err[0]
