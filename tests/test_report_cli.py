"""`gpmotion report NAME` on a shipped study: its committed ledger's page,
written where the user is (never inside the installed package)."""
from gpmotion.cli import main
from gpmotion.study import SHIPPED


def test_a_shipped_study_by_name_writes_its_page_here(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in (SHIPPED / "gp-vs-bsr").iterdir())
    assert main(["report", "gp-vs-bsr"]) == 0
    page = (tmp_path / "gp-vs-bsr-report.html").read_text()
    assert "<html" in page and "gp-vs-bsr" in page
    assert sorted(p.name for p in (SHIPPED / "gp-vs-bsr").iterdir()) == before
    assert main(["report", "gp-vs-bsr", "-o", str(tmp_path / "mine.html")]) == 0
    assert (tmp_path / "mine.html").stat().st_size > 0


def test_an_unknown_source_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["report", "no-such-study"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["gpmotion: error: no-such-study: no such run, comparison, study or composite"]
