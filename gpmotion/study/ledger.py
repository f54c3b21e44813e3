"""A study directory: study.json (the spec and its digest), results.jsonl (one
row per configuration × seed × start) and controllers/ (each row's best
controller, compact JSON).

Rows are appended whole or not at all: one ``write`` of one line on an
``O_APPEND`` descriptor, then ``fsync``; a torn last line (a writer killed
mid-write) is dropped when the directory is next opened for writing, and
ignored by readers.  Files are opened without following symbolic links and
must be regular files.  The directory is locked by :class:`RunDir` while a
study runs into it, so there is one writer.
"""
from __future__ import annotations

import errno
import json
import os
import stat
from pathlib import Path

from ..records import FormatError, RunDirError, atomic_write_text, envelope, parse_json
from ..rundir import RunDir

RESULTS, STUDY, CONTROLLERS = "results.jsonl", "study.json", "controllers"
SPEC = "spec.toml"           # a shipped study's spec sits beside its ledger
MAX_LEDGER = 1 << 30
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
ROW_KEYS = ("config", "seed", "start")


def row_key(row: dict) -> tuple:
    return tuple(row[k] for k in ROW_KEYS)


def row_line(row: dict) -> str:
    """A row as its ledger line (compact, keys sorted, no NaN)."""
    return json.dumps(row, sort_keys=True, separators=(",", ":"), allow_nan=False) + "\n"


def study_text(digest: str, spec_doc: dict, quick: bool) -> str:
    """``study.json``: the spec (in its own order: the table's) and its digest."""
    return json.dumps(envelope("study", {"digest": digest, "quick": quick, "spec": spec_doc}),
                      indent=1, ensure_ascii=False) + "\n"


def _read_regular(path: Path, limit: int) -> bytes | None:
    """A regular file's bytes (None if absent), never through a symlink."""
    try:
        fd = os.open(path, os.O_RDONLY | _NOFOLLOW)
    except FileNotFoundError:
        return None
    except OSError as e:
        why = "a symbolic link (not followed)" if e.errno == errno.ELOOP else (e.strerror or str(e))
        raise FormatError(f"{path}: {why}") from None
    with open(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise FormatError(f"{path}: not a regular file")
        data = f.read(limit + 1)
    if len(data) > limit:
        raise FormatError(f"{path}: larger than the {limit}-byte limit")
    return data


def parse_rows(data: bytes, source: str) -> list[dict]:
    """Complete lines of a ledger as rows (a torn last line is not a row)."""
    text = data.decode("utf-8", "replace")
    rows, seen = [], set()
    for i, line in enumerate(text.split("\n")[:-1], 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line, parse_constant=_no_constant)
        except ValueError as e:
            raise FormatError(f"{source}:{i}: not a JSON row ({e})") from None
        if not isinstance(row, dict) or any(k not in row for k in ROW_KEYS):
            raise FormatError(f"{source}:{i}: a row needs {', '.join(ROW_KEYS)}")
        if row_key(row) in seen:
            raise FormatError(f"{source}:{i}: a second row for {row_key(row)}")
        seen.add(row_key(row))
        rows.append(row)
    return rows


def _no_constant(name):
    raise ValueError(f"non-standard constant {name}")


def read_rows(directory: str | Path) -> list[dict]:
    """The rows of ``DIRECTORY/results.jsonl`` (none if it has none)."""
    path = Path(directory) / RESULTS
    data = _read_regular(path, MAX_LEDGER)
    return [] if data is None else parse_rows(data, str(path))


def read_study(directory: str | Path) -> dict:
    """``study.json``: the spec a directory was run from, and its digest."""
    path = Path(directory) / STUDY
    data = _read_regular(path, 8 << 20)
    if data is None:
        raise FormatError(f"{directory}: not a study directory (no {STUDY})")
    doc = parse_json(data, kind="study", source=str(path))
    for k in ("digest", "spec", "quick"):
        if k not in doc:
            raise FormatError(f"{path}: lacks {k!r}")
    return doc


class StudyDir:
    """A locked study directory being written (see the module docstring)."""

    def __init__(self, path: str | Path, digest: str, spec_doc: dict, quick: bool):
        path = Path(path)
        fresh = not (path / STUDY).exists()
        self.path = path
        if fresh and path.is_dir() and any(p.name not in (SPEC, ".lock") for p in path.iterdir()):
            raise RunDirError(f"{path}: exists, is not empty and is not a study directory; "
                              "choose another --out")
        self.rd = RunDir.create(path, resume=path.is_dir())
        try:
            if fresh:
                atomic_write_text(self.rd.file(STUDY), study_text(digest, spec_doc, quick))
            else:
                have = read_study(path)
                if have["digest"] != digest:
                    raise RunDirError(
                        f"{path}: was run from another spec (digest {have['digest'][:12]}… ≠ "
                        f"{digest[:12]}…{'; one is --quick' if have['quick'] != quick else ''}); "
                        "a changed spec needs a new --out")
            self._mend_torn_tail()
            ctl = Path(self.rd.file(CONTROLLERS))
            if os.path.islink(ctl) or (ctl.exists() and not ctl.is_dir()):
                raise RunDirError(f"{path / CONTROLLERS}: not a directory of this study")
            ctl.mkdir(exist_ok=True)
            self.rd.clean_temp(CONTROLLERS)          # a controller's write cut by a kill
        except BaseException:
            self.rd.close()
            raise

    def close(self):
        self.rd.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def rows(self) -> list[dict]:
        data = _read_regular(Path(self.rd.file(RESULTS)), MAX_LEDGER)
        return [] if data is None else parse_rows(data, str(self.path / RESULTS))

    def _open(self, flags: int) -> int:
        try:
            fd = os.open(self.rd.file(RESULTS), flags | _NOFOLLOW, 0o666)
        except OSError as e:
            why = "a symbolic link (not followed)" if e.errno == errno.ELOOP else (e.strerror or str(e))
            raise RunDirError(f"{self.path / RESULTS}: {why}") from None
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
            os.close(fd)
            raise RunDirError(f"{self.path / RESULTS}: not a plain file of this study; "
                              "refusing to write it")
        return fd

    def _mend_torn_tail(self) -> None:
        """Drop a last line left without its newline by a killed writer."""
        if not os.path.lexists(self.rd.file(RESULTS)):
            return
        fd = self._open(os.O_RDWR)
        try:
            size = os.fstat(fd).st_size
            if size == 0 or os.pread(fd, 1, size - 1) == b"\n":
                return
            data = os.pread(fd, size, 0)
            os.ftruncate(fd, data.rfind(b"\n") + 1)
            os.fsync(fd)
        finally:
            os.close(fd)

    def append(self, row: dict) -> None:
        """One row, whole or not at all."""
        line = row_line(row).encode("utf-8")
        fd = self._open(os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        try:
            n = os.write(fd, line)
            if n != len(line):               # a short write: undo it, never leave half a row
                os.ftruncate(fd, os.fstat(fd).st_size - n)
                raise OSError(errno.EIO, f"cannot append to {self.path / RESULTS}: short write")
            os.fsync(fd)
        finally:
            os.close(fd)

    def write_controller(self, name: str, record: dict) -> str:
        """``controllers/NAME.json`` (compact, atomic); returns its path in the study."""
        rel = f"{CONTROLLERS}/{name}.json"
        text = json.dumps(envelope("best", record), sort_keys=True, separators=(",", ":"),
                          allow_nan=False) + "\n"
        atomic_write_text(Path(self.rd.file(CONTROLLERS)) / f"{name}.json", text)
        return rel
