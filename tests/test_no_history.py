"""The product speaks of itself: no tracked text file outside CHANGELOG.md tells
how the project was developed (a development session or a tracker's issue by
number, "tried in" a session, a commit hash given as history, a file or folder
named by session),
and research data lives with its study, not in a notes folder."""
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXEMPT = ("CHANGELOG.md",)                       # history by version belongs there
THIRD_PARTY = ("gpmotion/report/vendor/",)       # vendored libraries, not ours to reword

S = "session"   # spelled once, so that this file's own patterns are not hits
PHRASES = re.compile(
    rf"\b{S}s?\s+\d+"                                                # the development session by number
    rf"|\b(?:this|next|earlier|last|previous|later|that|one) {S}\b"  # ... or by its place
    rf"|\btried in (?:a |an |the )?(?:{S}|round)\b"
    r"|\bwhat we learned\b"
    r"|\b(?:issue|defect)s?\s+#?\d+",                            # the tracker's work items
    re.IGNORECASE)
# a file or folder named by session: herman_s17_bar.jsonl, auslander_s26/, rex_s23/
SESSION_NAME = re.compile(r"(?:^|[_/-])s\d{1,2}(?:[_/.-]|$)")
HEX = re.compile(r"\b[0-9a-f]{7,40}\b")


def _git(*args):
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout


@pytest.fixture(scope="module")
def tracked():
    try:
        names = _git("ls-files", "-z").split("\0")
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    return [n for n in names if n and (ROOT / n).is_file()]


def _texts(tracked):
    for name in tracked:
        if name in EXEMPT or name.startswith(THIRD_PARTY):
            continue
        data = (ROOT / name).read_bytes()
        if b"\0" in data:
            continue                                  # binary: pictures, fonts
        try:
            yield name, data.decode("utf-8")
        except UnicodeDecodeError:
            continue


def history_phrases(text):
    """(line number, line) of every line that speaks of development."""
    return [(i, line.strip()) for i, line in enumerate(text.splitlines(), 1) if PHRASES.search(line)]


def test_the_phrases_are_found():
    assert history_phrases(f"as measured in {S} 14\nfine\nthe {S}s 20-21 table") == [
        (1, f"as measured in {S} 14"), (3, f"the {S}s 20-21 table")]
    assert history_phrases(f"Tried in {S.capitalize()} 23.")
    assert history_phrases(f"left for the next {S}")
    assert history_phrases("## What we " + "learned")
    assert history_phrases("The bar (iss" + "ue 16): K starts") and history_phrases("defect" + " 2")
    # the product's own words are not history: compose's session module, a process group
    assert not history_phrases("from ..compose import optimize, " + S)
    assert not history_phrases(f"start_new_{S}=True; after round 1 the log has two rows")
    assert SESSION_NAME.search("docs/notes/herman_s17_bar.jsonl")
    assert SESSION_NAME.search("data/auslander_s26/x.json")
    assert not SESSION_NAME.search("gpmotion/sim/spatial3d.py")


def test_no_tracked_text_speaks_of_development_sessions(tracked):
    hits = [f"{name}:{i}: {line[:120]}" for name, text in _texts(tracked) for i, line in history_phrases(text)]
    assert not hits, "history belongs in CHANGELOG.md:\n" + "\n".join(hits)


def test_no_tracked_file_is_named_by_session(tracked):
    assert not [n for n in tracked if SESSION_NAME.search(n)]


# a session-named folder or file cited inside a text (a ledger's record path, a label's source)
SESSION_PATH = re.compile(r"[A-Za-z]_s\d{1,2}(?:[_/.]|\b)")


def test_no_tracked_text_cites_a_path_named_by_session(tracked):
    hits = [f"{name}:{i}" for name, text in _texts(tracked) if name != "tests/test_no_history.py"
            for i, line in enumerate(text.splitlines(), 1) if SESSION_PATH.search(line)]
    assert not hits, "paths named by session: " + ", ".join(hits[:10])
    assert SESSION_PATH.search('"imported":"docs/notes/auslander_s26/full-height-t1-seed0.json"')
    assert not SESSION_PATH.search("bsr_sense keeps its senses_s over t_sample")


def test_docs_holds_no_research_notes_that_nothing_reads(tracked):
    """Research data lives with its study (gpmotion/studies/NAME) or beside the
    test that reads it, and what no table, test or page uses is removed: a file
    left under docs/notes/ must be named, folder and file, by a test or a
    benchmark that still reads it (until its study takes it)."""
    readers = "\n".join((ROOT / n).read_text(encoding="utf-8") for n in tracked
                         if n.endswith(".py") and n.startswith(("tests/", "benchmarks/"))
                         and not n.endswith("test_no_history.py"))

    def read(name):
        folder, _, file = name.removeprefix("docs/notes/").rpartition("/")
        if not folder:
            return name in readers
        stem = file.rsplit(".", 1)[0]
        named = f'"notes" / "{folder}"' in readers or f"docs/notes/{folder}/" in readers
        return named and (f'"{file}"' in readers or f'"{stem}' in readers)

    unread = [n for n in tracked if n.startswith("docs/notes/") and not read(n)]
    assert not unread, f"{len(unread)} files under docs/notes/ that nothing reads, e.g. {unread[:5]}"


def test_no_commit_hash_given_as_history(tracked):
    """A hex word that abbreviates one of the repository's commits is history
    (content digests are not commits, so they are not hits)."""
    try:
        commits = _git("rev-list", "--all").split()
    except subprocess.CalledProcessError:
        pytest.skip("no history in this checkout")
    by_prefix = {}
    for c in commits:
        by_prefix.setdefault(c[:7], []).append(c)
    hits = []
    for name, text in _texts(tracked):
        for word in set(HEX.findall(text)):
            if re.search("[a-f]", word) and re.search("[0-9]", word) and any(
                    c.startswith(word) for c in by_prefix.get(word[:7], ())):
                hits.append(f"{name}: {word}")
    assert not hits, hits
