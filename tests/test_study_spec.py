"""Study specs are parsed and checked: every bad spec is one line naming the
key, exit code 2, nothing written; the shipped specs parse."""
import pytest

from gpmotion.cli import main
from gpmotion.study import shipped_names, spec_path
from gpmotion.study.spec import load, parse, select_seeds

GOOD = """
[study]
name = "s"
tune_seeds = [0, 1]
report_seeds = [100]
[defaults]
task = "starman_travel"
family = "bsr-time"
search = { n_working = 4, n_generations = 3 }
[quick]
seeds = [0]
search = { n_generations = 1 }
[configurations.a]
judge = "gait"
expect = ["hop"]
"""

BAD = [  # (replace this, with that, the error names)
    ('name = "s"', 'name = "../up"', "study.name"),
    ('name = "s"', 'name = "s"\ncolour = 1', "study: unknown key(s) ['colour']"),
    ("report_seeds = [100]", "report_seeds = [1]", "study.report_seeds"),
    ("tune_seeds = [0, 1]", "tune_seeds = [0, 0]", "study.tune_seeds"),
    ("tune_seeds = [0, 1]", "tune_seeds = [-1]", "study.tune_seeds[0]"),
    ('judge = "gait"', 'judge = "gaits"', "configurations.a.judge"),
    ('expect = ["hop"]', 'expect = ["flying"]', "configurations.a.expect"),
    ('expect = ["hop"]', 'expect = ["hop"]\nbudjet = 3', "configurations.a: unknown key(s) ['budjet']"),
    ('family = "bsr-time"', 'family = "bsr"', "configurations.a.family"),
    ('task = "starman_travel"', 'task = "starman_travl"', "configurations.a.task"),
    ("n_generations = 3 }", "n_generations = 3, popsize = 4 }", "configurations.a.search"),
    ('judge = "gait"', 'judge = "gait"\nstarts = 0', "configurations.a.starts"),
    ('judge = "gait"', 'judge = "gait"\nfigure = "nobody"', "configurations.a.figure"),
    ('judge = "gait"', 'judge = "gait"\nparams = { figure = "beryl" }', "configurations.a.params.figure"),
    ('judge = "gait"\nexpect = ["hop"]', 'judge = "walk-turn-walk"', "configurations.a.judge"),
    ("[configurations.a]", "[configurations.A]", "configurations.A (its name)"),
    ("seeds = [0]", "seeds = [7]", "quick.seeds"),
]


@pytest.mark.parametrize("old,new,names", BAD)
def test_a_bad_spec_is_one_line_naming_the_key(tmp_path, capsys, old, new, names):
    assert old in GOOD
    p = tmp_path / "spec.toml"
    p.write_text(GOOD.replace(old, new, 1))
    out = tmp_path / "out"
    assert main(["study", "run", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gpmotion: error: ") and err.count("\n") == 1, err
    assert names in err, err
    assert not out.exists()


def test_a_bad_task_parameter_is_refused_before_the_disk(tmp_path, capsys):
    p = tmp_path / "spec.toml"
    p.write_text(GOOD.replace('judge = "gait"', 'judge = "gait"\nparams = { wings = 2 }'))
    assert main(["study", "run", str(p), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "configurations.a" in err and "wings" in err and not (tmp_path / "out").exists()


def test_not_toml_and_no_quick_form(tmp_path, capsys):
    p = tmp_path / "spec.toml"
    p.write_text("[study\n")
    assert main(["study", "run", str(p), "--out", str(tmp_path / "o")]) == 2
    assert "not a TOML file" in capsys.readouterr().err
    p.write_text(GOOD.split("[quick]")[0] + "[configurations.a]\njudge = 'gait'\n")
    assert main(["study", "run", str(p), "--out", str(tmp_path / "o"), "--quick"]) == 2
    assert "quick" in capsys.readouterr().err


def test_quick_form_and_seed_selection(tmp_path):
    import tomllib
    doc = tomllib.loads(GOOD)
    full, quick = parse(doc), parse(doc, quick=True)
    assert full.configurations["a"].stages[0].search["n_generations"] == 3
    assert quick.configurations["a"].stages[0].search == {"n_working": 4, "n_generations": 1}
    assert quick.seeds == [0] and full.digest() != quick.digest()
    assert select_seeds(full, "report") == [100] and select_seeds(full, "0,100") == [0, 100]
    with pytest.raises(ValueError, match="--seeds"):
        select_seeds(full, "5")


@pytest.mark.parametrize("name", shipped_names())
def test_every_shipped_spec_parses_with_its_quick_form(name):
    spec = load(spec_path(name))
    quick = load(spec_path(name), quick=True)
    assert spec.name == name and quick.seeds
    assert not set(spec.tune_seeds) & set(spec.report_seeds)


def test_study_list_names_every_shipped_study(capsys):
    assert main(["study", "list"]) == 0
    out = capsys.readouterr().out
    for name in shipped_names():
        assert name in out
