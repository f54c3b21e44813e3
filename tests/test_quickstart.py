"""The README's Quick-start runs as written, in order, in one fresh folder.

The lines are read from the README's quickstart block (between
``<!-- quickstart:begin -->`` and ``<!-- quickstart:end -->``), so they cannot
drift from what a newcomer types.  What differs from typing them:

* ``pip install ...`` is not run here (tests/test_first_hour.py installs the
  package the README's way into a fresh venv); of ``pip install . && CMD`` the
  ``CMD`` runs.  ``python -m pytest`` (the whole suite) is not run;
* search budgets are made small: a budget option the line gives gets a small
  value (``SMALL``), and a line that sets none gets the docs tests' small budget
  (tests/test_docs_code.small_budget);
* the folder holds a link to the checkout's ``examples/``, as a clone does.

Every line must exit 0; some say what they show, and the test checks that too.
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from tests.test_docs_code import small_budget

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
SMALL = {"--generations": "2", "--population": "16", "--rounds": "2", "--budget": "64",
         "--seeds": "1", "--trials": "4"}


def quickstart_lines(text: str = README) -> list[str]:
    """The commands of the quickstart block's code blocks, comments dropped."""
    block = text.split("<!-- quickstart:begin -->", 1)[1].split("<!-- quickstart:end -->", 1)[0]
    out = []
    for code in re.findall(r"```[^\n]*\n(.*?)```", block, flags=re.S):
        for line in code.splitlines():
            line = line.split("  #", 1)[0].strip()
            if line:
                out.append(line)
    return out


def runnable(line: str) -> list[list[str]]:
    """The commands of one line this test runs, budgets made small."""
    out = []
    for part in line.split("&&"):
        argv = shlex.split(part)
        if argv[:2] == ["pip", "install"] or argv[:3] == ["python", "-m", "pytest"]:
            continue
        out.append(small_budget(shrink(argv)))
    return out


def shrink(argv: list[str]) -> list[str]:
    """A budget option's value replaced by its small one (``--opt V`` or ``--opt=V``)."""
    out, i = [], 0
    while i < len(argv):
        key = argv[i].split("=", 1)[0]
        if key in SMALL:
            out += [key, SMALL[key]]
            i += 1 if "=" in argv[i] else 2
        else:
            out.append(argv[i])
            i += 1
    return out


def test_quickstart_lines_run_in_order(tmp_path):
    (tmp_path / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    printed = {}
    for line in quickstart_lines():
        for argv in runnable(line):
            exe = [sys.executable, "-m", "gpmotion", *argv[1:]] if argv[0] == "gpmotion" else argv
            proc = subprocess.run(exe, cwd=tmp_path, env=env, capture_output=True, text=True,
                                  timeout=1200)
            assert proc.returncode == 0, f"`{line}` exited {proc.returncode}\n{proc.stderr[-3000:]}"
            printed[line] = proc.stdout + proc.stderr
    ran = " ".join(printed)
    assert "--preset gritz-hahn" in ran and "bsr-sense --actuation pd" in ran
    # the preset's run has a folder of its own beside the first run's
    assert (tmp_path / "runs" / "lamp_hop-gp-seed0" / "best.json").exists()
    assert (tmp_path / "runs" / "lamp_hop-gp-gritz-hahn-seed0" / "best.json").exists()
    assert (tmp_path / "hop.png").exists() and (tmp_path / "hop.gif").exists()
    compose = next(v for k, v in printed.items() if k.startswith("gpmotion compose"))
    careless = float(re.search(r"careless: .* total (\S+)", compose).group(1))
    best = float(re.search(r"best: .* total (\S+)", compose).group(1))
    assert best > careless + 0.1, "the compose example shows the search repairing the careless one"
    assert "ok    task lamp_reach-v1" in " ".join(printed.values())


def test_the_lines_are_read_from_the_readme_and_budgets_shrunk():
    lines = quickstart_lines()
    assert lines[0] == "pip install . && gpmotion run lamp_hop"
    assert lines[-1] == 'pip install -e ".[test]" && python -m pytest -q'
    assert runnable(lines[0]) == [["gpmotion", "run", "lamp_hop", "--generations", "2",
                                   "--population", "16"]]
    assert runnable(lines[-1]) == []
    assert shrink(["gpmotion", "run", "x", "--generations", "282", "--working", "10"]) == [
        "gpmotion", "run", "x", "--generations", "2", "--working", "10"]
    assert shrink(["gpmotion", "compare", "x", "--budget=3000"]) == [
        "gpmotion", "compare", "x", "--budget", "64"]


def test_the_bsr_line_names_the_setting_under_which_bsr_solves_the_lamp():
    """The gp-vs-bsr study's setting (PD, 3,000 evaluations: 10 working controllers,
    282 rounds), under which BSR solved every seed it was run on."""
    try:
        import tomllib
    except ModuleNotFoundError:                     # Python 3.10
        import tomli as tomllib
    from gpmotion.families import make_family
    from gpmotion.task import get_task
    spec = tomllib.loads((ROOT / "gpmotion/studies/gp-vs-bsr/spec.toml").read_text())
    [line] = [ln for ln in quickstart_lines() if "--controller bsr-sense" in ln]
    argv = shlex.split(line)
    opt = lambda k: argv[argv.index(k) + 1]          # noqa: E731
    settings = make_family("bsr-sense", get_task("lamp_hop")).budget_settings(
        spec["defaults"]["budget"])
    assert opt("--actuation") == spec["defaults"]["actuation"]
    assert int(opt("--working")) == settings["n_working"]
    assert int(opt("--generations")) == settings["n_generations"]
