"""A writer's directory (a run, a compose search, a study): its records with
exactly one writer, checked before anything is changed.

API for every writer of a directory (``gpmotion run``/``resume``,
``gpmotion compose``, ``gpmotion study``)::

    rd = RunDir.create(path)               # new (or empty) directory, locked
    rd = RunDir.create(path, force=True)   # an existing one is moved aside first
    rd = RunDir.open(path)                 # an existing one, locked, to continue
    rd.read_bytes(name) / rd.read_text(name) / rd.read_json(name, kind)
    rd.write_text(name, text) / rd.write_json(name, kind, obj)   # atomic
    rd.log_rows([dict, ...]) / rd.read_log() / rd.log_prefix(n) / rd.trim_log(n)
    rd.names(); rd.exists(name); rd.file(name)   # a path for other libraries' writers
    rd.close()                             # or ``with RunDir.open(path) as rd:``
    plain_name(text, what)                 # a name that becomes a path: checked
    read_regular(path) / read_text(path)   # (gpmotion.records) any input file

* **One writer.**  :meth:`RunDir.create` takes an exclusive ``flock`` on the
  directory itself (a descriptor of its own), held until :meth:`close` or the
  process dies (the kernel releases it, so a SIGKILLed run never blocks its
  own resume).  Deleting ``.lock`` (which only names the holder's pid) cannot
  unlock it.  A second writer on a live directory is refused with one line.
* **Writes go through the directory we locked**, not through its name: files
  are opened relative to our descriptor of the directory (paths handed out
  are ``/proc/self/fd/N/NAME``), so a run whose directory was renamed or
  replaced keeps writing into its own files, never into a newcomer's.
* **Symlinks inside the directory are never followed**: reads and log appends
  open with ``O_NOFOLLOW`` (and refuse hard-linked files), JSON and artifacts
  are replaced by rename (which replaces a link, never its target).
* **Regular files only, never blocking**: every read opens non-blocking and
  checks ``fstat`` first, so a FIFO, a directory or a device in place of a
  record is one error line, never a hang.
* **One line ending** (``\n``) in every log; a torn last line is dropped.
* Temp files left by a killed writer (``.NAME.PID.HEX.tmp``) are removed when
  the next writer takes the lock.
"""
from __future__ import annotations

import csv
import errno
import fcntl
import io
import json
import os
import stat
import time
from pathlib import Path
from typing import Any

import numpy as np

from .records import (_DISPLAY, DEFAULT_MAX_BYTES, FormatError, RunDirError, _no_duplicates,
                      _reject_constant, atomic_write_json, atomic_write_text, envelope,
                      display_path, parse_json, read_regular)  # noqa: F401 (display_path: re-exported)

LOCK = ".lock"
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


def _busy(path: Path, pid_fd: int) -> RunDirError:
    try:
        pid = os.pread(pid_fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        pid = ""
    who = f" (pid {pid})" if pid.isdigit() else ""
    return RunDirError(f"run directory {path} is in use by another gpmotion process{who}; "
                       "wait for it to finish or stop it first")


class _Lock:
    """An exclusive flock on the directory itself (a descriptor of our own on
    it, opened through ``dirfd``): deleting or replacing ``.lock`` cannot
    unlock it.  ``.lock`` only says who holds the lock (and is the write probe)."""

    def __init__(self, path: Path, dirfd: int):
        try:
            fd = os.open(LOCK, os.O_RDWR | os.O_CREAT | _NOFOLLOW | os.O_NONBLOCK, 0o666,
                         dir_fd=dirfd)
        except OSError as e:
            why = "it is a symbolic link" if e.errno == errno.ELOOP else (e.strerror or str(e))
            raise RunDirError(f"cannot write run directory {path}: {LOCK}: {why}") from None
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            os.close(fd)
            raise RunDirError(f"cannot lock run directory {path}: {LOCK} is not a regular file")
        lock = os.open(".", os.O_RDONLY | getattr(os, "O_DIRECTORY", 0), dir_fd=dirfd)
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            err = _busy(path, fd) if e.errno in (errno.EWOULDBLOCK, errno.EACCES) else \
                RunDirError(f"cannot lock run directory {path}: {e.strerror or e}")
            os.close(fd)
            os.close(lock)
            raise err from None
        if st.st_nlink == 1:              # ours alone: say who holds it
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        os.close(fd)
        self.fd = lock

    def release(self):
        if self.fd is not None:
            os.close(self.fd)             # closing the last descriptor drops the flock
            self.fd = None


_OPEN_LOCKS: list[_Lock] = []


def _drop_locks_in_child():
    """A forked child must not keep its parent's run locked after the parent dies."""
    for lk in _OPEN_LOCKS:
        if lk.fd is not None:
            try:
                os.close(lk.fd)
            except OSError:
                pass
            lk.fd = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_drop_locks_in_child)


def _entries(dirfd: int) -> list[str]:
    """Names in the directory that are a run's content (not the lock, not temp files)."""
    return [n for n in os.listdir(dirfd) if n != LOCK and not _is_temp(n)]


def _is_temp(name: str) -> bool:
    return name.startswith(".") and (name.endswith(".tmp") or name.startswith(".write-test."))


def _remove_temp(dirfd: int) -> None:
    for name in os.listdir(dirfd):
        if _is_temp(name):
            try:
                os.unlink(name, dir_fd=dirfd)
            except OSError:
                pass


def _nonempty(path: Path) -> bool:
    try:
        return any(n != LOCK and not _is_temp(n) for n in os.listdir(path))
    except OSError:
        return False


MAX_NAME = 100


def plain_name(text, what: str) -> str:
    """``text`` if it is a plain name that may become one path component (a
    study, a configuration, an artifact): not empty, at most MAX_NAME
    characters, no ``/``, ``\\`` or NUL, not ``.``/``..`` nor starting with
    ``.``, no control characters.  Otherwise a ValueError naming ``what``."""
    if not isinstance(text, str):
        raise ValueError(f"{what} must be a name (text), got {type(text).__name__}")
    why = ("is empty" if not text else
           f"is longer than {MAX_NAME} characters" if len(text) > MAX_NAME else
           "contains '/' or '\\'" if "/" in text or "\\" in text else
           "starts with '.'" if text.startswith(".") else
           "contains a control character" if any(ord(c) < 32 or ord(c) == 127 for c in text)
           else "")
    if why:
        r = repr(text)
        raise ValueError(f"{what} {r if len(r) <= 40 else r[:37] + '...'} {why}; "
                         "it must be a plain name (it becomes a file or folder name)")
    return text


def _check_rows(rows: list[dict], where) -> None:
    """Rows a resume keeps: every column of the header filled, no extra field,
    generation and evaluations whole numbers that never go down (a mangled row
    is refused, not carried into the continued log)."""
    last = (-1, 0)
    for i, r in enumerate(rows, 1):
        if None in r or any(v is None for v in r.values()):
            raise FormatError(f"{where}: row {i} does not have the header's columns")
        try:
            now = (int(r.get("generation", 0)), int(r.get("evaluations", 0)))
        except ValueError:
            raise FormatError(f"{where}: row {i}: generation and evaluations must be whole "
                              "numbers") from None
        if now[0] < last[0] or now[1] < last[1] or min(now) < 0:
            raise FormatError(f"{where}: row {i} goes back (generation {now[0]}, "
                              f"{now[1]} evaluations after {last[0]}, {last[1]})")
        last = now


class RunDir:
    """One run's directory (see the module docstring).

    Build with :meth:`create`; an existing run is never overwritten or
    deleted — ``force`` moves it aside, ``resume`` continues it.
    """

    CONFIG, LOG, BEST, CHECKPOINT = "config.json", "log.csv", "best.json", "checkpoint.json"

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.backup: Path | None = None
        self._fields: list[str] | None = None
        self._dirfd: int | None = None
        self._lock: _Lock | None = None
        self._base = self.path            # where files are opened: /proc/self/fd/N

    # ------------------------------------------------------------ lifetime
    @classmethod
    def create(cls, path: str | os.PathLike, *, force: bool = False,
               resume: bool = False) -> "RunDir":
        """Create (or reopen, with ``resume``) and lock a run directory."""
        path = Path(path)
        if force and resume:
            raise RunDirError("choose either --force or --resume, not both")
        if path.exists() and not path.is_dir():
            raise RunDirError(f"run directory {path} exists and is not a directory")
        if resume and not path.is_dir():
            raise RunDirError(f"run directory {path} does not exist")
        run = cls(path)
        if path.is_dir() and _nonempty(path) and not resume:
            if not force:
                raise RunDirError(
                    f"run directory {path} exists and is not empty; pass --force "
                    "to move it aside or --resume to continue it")
            run.backup = cls._move_aside(path)
        try:
            path.mkdir(parents=True, exist_ok=True)
            run._dirfd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError as e:
            raise RunDirError(f"cannot write run directory {path}: "
                              f"{e.strerror or e}") from None
        try:
            run._take(force or not resume)
        except BaseException:
            run.close()
            raise
        return run

    @property
    def current_path(self) -> Path:
        """Where the directory we hold is now (renamed since: its new name), for
        hints such as `gpmotion resume PATH`; the given path when unknown."""
        if self._dirfd is not None:
            try:
                now = os.readlink(f"/proc/self/fd/{self._dirfd}")
            except OSError:
                return self.path
            if now.startswith("/") and not now.endswith(" (deleted)"):
                return Path(now) if Path(now).resolve() != self.path.resolve() else self.path
        return self.path

    def clean_temp(self, folder: str) -> None:
        """Remove a killed writer's temp files from ``folder`` inside the directory
        (a link there is not followed); the directory itself is cleaned when locked."""
        try:
            fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | _NOFOLLOW, dir_fd=self._dirfd)
        except OSError:
            return
        try:
            _remove_temp(fd)
        finally:
            os.close(fd)

    @classmethod
    def open(cls, path: str | os.PathLike) -> "RunDir":
        """An existing directory, locked, to continue writing it."""
        return cls.create(path, resume=True)

    def _take(self, must_be_empty: bool) -> None:
        self._lock = _Lock(self.path, self._dirfd)      # also the write probe
        _OPEN_LOCKS.append(self._lock)
        if must_be_empty and _entries(self._dirfd):     # another writer came and went
            raise RunDirError(f"run directory {self.path} exists and is not empty; pass "
                              "--force to move it aside or --resume to continue it")
        _remove_temp(self._dirfd)                       # temp files of a killed writer
        proc = Path(f"/proc/self/fd/{self._dirfd}")
        if proc.is_dir():
            self._base = proc
            _DISPLAY[str(proc)] = self.path

    def close(self) -> None:
        """Release the lock (idempotent); the files stay."""
        _DISPLAY.pop(str(self._base), None)
        self._base = self.path
        if self._lock is not None:
            self._lock.release()
            if self._lock in _OPEN_LOCKS:
                _OPEN_LOCKS.remove(self._lock)
            self._lock = None
        if self._dirfd is not None:
            os.close(self._dirfd)
            self._dirfd = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @staticmethod
    def _move_aside(path: Path) -> Path:
        """Rename a finished (unlocked) run out of the way; a live one is refused."""
        stamp = time.strftime("%Y%m%d-%H%M%S")
        backup = path.with_name(f"{path.name}.bak-{stamp}")
        n = 1
        while backup.exists():
            backup = path.with_name(f"{path.name}.bak-{stamp}-{n}")
            n += 1
        try:
            dirfd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError as e:
            raise RunDirError(f"cannot move {path} aside: {e.strerror or e}") from None
        lock = None
        try:
            lock = _Lock(path, dirfd)           # refuses while its writer lives
            os.rename(path, backup)
        except OSError as e:
            raise RunDirError(f"cannot move {path} aside to {backup}: "
                              f"{e.strerror or e}") from None
        finally:
            if lock is not None:
                lock.release()
            os.close(dirfd)
        return backup

    # ------------------------------------------------------------ paths
    def file(self, name: str) -> Path:
        """Where to open ``name`` (a plain file name) inside this run."""
        if not name or name in (".", "..") or "/" in name or "\\" in name or "\0" in name:
            raise ValueError(f"artifact name must be a plain file name, got {name!r}")
        return self._base / name

    artifact = file

    def _at(self, name: str) -> tuple[str | Path, int | None]:
        """(what to open, dir_fd): the name relative to our descriptor when we hold one."""
        self.file(name)                                   # a plain name
        return (name, self._dirfd) if self._dirfd is not None else (self.path / name, None)

    def exists(self, name: str) -> bool:
        return os.path.lexists(self.file(name))

    def names(self) -> list[str]:
        """The directory's entries (not the lock, not temp files), sorted."""
        if self._dirfd is not None:
            return sorted(_entries(self._dirfd))
        return sorted(n for n in os.listdir(self.path) if n != LOCK and not _is_temp(n))

    def read_bytes(self, name: str, max_bytes: int = DEFAULT_MAX_BYTES) -> bytes:
        """A regular file's bytes: a symlink is refused (not followed), a FIFO never
        waited on, anything over ``max_bytes`` refused (one FormatError line)."""
        where, dirfd = self._at(name)
        return read_regular(where, max_bytes, dir_fd=dirfd, follow=False,
                            shown=self.path / name)

    def read_text(self, name: str, max_bytes: int = DEFAULT_MAX_BYTES) -> str:
        data = self.read_bytes(name, max_bytes)
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise FormatError(f"{self.path / name}: not UTF-8 text (byte {e.start})") from None

    def read_json(self, name: str, kind: str, max_bytes: int = DEFAULT_MAX_BYTES) -> dict:
        return parse_json(self.read_bytes(name, max_bytes), kind=kind, source=str(self.path / name))

    def write_text(self, name: str, text: str) -> Path:
        """Replace ``name`` atomically (temp file, fsync, rename: a link is replaced,
        never followed); returns the path as the user knows it."""
        atomic_write_text(self.file(name), text)
        return self.path / name

    def write_json(self, name: str, kind: str, obj: dict) -> Path:
        """``obj`` in a ``gpmotion-KIND`` envelope, written atomically."""
        atomic_write_json(self.file(name), envelope(kind, obj))
        return self.path / name

    # ------------------------------------------------------------ JSON records
    def write_config(self, config: dict) -> Path:
        atomic_write_json(self.file(self.CONFIG), envelope("config", config))
        return self.path / self.CONFIG

    def read_config(self) -> dict:
        return self.read_json(self.CONFIG, "config")

    def write_best(self, best: dict) -> Path:
        atomic_write_json(self.file(self.BEST), envelope("best", best))
        return self.path / self.BEST

    @property
    def checkpoint_path(self) -> Path:
        return self.path / self.CHECKPOINT

    def has_checkpoint(self) -> bool:
        return self.exists(self.CHECKPOINT)

    def save_checkpoint(self, state: dict) -> Path:
        atomic_write_json(self.file(self.CHECKPOINT), envelope("checkpoint", state))
        return self.checkpoint_path

    def load_checkpoint(self, *, max_bytes: int = DEFAULT_MAX_BYTES) -> dict:
        return self.read_json(self.CHECKPOINT, "checkpoint", max_bytes)

    # ------------------------------------------------------------ log.csv
    @property
    def log_path(self) -> Path:
        return self.path / self.LOG

    def _open_log_fd(self, flags: int) -> int:
        """Open log.csv without following a link; refuse one hard-linked elsewhere."""
        try:
            where, dirfd = self._at(self.LOG)
            fd = os.open(where, flags | _NOFOLLOW | os.O_NONBLOCK, 0o666, dir_fd=dirfd)
        except OSError as e:
            why = "it is a symbolic link (not followed)" if e.errno == errno.ELOOP else \
                (e.strerror or str(e))
            raise OSError(e.errno, f"cannot write {self.log_path}: {why}") from None
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
            os.close(fd)
            raise RunDirError(f"{self.log_path}: not a plain file of this run (a link, a FIFO?); "
                              "refusing to write it")
        os.set_blocking(fd, True)
        return fd

    def _open_log(self) -> list[str] | None:
        """Header of an existing log (dropping a torn last line), or None."""
        if not self.exists(self.LOG):
            return None
        with open(self._open_log_fd(os.O_RDWR), "rb+") as f:
            data = f.read()
            if data and not data.endswith(b"\n"):
                keep = data.rfind(b"\n") + 1  # 0 if even the header is torn
                f.truncate(keep)
                f.flush()
                os.fsync(f.fileno())
                data = data[:keep]
        if not data:
            return None
        header = data.split(b"\n", 1)[0].decode("utf-8").rstrip("\r")
        return next(csv.reader([header]))

    def log_row(self, row: dict) -> None:
        """Append one row to log.csv and fsync it."""
        self.log_rows([row])

    def log_rows(self, rows: list[dict]) -> None:
        """Append rows to log.csv with one write and one fsync.

        The header comes from the first row's keys (or the existing file's
        header on resume); later rows may omit keys (blank cells) but not add
        new ones.  Newlines inside values are replaced by spaces so that one
        row is always one line — what makes torn-line recovery sound.
        """
        if not rows:
            return
        if self._fields is None:
            self._fields = self._open_log()
            write_header = self._fields is None
            if write_header:
                self._fields = [str(k) for k in rows[0]]
        else:
            write_header = False
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        if write_header:
            writer.writerow(self._fields)
        for row in rows:
            extra = [k for k in row if str(k) not in self._fields]
            if extra:
                raise ValueError(f"{self.log_path}: row has columns {extra} not in "
                                 f"the header {self._fields}")
            cells = {str(k): v for k, v in row.items()}
            writer.writerow([_cell(cells.get(k)) for k in self._fields])
        data = buf.getvalue().encode("utf-8")
        fd = self._open_log_fd(os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        try:
            while data:
                data = data[os.write(fd, data):]
            os.fsync(fd)
        except OSError as e:
            raise OSError(e.errno, f"cannot write {self.log_path}: {e.strerror or e}") from None
        finally:
            os.close(fd)

    def read_log(self) -> list[dict[str, str]]:
        """Rows of log.csv as dicts of strings (complete lines only)."""
        if not self.exists(self.LOG):
            return []
        text = self.read_bytes(self.LOG, 1 << 30).decode("utf-8", "replace")
        if not text.endswith("\n"):
            text = text[: text.rfind("\n") + 1]
        return list(csv.DictReader(io.StringIO(text)))

    def log_prefix(self, n_rows: int) -> list[dict[str, str]]:
        """The first ``n_rows`` rows of log.csv, changing nothing: a resume checks
        them against its checkpoint before :meth:`trim_log` drops the rest."""
        if not self.exists(self.LOG):
            if n_rows:
                raise FormatError(f"{self.log_path}: missing, but the checkpoint was taken "
                                  f"after {n_rows} rows of it")
            return []
        rows = self.read_log()
        if len(rows) < n_rows:
            raise FormatError(f"{self.log_path}: {len(rows)} rows, fewer than the {n_rows} "
                              "the checkpoint was taken after")
        _check_rows(rows[:n_rows], self.log_path)
        return rows[:n_rows]

    def trim_log(self, n_rows: int) -> None:
        """Keep the header and the first ``n_rows`` rows (rows written after the
        checkpoint that a resume continues from are dropped); atomic."""
        if not self.exists(self.LOG):
            if n_rows:
                raise FormatError(f"{self.log_path}: missing, but the checkpoint was taken "
                                  f"after {n_rows} rows of it")
            return
        text = self.read_bytes(self.LOG, 1 << 30).decode("utf-8", "replace")
        end = -1
        for _ in range(1 + n_rows if n_rows else 0):     # header + n rows, one line each
            end = text.find("\n", end + 1)
            if end < 0:
                raise FormatError(f"{self.log_path}: fewer than the {n_rows} rows "
                                  "the checkpoint was taken after")
        keep = text[:end + 1]
        if keep != text:
            atomic_write_text(self.file(self.LOG), keep)
        self._fields = None


    # ------------------------------------------------------------ generations.jsonl
    GENERATIONS = "generations.jsonl"

    def append_generations(self, records: list[dict]) -> None:
        """Append film records (gpmotion.generations), one JSON line each, one write
        and one fsync; a link or a hard-linked file is refused as for log.csv."""
        if not records:
            return
        data = "".join(json.dumps(r, separators=(",", ":"), allow_nan=False) + "\n"
                       for r in records).encode("utf-8")
        try:
            fd = os.open(self.file(self.GENERATIONS), os.O_WRONLY | os.O_APPEND | os.O_CREAT
                         | _NOFOLLOW | os.O_NONBLOCK, 0o666)
        except OSError as e:
            why = "it is a symbolic link (not followed)" if e.errno == errno.ELOOP else \
                (e.strerror or str(e))
            raise OSError(e.errno, f"cannot write {self.path / self.GENERATIONS}: {why}") from None
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
                raise RunDirError(f"{self.path / self.GENERATIONS}: not a plain file of this "
                                  "run (a link?); refusing to write it")
            while data:
                data = data[os.write(fd, data):]
            os.fsync(fd)
        finally:
            os.close(fd)

    def read_generations(self) -> list[dict]:
        """The film records (complete lines only); [] when the run has none."""
        if not self.exists(self.GENERATIONS):
            return []
        text = self.read_bytes(self.GENERATIONS, 1 << 30).decode("utf-8", "replace")
        out = []
        for n, line in enumerate(text.split("\n")[:-1], 1):   # the last piece: torn or ""
            try:
                rec = json.loads(line, parse_constant=_reject_constant,
                                 object_pairs_hook=_no_duplicates)
            except (ValueError, RecursionError):
                rec = None
            if not isinstance(rec, dict) or type(rec.get("generation")) is not int:
                raise FormatError(f"{self.path / self.GENERATIONS}:{n}: not a generation record")
            out.append(rec)
        return out

    def trim_generations(self, last_generation: int) -> list[dict]:
        """Keep the records up to ``last_generation`` (a resume's checkpoint; -1:
        none), dropping a torn last line; atomic.  Returns the records kept."""
        if not self.exists(self.GENERATIONS):
            return []
        keep = [r for r in self.read_generations() if r["generation"] <= last_generation]
        text = "".join(json.dumps(r, separators=(",", ":"), allow_nan=False) + "\n" for r in keep)
        old = self.read_bytes(self.GENERATIONS, 1 << 30).decode("utf-8", "replace")
        if text != old:
            atomic_write_text(self.file(self.GENERATIONS), text)
        return keep


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float):
        return repr(v)  # round-trips exactly; inf/nan as 'inf'/'nan'
    return str(v).replace("\r", " ").replace("\n", " ")
