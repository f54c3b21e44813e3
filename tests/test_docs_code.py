"""Every code block of the tutorial and the how-to guides runs, so the docs cannot rot.

Per page, in order, in one scratch folder that holds a link to the checkout's
``examples/`` (so a later block may use an earlier block's run directory or
files, and any block the shipped examples):

* a block with a ``title="PATH"`` attribute is a file the reader creates: it is
  written to PATH;
* a ```` ```python ```` block runs as a script;
* a ```` ```console ```` block runs each ``$ `` line (``\\`` continues a line) as a
  command, without a shell.  The lines after a command are its output: each must
  appear in what it printed (``...`` elides a part of a line).  A command whose
  output starts ``gpmotion: error:`` must fail with exit code 2, every other
  command must succeed;
* a block preceded by ``<!-- docs-test: skip REASON -->`` does not run (kept for
  what no test machine has, such as a cluster of several hosts);
* other blocks (``toml``, ``text``, ``json`` ... without a title) are shown data.

Searches run with small budgets: a ``gpmotion run`` line that sets no
``--generations`` gets ``--generations 2`` (and ``--population 16`` for the
population-based families), ``compare`` ``--seeds 1 --budget 64``,
``robustness`` ``--trials 4``, ``compose`` ``--rounds 2``, unless the line sets them.
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "docs" / "tutorial.md", *sorted((ROOT / "docs" / "howto").glob("*.md"))]
SKIP = re.compile(r"<!--\s*docs-test:\s*skip\b(.*?)-->")
FENCE = re.compile(r"^(\s*)```(\w*)(.*)$")
TIMEOUT = 1800


@dataclass
class Block:
    lang: str
    code: str
    line: int
    title: str | None = None
    skip: str | None = None
    attrs: dict = field(default_factory=dict)


def blocks(text: str) -> list[Block]:
    """The fenced blocks of a Markdown page, with their language, title and skip mark."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang, rest = m.groups()
        title = re.search(r'title="([^"]+)"', rest)
        prev = next((l for l in reversed(lines[:i]) if l.strip()), "")
        skip = SKIP.search(prev)
        body, j = [], i + 1
        while j < len(lines) and not lines[j].strip().startswith("```"):
            body.append(lines[j][len(indent):] if lines[j].startswith(indent) else lines[j])
            j += 1
        out.append(Block(lang, "\n".join(body) + "\n", i + 1, title and title.group(1),
                         skip and (skip.group(1).strip() or "skipped")))
        i = j + 1
    return out


def commands(console: str) -> list[tuple[str, list[str]]]:
    """(command, expected output lines) for each ``$ `` line of a console block."""
    out, pending = [], None
    for line in console.splitlines():
        if line.startswith("$ "):
            out.append([line[2:], []])
            pending = line.endswith("\\")
        elif pending and out:
            out[-1][0] = out[-1][0][:-1].rstrip() + " " + line.strip()
            pending = line.endswith("\\")
        elif out and line.strip():
            out[-1][1].append(line.strip())
    return [(cmd, expected) for cmd, expected in out]


def small_budget(argv: list[str]) -> list[str]:
    """The command with the test's small search budgets added where it sets none."""
    if argv[:1] != ["gpmotion"] or len(argv) < 2:
        return argv
    extra, cmd = [], argv[1]
    given = set(a.split("=")[0] for a in argv)
    if cmd == "run" and "--generations" not in given:
        extra += ["--generations", "2"]
        family = argv[argv.index("--controller") + 1] if "--controller" in argv else "gp"
        if family in ("gp", "keyframes") and "--population" not in given:
            extra += ["--population", "16"]
    elif cmd == "compare":
        extra += [] if "--seeds" in given else ["--seeds", "1"]
        extra += [] if "--budget" in given else ["--budget", "64"]
    elif cmd == "robustness" and "--trials" not in given:
        extra += ["--trials", "4"]
    elif cmd == "compose" and "--rounds" not in given and "--no-search" not in given:
        extra += ["--rounds", "2"]
    return argv + extra


def _executable(argv: list[str]) -> list[str]:
    if argv[0] == "gpmotion":
        return [sys.executable, "-m", "gpmotion", *argv[1:]]
    if argv[0] == "python":
        return [sys.executable, *argv[1:]]
    return argv


def _appears(expected: str, printed: str) -> bool:
    squeeze = lambda s: " ".join(s.split())       # noqa: E731 - whitespace is layout
    text, at = squeeze(printed), 0
    for piece in (squeeze(p) for p in re.split(r"\.\.\.|…", expected)):
        at = text.find(piece, at)
        if at < 0:
            return False
        at += len(piece)
    return True


def run_console(block: Block, cwd: Path, env: dict, where: str) -> None:
    for cmd, expected in commands(block.code):
        argv = small_budget(shlex.split(cmd, comments=True))
        proc = subprocess.run(_executable(argv), cwd=cwd, env=env, capture_output=True,
                              text=True, timeout=TIMEOUT)
        printed = proc.stdout + proc.stderr
        failing = bool(expected) and expected[0].startswith("gpmotion: error:")
        assert proc.returncode == (2 if failing else 0), (
            f"{where}: `{cmd}` exited {proc.returncode}\n{printed[-3000:]}")
        for line in expected:
            assert _appears(line, printed), f"{where}: `{cmd}` did not print {line!r}\n{printed[-3000:]}"


def run_page(page: Path, cwd: Path) -> int:
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(cwd)}
    (cwd / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    ran = 0
    for block in blocks(page.read_text(encoding="utf-8")):
        where = f"{page.relative_to(ROOT)}:{block.line}"
        if block.skip:
            continue
        if block.title:
            path = cwd / block.title
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(block.code, encoding="utf-8")
        elif block.lang == "python":
            script = cwd / f"_block_{block.line}.py"
            script.write_text(block.code, encoding="utf-8")
            proc = subprocess.run([sys.executable, script.name], cwd=cwd, env=env,
                                  capture_output=True, text=True, timeout=TIMEOUT)
            assert proc.returncode == 0, f"{where}: python block failed\n{proc.stderr[-3000:]}"
        elif block.lang == "console":
            run_console(block, cwd, env, where)
        else:
            continue
        ran += 1
    return ran


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_page_code_runs(page, tmp_path):
    assert run_page(page, tmp_path) > 0, f"{page.name} has no code block that runs"


# The harness itself -------------------------------------------------------------

def test_blocks_reads_language_title_and_skip_mark():
    text = ('x\n```python title="pkg/m.py"\nA = 1\n```\n<!-- docs-test: skip needs a cluster -->\n'
            '```console\n$ dask scheduler\n```\n```toml\nk = 1\n```\n')
    got = blocks(text)
    assert [(b.lang, b.title, b.skip) for b in got] == [
        ("python", "pkg/m.py", None), ("console", None, "needs a cluster"), ("toml", None, None)]
    assert got[0].code == "A = 1\n"


def test_commands_join_continuations_and_collect_output():
    got = commands("$ gpmotion run lamp_hop \\\n    --seed 2\nbest ... cost\n$ gpmotion list\n")
    assert got == [("gpmotion run lamp_hop --seed 2", ["best ... cost"]), ("gpmotion list", [])]


def test_small_budget_only_where_the_line_sets_none():
    assert small_budget(["gpmotion", "run", "lamp_hop"]) == [
        "gpmotion", "run", "lamp_hop", "--generations", "2", "--population", "16"]
    assert small_budget(["gpmotion", "run", "lamp_hop", "--controller", "bsr-sense"]) == [
        "gpmotion", "run", "lamp_hop", "--controller", "bsr-sense", "--generations", "2"]
    assert small_budget(["gpmotion", "run", "x", "--generations=5"]) == ["gpmotion", "run", "x",
                                                                         "--generations=5"]
    assert small_budget(["gpmotion", "list"]) == ["gpmotion", "list"]


def test_expected_output_with_elisions():
    assert _appears("ok    primitive ... hypot", "ok primitive  hypot\n")
    assert not _appears("ok primitive hypot", "FAIL primitive hypot")
    assert not _appears("b ... a", "a b")


def test_a_failing_block_fails(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```python\nraise SystemExit(3)\n```\n")
    global ROOT
    saved, ROOT = ROOT, tmp_path
    try:
        with pytest.raises(AssertionError, match="python block failed"):
            run_page(page, tmp_path)
    finally:
        ROOT = saved
