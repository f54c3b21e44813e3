"""Run directories and safe JSON (DESIGN.md §8 and "Formats and safety").

A run may be killed at any instant (Ctrl-C, OOM, a cluster pre-empting the
job), and its files may later be loaded by someone else's gpmotion.  So:

* every JSON file is written atomically (temp file in the same directory,
  fsync, ``os.replace``, fsync the directory): a reader sees the old file or
  the new one, never half of either;
* ``log.csv`` is appended and fsynced in batches just before each checkpoint,
  and a torn last line left by a crash is dropped on resume (the run
  directory itself, with its lock, is :mod:`gpmotion.rundir`);
* loading parses with :mod:`json` only (never ``eval``/``pickle``), caps the
  size, checks a ``"format": "gpmotion-<kind>"`` / ``"version": 1`` envelope
  and turns every problem into one :class:`FormatError` line naming the file.

Non-finite floats: JSON has no NaN/inf, and encoding them as strings would be
ambiguous with genuine strings, so :func:`atomic_write_json` *refuses* them
with a ValueError naming where in the object they sit (e.g.
``best.fitness``).  Callers map a diverged score to ``None`` or a finite
penalty before saving.  :func:`read_json` likewise rejects ``NaN``/
``Infinity`` literals that Python's json would otherwise accept.
"""
from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import stat
import random
import secrets
from pathlib import Path
from typing import Any, Iterator

import numpy as np

FORMAT_VERSION = 1
DEFAULT_MAX_BYTES = 32 * 1024 * 1024


class FormatError(ValueError):
    """A file (or JSON blob) is malformed, truncated, too big, or not ours."""


class ConfigError(ValueError):
    """A user-supplied setting is invalid; the message is one clear line."""


class RunDirError(ConfigError):
    """A run directory cannot be created, reused or written."""


# --------------------------------------------------------------- atomic I/O

def _fsync_dir(directory: Path) -> None:
    """Make a rename durable; silently skipped where directories can't be
    opened (Windows) — the rename itself is still atomic there."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temp path beside ``path``; on success fsync it and move it into
    place, on any exception delete it and leave ``path`` untouched.

    Used for files written by other libraries (matplotlib, PIL), too.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(e, OSError) and not e.filename:     # ENOSPC from write(): name the file
            raise OSError(e.errno, f"cannot write {_shown(path)}: {e.strerror or e}") from None
        raise
    _fsync_dir(path.parent)


# A RunDir (gpmotion.rundir) writes through /proc/self/fd/N, its directory's
# descriptor, which means nothing to a reader: it records here the path the
# user gave, so every message shows that path.
_DISPLAY: dict[str, Path] = {}       # "/proc/self/fd/N" -> the path the user gave


def display_path(path: str | os.PathLike) -> Path:
    """``path`` with a RunDir's /proc/self/fd/N prefix shown as the run directory."""
    s = str(path)
    for prefix, real in _DISPLAY.items():
        if s == prefix or s.startswith(prefix + "/"):
            return Path(str(real) + s[len(prefix):])
    return Path(s)


def _shown(path: Path) -> Path:
    """A path as the user knows it (see :func:`display_path`)."""
    return display_path(path)


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically and durably."""
    data = text.encode("utf-8")
    with atomic_output(path) as tmp:
        # O_EXCL: never follow or clobber something already at the temp name;
        # mode 0o666 lets the umask decide permissions, like a plain open().
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        with open(fd, "wb") as f:
            f.write(data)
            f.flush()


def to_jsonable(obj: Any, where: str = "$") -> Any:
    """Plain JSON data from dicts/lists/tuples/numpy scalars and arrays.

    Raises ValueError on non-finite floats and TypeError on anything JSON
    can't represent, naming the position (``$.population[3].fitness``).
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item(), where)
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        if not math.isfinite(obj):
            raise ValueError(f"non-finite float {obj!r} at {where} cannot be "
                             "stored in JSON (map it to None or a finite value)")
        return float(obj)
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist(), where)
    if isinstance(obj, dict):
        out = {}
        for k, v in obj.items():
            if isinstance(k, np.str_):
                k = str(k)
            if not isinstance(k, str):
                raise TypeError(f"dict key {k!r} at {where} is not a string")
            out[k] = to_jsonable(v, f"{where}.{k}")
        return out
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v, f"{where}[{i}]") for i, v in enumerate(obj)]
    raise TypeError(f"{type(obj).__name__} at {where} is not JSON-serializable")


def atomic_write_json(path: str | os.PathLike, obj: Any) -> None:
    """Serialize first (so a bad object never touches the disk), then write
    atomically.  Non-finite floats are an error (see module docstring)."""
    text = json.dumps(to_jsonable(obj), allow_nan=False, indent=1,
                      ensure_ascii=False) + "\n"
    atomic_write_text(path, text)


def envelope(kind: str, obj: dict) -> dict:
    """``obj`` with ``format``/``version`` keys first; a conflicting existing
    envelope is an error rather than silently overwritten."""
    fmt = f"gpmotion-{kind}"
    if obj.get("format", fmt) != fmt or obj.get("version", FORMAT_VERSION) != FORMAT_VERSION:
        raise ValueError(f"object already carries format={obj.get('format')!r} "
                         f"version={obj.get('version')!r}, not {fmt!r} v{FORMAT_VERSION}")
    return {"format": fmt, "version": FORMAT_VERSION,
            **{k: v for k, v in obj.items() if k not in ("format", "version")}}


# ------------------------------------------------------------------ reading

def _reject_constant(name: str):
    raise ValueError(f"non-standard JSON constant {name}")


def _no_duplicates(pairs: list) -> dict:
    out = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"duplicate key {k!r}")
        out[k] = v
    return out


def parse_json(text: str | bytes, *, kind: str, source: str = "<json>") -> dict:
    """Check a JSON document carries our ``kind`` envelope; return the object.

    Every failure is a :class:`FormatError` whose single line starts with
    ``source``.
    """
    def fail(problem: str) -> FormatError:
        return FormatError(f"{source}: {problem}")

    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as e:
            raise fail(f"not UTF-8 text (byte {e.start})") from None
    try:
        obj = json.loads(text, parse_constant=_reject_constant,
                         object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as e:
        raise fail(f"malformed or truncated JSON ({e.msg} at line {e.lineno} "
                   f"column {e.colno})") from None
    except RecursionError:
        raise fail("JSON nested too deeply") from None
    except ValueError as e:  # constants, duplicates, over-long integers
        raise fail(f"invalid JSON ({(str(e).splitlines() or ['?'])[0]})") from None
    fmt = f"gpmotion-{kind}"
    if not isinstance(obj, dict):
        raise fail(f"expected a JSON object with format {fmt!r}, "
                   f"got {type(obj).__name__}")
    if obj.get("format") != fmt:
        raise fail(f"expected format {fmt!r}, got {_short(obj.get('format'))}")
    version = obj.get("version")
    if type(version) is not int or version != FORMAT_VERSION:
        raise fail(f"unsupported {fmt} version {_short(version)} "
                   f"(this gpmotion reads version {FORMAT_VERSION})")
    return obj


def _short(value: Any) -> str:
    r = repr(value)
    return r if len(r) <= 60 else r[:57] + "..."


def read_regular(path: str | os.PathLike, max_bytes: int = DEFAULT_MAX_BYTES, *,
                 dir_fd: int | None = None, follow: bool = True,
                 shown: str | os.PathLike | None = None) -> bytes:
    """The bytes of a regular file, never blocking and never unbounded.

    The open is non-blocking (a FIFO in place of the file opens at once and is
    refused, it never waits for a writer), ``fstat`` decides (a directory, a
    FIFO, a device: refused), and at most ``max_bytes`` are read (``+1`` to
    detect more).  ``dir_fd``: ``path`` is a name inside that open directory;
    ``follow=False``: a symbolic link is refused, not followed.  Every problem
    is one :class:`FormatError` line naming ``shown`` (default ``path``).
    """
    shown = display_path(shown if shown is not None else path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    if not follow:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags, dir_fd=dir_fd)
    except OSError as e:
        if e.errno == errno.ELOOP and not follow:
            raise FormatError(f"{shown}: a symbolic link (not followed)") from None
        raise FormatError(f"{shown}: cannot read ({e.strerror or e})") from None
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):
            raise FormatError(f"{shown}: cannot read (a directory, not a file)")
        if not stat.S_ISREG(mode):
            raise FormatError(f"{shown}: cannot read (not a regular file: a FIFO, socket or device)")
        chunks, left = [], max_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    except OSError as e:
        raise FormatError(f"{shown}: cannot read ({e.strerror or e})") from None
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > max_bytes:
        raise FormatError(f"{shown}: larger than the {max_bytes}-byte limit")
    return data


def read_text(path: str | os.PathLike, max_bytes: int = DEFAULT_MAX_BYTES, **kw) -> str:
    """:func:`read_regular` decoded as UTF-8 (anything else: one FormatError line)."""
    data = read_regular(path, max_bytes, **kw)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        shown = display_path(kw.get("shown") or path)
        raise FormatError(f"{shown}: not UTF-8 text (byte {e.start})") from None


def read_json(path: str | os.PathLike, *, kind: str,
              max_bytes: int = DEFAULT_MAX_BYTES) -> dict:
    """Load a ``gpmotion-<kind>`` v1 JSON file, refusing anything else.

    Reads at most ``max_bytes`` (+1 to detect overflow), so a huge or endless
    file (``/dev/zero``) cannot exhaust memory, and only a regular file (a
    FIFO is refused, never waited on).  Unreadable files are a FormatError
    too, so a CLI can print one line and exit 2.
    """
    path = Path(path)
    return parse_json(read_regular(path, max_bytes), kind=kind, source=str(display_path(path)))


# ---------------------------------------------------------- config checking

def validate_number(name: str, value: Any, *, lo: float | None = None,
                    hi: float | None = None, integer: bool = False,
                    allow_none: bool = False):
    """Return ``value`` as int/float if it is finite and within [lo, hi].

    Otherwise raise ConfigError with one line such as
    ``--generations must be an integer ≥ 1, got -3``.  Strings are parsed
    (values from the command line or an environment variable); booleans are
    rejected (``True`` is not a population size).
    """
    kind = "an integer" if integer else "a number"
    if lo is not None and hi is not None:
        need = f"{kind} between {lo} and {hi}"
    elif lo is not None:
        need = f"{kind} ≥ {lo}"
    elif hi is not None:
        need = f"{kind} ≤ {hi}"
    else:
        need = kind if integer else "a finite number"
    if allow_none:
        need += " (or none)"

    def fail() -> ConfigError:
        return ConfigError(f"{name} must be {need}, got {_short(value)}")

    if value is None:
        if allow_none:
            return None
        raise fail()
    x = value
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, bool):
        raise fail()
    if isinstance(x, str):
        try:
            x = int(x.strip()) if integer else float(x.strip())
        except ValueError:
            try:
                x = float(x.strip())
            except ValueError:
                raise fail() from None
    if not isinstance(x, (int, float)):
        raise fail()
    if isinstance(x, float):
        if not math.isfinite(x):
            raise fail()
        if integer:
            if not x.is_integer():
                raise fail()
            x = int(x)
    if (lo is not None and x < lo) or (hi is not None and x > hi):
        raise fail()
    return x


# ------------------------------------------------------------- RNG states

def python_random_state_to_json(state: tuple | None = None) -> dict:
    """``random.getstate()`` (default: the global one) as JSON data.

    DEAP's operators draw from Python's ``random``; saving it in every
    checkpoint makes a resumed run continue the same sequence.
    """
    if state is None:
        state = random.getstate()
    version, internal, gauss_next = state
    return {"version": int(version), "internal": [int(v) for v in internal],
            "gauss_next": gauss_next}


def python_random_state_from_json(d: Any) -> tuple:
    """Validated inverse: a tuple for ``random.setstate``."""
    def fail(problem: str) -> FormatError:
        return FormatError(f"python random state: {problem}")
    if not isinstance(d, dict):
        raise fail("expected an object")
    if d.get("version") != 3 or type(d.get("version")) is not int:
        raise fail(f"unsupported version {_short(d.get('version'))}")
    internal = d.get("internal")
    if (not isinstance(internal, list) or len(internal) != 625
            or any(type(v) is not int for v in internal)):
        raise fail("'internal' must be a list of 625 integers")
    if any(not 0 <= v < 2**32 for v in internal[:624]) or not 0 <= internal[624] <= 624:
        raise fail("'internal' value out of range")
    g = d.get("gauss_next")
    if g is not None and (type(g) is not float or not math.isfinite(g)):
        raise fail("'gauss_next' must be null or a finite float")
    return (3, tuple(internal), g)


_BIT_GENERATORS = ("PCG64", "PCG64DXSM", "Philox", "SFC64", "MT19937")


def numpy_rng_state_to_json(gen: np.random.Generator | np.random.BitGenerator) -> dict:
    """``gen.bit_generator.state`` with arrays as lists (its ints may be
    128-bit; Python's json keeps them exact)."""
    bitgen = gen.bit_generator if isinstance(gen, np.random.Generator) else gen
    return to_jsonable(bitgen.state)


def _check_state_leaves(x: Any, where: str) -> None:
    if isinstance(x, dict):
        for k, v in x.items():
            _check_state_leaves(v, f"{where}.{k}")
    elif isinstance(x, list):
        if len(x) > 1000:
            raise FormatError(f"numpy rng state: {where} too long")
        for i, v in enumerate(x):
            _check_state_leaves(v, f"{where}[{i}]")
    elif type(x) is int:
        if not 0 <= x < 2**128:
            raise FormatError(f"numpy rng state: {where} out of range")
    elif not isinstance(x, str):
        raise FormatError(f"numpy rng state: {where} must be an integer")


def numpy_rng_from_json(d: Any) -> np.random.Generator:
    """A ``numpy.random.Generator`` continuing exactly from a saved state.

    Only numpy's own bit generators are accepted, by name.
    """
    if not isinstance(d, dict) or d.get("bit_generator") not in _BIT_GENERATORS:
        name = d.get("bit_generator") if isinstance(d, dict) else None
        raise FormatError(f"numpy rng state: unknown bit generator {_short(name)}")
    _check_state_leaves(d, "$")
    bitgen = getattr(np.random, d["bit_generator"])()
    state = dict(d)
    try:
        if d["bit_generator"] == "MT19937":
            inner = dict(d.get("state") or {})
            key = inner.get("key")
            if not isinstance(key, list) or len(key) != 624 or max(key) >= 2**32:
                raise ValueError("MT19937 key must be 624 integers < 2**32")
            inner["key"] = np.asarray(key, dtype=np.uint32)
            state["state"] = inner
        bitgen.state = state
    except (ValueError, TypeError, KeyError, IndexError, OverflowError) as e:
        raise FormatError(f"numpy rng state: rejected by numpy ({e})") from None
    return np.random.Generator(bitgen)

