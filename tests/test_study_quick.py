"""Every shipped study in its --quick form (what CI runs): it runs end to end
into a fresh directory, gives one row per configuration x seed x start of its
quick spec, and tables one line per configuration.  (auslander-2d has its own,
fuller end-to-end test in test_study_shipped.py.)"""
import json

import pytest

from gpmotion.cli import main
from gpmotion.study import SHIPPED
from gpmotion.study.ledger import read_rows
from gpmotion.study.spec import load

STUDIES = sorted(p.name for p in SHIPPED.iterdir()
                 if (p / "spec.toml").is_file() and p.name != "auslander-2d")


def test_the_list_covers_every_shipped_study():
    assert {"creatures", "gp-vs-bsr", "gritz-hahn-lamp", "herman", "limbo-series",
            "robustness"} <= set(STUDIES)


@pytest.mark.parametrize("name", STUDIES)
def test_a_shipped_study_runs_in_its_quick_form(name, tmp_path, capsys):
    out = tmp_path / name
    assert main(["study", "run", name, "--quick", "--out", str(out), "--quiet"]) == 0
    spec = load(SHIPPED / name / "spec.toml", quick=True)
    seeds = spec.seeds
    want = {(c.name, s, k) for c in spec.configurations.values() for s in seeds
            for k in range(c.starts)}
    assert {(r["config"], r["seed"], r["start"]) for r in read_rows(out)} == want
    capsys.readouterr()
    assert main(["study", "table", str(out), "--seeds", "tune", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["quick"] and [r["configuration"] for r in doc["rows"]] == list(spec.configurations)
