"""A shipped 2-D study end to end in its --quick form (what CI runs): every
configuration's search through the run loop, a row each, its table."""
import json

from gpmotion.cli import main
from gpmotion.study import SHIPPED
from gpmotion.study.ledger import read_rows
from gpmotion.study.spec import load


def test_auslander_2d_quick_runs_end_to_end(tmp_path, capsys):
    out = tmp_path / "a2d"
    assert main(["study", "run", "auslander-2d", "--quick", "--out", str(out), "--quiet"]) == 0
    spec = load(SHIPPED / "auslander-2d" / "spec.toml", quick=True)
    rows = read_rows(out)
    assert sorted(r["config"] for r in rows) == sorted(spec.configurations)
    assert {r["seed"] for r in rows} == set(spec.seeds) == {0}
    assert all(r["evaluations"] == 50 and r["label"] for r in rows)
    capsys.readouterr()
    assert main(["study", "table", str(out), "--seeds", "tune", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["quick"] and [r["configuration"] for r in doc["rows"]] == list(spec.configurations)
    # the quick form is another spec: never mixed into a full study's directory
    assert main(["study", "run", "auslander-2d", "--out", str(out), "--seeds", "0"]) == 2
