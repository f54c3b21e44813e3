"""Every study table in the README and the docs is what `gpmotion study table`
prints from the shipped ledgers (`gpmotion study publish` rewrites them)."""
from pathlib import Path

import pytest

from gpmotion.study import SHIPPED, load_directory, shipped_names
from gpmotion.study.ledger import STUDY, read_rows
from gpmotion.study.publish import BLOCK, expected, pages, publish
from gpmotion.study.spec import load

ROOT = Path(__file__).resolve().parents[1]
PAGES = [p for p in pages(ROOT) if BLOCK.search(p.read_text(encoding="utf-8"))]


def test_some_page_embeds_a_study_table():
    assert PAGES, "no page embeds a study table"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_a_committed_table_is_what_the_command_prints(page):
    text = page.read_text(encoding="utf-8")
    assert text == expected(text), (f"{page}: a study table differs from its ledger; "
                                    "run `gpmotion study publish`")


def test_publish_check_names_a_table_that_drifted(tmp_path):
    (tmp_path / "docs").mkdir()
    page = tmp_path / "docs" / "p.md"
    page.write_text("x\n<!-- study-table: auslander-2d --seeds tune -->\n| made up |\n"
                    "<!-- /study-table -->\n")
    assert publish(tmp_path, check=True) == [(page, "auslander-2d --seeds tune")]
    assert "made up" in page.read_text()                 # --check changes nothing
    publish(tmp_path)
    assert publish(tmp_path, check=True) == [] and "made up" not in page.read_text()


@pytest.mark.parametrize("name", [n for n in shipped_names() if (SHIPPED / n / STUDY).exists()])
def test_a_shipped_ledger_was_run_from_its_shipped_spec(name):
    spec, rows = load_directory(SHIPPED / name)
    assert spec.digest() == load(SHIPPED / name / "spec.toml").digest()
    for r in rows:
        assert (SHIPPED / name / r["controller"]).is_file()
        assert r["seeds"] == spec.seed_set(r["seed"])
        # report rows come from real runs: the driver's, or a run script's record of the
        # same configuration and seed (tests/test_gaits_ledger.py replays each to its cost)
        assert r["seeds"] == "tune" or r.get("imported", "benchmarks/").startswith("benchmarks/")
    assert rows == read_rows(SHIPPED / name)
