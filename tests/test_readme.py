"""The front page: short, its commands the ones CI runs, its links and pictures real."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_readme_is_a_front_page_of_at_most_200_lines():
    assert len(README.splitlines()) <= 200


def test_ci_runs_the_readme_test_command_verbatim():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1]
    assert ci == 'pip install -e ".[test]" && python -m pytest -q'
    assert f"\n{ci}\n" in README


def test_the_quickstart_block_is_marked_once():
    assert README.count("<!-- quickstart:begin -->") == 1
    assert README.count("<!-- quickstart:end -->") == 1
    assert README.index("<!-- quickstart:begin -->") < README.index("<!-- quickstart:end -->")


def test_every_relative_link_and_picture_exists():
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README)
    local = [t for t in targets if not re.match(r"[a-z]+://", t)]
    assert local, "the README links its documentation"
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, missing


def test_no_development_history_on_the_front_page():
    assert not re.search(r"(?i)\bsessions? \d+|(this|next|earlier|last|previous) session", README)
    assert not re.search(r"\b[0-9a-f]{7,40}\b", README), "commit hashes are history: CHANGELOG.md"
