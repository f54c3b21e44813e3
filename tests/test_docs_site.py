"""The documentation site builds with ``mkdocs build --strict`` (a broken link, a
missing page or a docstring mkdocstrings cannot render fails the build), and the
published command-line reference is what the argument parser generates."""
import os
import re
import subprocess
import sys
from pathlib import Path

from gpmotion.cli import reference

ROOT = Path(__file__).resolve().parents[1]


def test_cli_reference_page_is_generated_from_the_parser():
    page = (ROOT / "docs" / "reference" / "cli.md").read_text(encoding="utf-8")
    assert page == reference.markdown(), (
        "docs/reference/cli.md is stale: python -m gpmotion.cli.reference > docs/reference/cli.md")


def test_cli_reference_covers_every_command_and_option():
    from gpmotion.cli import parser
    page = reference.markdown()
    ap = parser()
    commands = next(a for a in ap._actions if a.__class__.__name__ == "_SubParsersAction").choices
    for name, sub in commands.items():
        assert f"## `gpmotion {name}`" in page
        for action in sub._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help"):
                    assert f"`{flag}" in page or f", {flag}" in page, (name, flag)


def test_cli_reference_escapes_table_cells():
    import argparse
    ap = argparse.ArgumentParser(prog="gpmotion")
    sub = ap.add_subparsers(dest="cmd")
    p = sub.add_parser("demo", help="a <demo> command")
    p.add_argument("--mode", help="a|b, default %(default)s", default="a")
    page = reference.markdown(ap)
    assert "| `--mode MODE` | a\\|b, default a |" in page
    assert "a &lt;demo&gt; command" in page


def test_site_builds_strict(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    for page in ("index.html", "tutorial/index.html", "reference/cli/index.html",
                 "reproduction/gritz_hahn/index.html", "reproduction/auslander/index.html",
                 "reference/api/task/index.html"):
        assert (tmp_path / "site" / page).is_file(), page
    # mkdocstrings rendered the API from the docstrings, not an empty page
    assert "register_task" in (tmp_path / "site" / "reference/api/task/index.html").read_text()
    # docstrings' reST roles (:func:`run`) render as links or code, never as the raw role
    api = sorted((tmp_path / "site" / "reference" / "api").glob("*/index.html"))
    raw = {p.parent.name: m.group(0) for p in api
           if (m := re.search(r":(class|func|meth|mod|data):(`|<code>)", p.read_text()))}
    assert not raw, raw
    links = sum(p.read_text().count('autorefs-internal" title="') for p in api)
    assert links > 0


def test_docstring_roles_become_autorefs_to_the_object_they_name():
    """docs/_griffe/roles.py: a short name resolves in the docstring's own scope,
    ``~`` shows the last part, an explicit title is kept, an import is followed
    to what it names."""
    import importlib.util
    import griffe
    path = ROOT / "docs" / "_griffe" / "roles.py"
    spec = importlib.util.spec_from_file_location("gpmotion_docs_roles", path)
    roles = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(roles)
    pkg = griffe.load("gpmotion", extensions=griffe.load_extensions(f"{path}:SphinxRoles"),
                      search_paths=[str(ROOT)])
    text = pkg["task"].docstring.value
    assert ":class:" not in text and ":func:" not in text
    assert '<autoref identifier="gpmotion.model.Figure" optional><code>Figure</code></autoref>' in text
    assert '<autoref identifier="gpmotion.task.task_id" optional><code>task_id</code></autoref>' in text
    assert roles.convert(pkg["task"], ":func:`the runner <gpmotion.run.run>`") == (
        '<autoref identifier="gpmotion.run.run" optional><code>the runner</code></autoref>')
    assert roles.resolve(pkg["task"]["Task"], "register_task") == "gpmotion.task.register_task"
