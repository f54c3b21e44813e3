"""The docs' study tables, regenerated from the shipped ledgers.

A page embeds a table between markers::

    <!-- study-table: NAME [--judge J] [--seeds report|tune] [--format md] -->
    ...
    <!-- /study-table -->

and :func:`publish` rewrites what is between them with what
``gpmotion study table NAME ...`` prints, so a number in the docs cannot
drift from the data (tests/test_published_tables.py checks it).
"""
from __future__ import annotations

import re
import shlex
from pathlib import Path

from ..records import atomic_write_text

# markers at the start of a line (an indented example in a code block is none)
BLOCK = re.compile(r"^(<!-- study-table: (?P<args>[^>\n]*?) -->\n)(?P<body>.*?)^(<!-- /study-table -->)",
                   re.S | re.M)


def pages(root: Path) -> list[Path]:
    root = Path(root)
    return [p for p in [root / "README.md", *sorted((root / "docs").rglob("*.md"))] if p.is_file()]


def table_text(args: str) -> str:
    """What ``gpmotion study table ARGS`` prints (NAME: a shipped study)."""
    from . import SHIPPED, load_directory, shipped_names
    from .table import render, summarize
    words = shlex.split(args)
    if not words or words[0] not in shipped_names():
        raise ValueError(f"study-table: {words[:1] or 'no name'} is not a shipped study")
    opts = {"--judge": None, "--seeds": "report", "--format": "md"}
    rest = words[1:]
    while rest:
        if rest[0] not in opts or len(rest) < 2:
            raise ValueError(f"study-table {args!r}: options are --judge, --seeds, --format")
        opts[rest[0]], rest = rest[1], rest[2:]
    spec, rows = load_directory(SHIPPED / words[0])
    return render(summarize(spec, rows, opts["--seeds"], opts["--judge"]), opts["--format"])


def expected(text: str) -> str:
    """A page with every study table as the ledgers give it."""
    def sub(m):
        return m.group(1) + table_text(m.group("args")) + m.group(4)
    return BLOCK.sub(sub, text)


def publish(root: str | Path, check: bool = False) -> list[tuple[Path, str]]:
    """Rewrite (or with ``check`` only compare) every page's study tables;
    returns (page, study) of each table that differed."""
    changed = []
    for page in pages(Path(root)):
        text = page.read_text(encoding="utf-8")
        if "<!-- study-table:" not in text:
            continue
        new = expected(text)
        if new != text:
            old = {m.group("args"): m.group("body") for m in BLOCK.finditer(text)}
            for m in BLOCK.finditer(new):
                if old.get(m.group("args")) != m.group("body"):
                    changed.append((page, m.group("args")))
            if not check:
                atomic_write_text(page, new)
    return changed
