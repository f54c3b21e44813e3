"""`gpmotion study amend`: a study directory takes an amended spec only when
every row stays true (new configurations, labels, judges re-judging kept
measures); anything else is one line, exit 2, and no byte changed."""
import hashlib
import json
import shutil

import pytest

from gpmotion.cli import main
from gpmotion.rundir import RunDir
from gpmotion.study import SHIPPED
from gpmotion.study.ledger import read_rows, read_study
from gpmotion.study.spec import load

SPEC_TEXT = (SHIPPED / "creatures" / "spec.toml").read_text()

NEW_CONFIG = """
[configurations.bob-bsr-time-r6]
label = "Bob walks, time-based BSR (R = 6)"
task = "bob_walk"
family = "bsr-time"
options = { rules = 6, segments = "variable", t_per = 1.0 }
judge = "long-walk"
expect = ["walk of ≥ 5 steps"]
"""


@pytest.fixture
def study(tmp_path):
    """The shipped creatures ledger without its controllers (amend reads none)."""
    d = tmp_path / "creatures"
    d.mkdir()
    for name in ("study.json", "results.jsonl"):
        shutil.copy(SHIPPED / "creatures" / name, d / name)
    return d


def _files(d):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(d.iterdir())
            if p.is_file()}


def _spec(tmp_path, text):
    p = tmp_path / "amended.toml"
    p.write_text(text)
    return str(p)


def _amend(spec, d, capsys):
    code = main(["study", "amend", spec, "--out", str(d)])
    return code, capsys.readouterr()


def test_the_same_spec_changes_nothing(study, capsys):
    before = _files(study)
    code, out = _amend(str(SHIPPED / "creatures" / "spec.toml"), study, capsys)
    assert code == 0 and "nothing changed" in out.out
    assert _files(study) == before


def test_a_new_configuration_binds_the_directory_and_keeps_every_row(study, tmp_path, capsys):
    rows = (study / "results.jsonl").read_bytes()
    spec = _spec(tmp_path, SPEC_TEXT + NEW_CONFIG)
    code, out = _amend(spec, study, capsys)
    assert code == 0 and "added bob-bsr-time-r6" in out.out
    assert (study / "results.jsonl").read_bytes() == rows
    assert read_study(study)["digest"] == load(spec).digest()
    # now `study run` takes the amended spec in this directory (it checks the digest)
    from gpmotion.study.ledger import StudyDir
    new = load(spec)
    with StudyDir(study, new.digest(), new.source, new.quick):
        pass


def test_a_changed_judge_rejudges_that_configurations_rows_from_their_kept_measures(
        study, tmp_path, capsys):
    old = read_rows(study)
    text = SPEC_TEXT.replace('judge = "gait3d"\nexpect = ["bound"]\n\n[configurations.cujo-bsr-sense]',
                             'judge = "gait3d"\nexpect = ["other"]\n\n[configurations.cujo-bsr-sense]')
    assert text != SPEC_TEXT
    code, out = _amend(_spec(tmp_path, text), study, capsys)
    assert code == 0 and "cujo-bsr-time re-judged gait3d → gait3d" in out.out
    new = read_rows(study)
    assert [r for r in new if r["config"] != "cujo-bsr-time"] == \
        [r for r in old if r["config"] != "cujo-bsr-time"]
    cujo = [r for r in new if r["config"] == "cujo-bsr-time"]
    assert [r["label"] for r in cujo] == [r["label"] for r in old if r["config"] == "cujo-bsr-time"]
    assert [r["success"] for r in cujo] == [r["label"] == "other" for r in cujo]
    assert f"{sum(r['label'] == 'other' for r in cujo) + sum(r['label'] == 'bound' for r in cujo)} " \
        "verdicts changed" in out.out


BAD = [
    ("a changed search", lambda t: t.replace("options = { rules = 4, segments = \"variable\", t_per = 0.6 }",
                                             "options = { rules = 5, segments = \"variable\", t_per = 0.6 }"),
     "cujo-bsr-time: its searches differ"),
    ("a configuration with rows dropped",
     lambda t: t.replace("[configurations.cujo-bsr-sense]", "[configurations.cujo-bsr-sense-x]"),
     "'cujo-bsr-sense' has rows but is not in the new spec"),
    ("a report seed moved", lambda t: t.replace("report_seeds = [100,", "report_seeds = [99,"),
     "seed 100: not a report seed"),
    ("a judge without the measures it needs",
     lambda t: t.replace('label = "Rex walks, time-based BSR (R = 4, t_per 0.4 s)"',
                         'label = "Rex walks, time-based BSR (R = 4, t_per 0.4 s)"\njudge = "gait3d"'),
     "needs measures"),
]


@pytest.mark.parametrize("what, change, says", BAD, ids=[b[0] for b in BAD])
def test_an_amendment_that_would_make_a_row_untrue_is_refused(study, tmp_path, capsys,
                                                                 what, change, says):
    text = change(SPEC_TEXT)
    assert text != SPEC_TEXT
    before = _files(study)
    code, out = _amend(_spec(tmp_path, text), study, capsys)
    assert code == 2 and says in out.err and len(out.err.strip().splitlines()) == 1
    assert _files(study) == before


def test_a_study_being_run_is_not_amended(study, tmp_path, capsys):
    rd = RunDir.create(study, resume=True)
    before = _files(study)
    try:
        code, out = _amend(_spec(tmp_path, SPEC_TEXT + NEW_CONFIG), study, capsys)
    finally:
        rd.close()
    assert code == 2 and len(out.err.strip().splitlines()) == 1
    assert _files(study) == before


def test_a_quick_directory_takes_only_a_quick_spec(study, tmp_path, capsys):
    doc = json.loads((study / "study.json").read_text())
    doc["quick"] = True
    (study / "study.json").write_text(json.dumps(doc))
    before = _files(study)
    code, out = _amend(_spec(tmp_path, SPEC_TEXT + NEW_CONFIG), study, capsys)
    assert code == 2 and "--quick" in out.err
    assert _files(study) == before
