"""Plugins: code gpmotion runs besides its own (primitives, tasks, TOML figures).

One loader for the three kinds: a primitive or a task registers itself when
its module is imported (``@primitive``, ``@register_task``); a figure is a
TOML spec registered under its file name.

The rule: **a data file never runs code.**  Code runs only from

* folders the user names on the command line (``--plugins DIR``) or passes to
  :func:`load_folder` from Python -- and of such a folder only the modules its
  manifest names (below), and
* installed entry points of the ``gpmotion.plugins`` group (as Gymnasium's
  ``load_plugin_envs``): a package declares
  ``[project.entry-points."gpmotion.plugins"] mine = "mypkg.gpm"`` and the
  module (or the callable it names) is imported (called) once per process by
  :func:`load_entry_points`, before any registry lookup.

A plugin folder's manifest, ``gpmotion-plugin.toml``, names what the loader
reads, in order; nothing else in the folder runs or registers::

    modules = ["hypot", "lamp_stand_tall"]   # ./hypot.py, ./lamp_stand_tall.py
    figures = ["stiff_lamp"]                 # ./stiff_lamp.toml -> figure "stiff_lamp"

A folder without a manifest is read by the old rule (every ``*.py`` and
``*.toml`` whose name does not start with ``_``) with a warning; that rule
goes in the next release.

A run and its controller record the plugins they were made with as
*requirements* -- ``{"name", "digest", "path"}`` (the digest covers the
manifest and the files it names; the path is relative to the run directory
and for information only).  A command that reads a run (``resume``,
``replay``, ``render``, ``export``) checks them with :func:`require` against
what the user loaded and refuses with one line naming what is missing or
different.  Nothing read from a run's files is ever imported or resolved
against the current directory.

Process-pool and Dask workers get the plugin *sources* from the main process
(:func:`sources_of`), write them to a cache folder named by their digest,
check the digest and load that folder (:func:`install_sources`), so a remote
worker needs no shared file system.
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import pkgutil
import re
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10
    import tomli as tomllib

GROUP = "gpmotion.plugins"
MANIFEST = "gpmotion-plugin.toml"
SUFFIXES = (".py", ".toml")
MAX_PLUGINS = 64
MAX_FILES = 256                 # modules + figures one manifest may name
_HEX = re.compile(r"^[0-9a-f]{64}$")
_FILE_STEM = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,99}$")


class PluginError(ValueError):
    """A run needs plugins that are not loaded (or whose code differs); one line."""


# requirement records of everything loaded in this process, by digest
_LOADED: dict[str, dict] = {}
_FOLDERS: dict[Path, dict] = {}
_SOURCES: dict[str, dict[str, str]] = {}      # digest -> the files as hashed (shipped to workers)
_ENTRY_POINTS: dict[str, dict] = {}           # "name = value" -> its record, once loaded
_BUILTIN_LOADED = False


# ---- built-ins -------------------------------------------------------------------

def import_package(package: str) -> None:
    """Import every module of a built-in plugin package (gpmotion.tasks, ...), sorted."""
    pkg = importlib.import_module(package)
    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda i: i.name):
        if not info.name.startswith("_"):
            importlib.import_module(f"{package}.{info.name}")


def load_builtin() -> None:
    """The shipped primitives and tasks, then the installed entry points (once)."""
    global _BUILTIN_LOADED
    if _BUILTIN_LOADED:
        return
    _BUILTIN_LOADED = True
    from .gp import primitives
    primitives.load_builtin()
    import_package("gpmotion.tasks")
    load_entry_points()


# ---- folders ---------------------------------------------------------------------

@dataclass(frozen=True)
class Manifest:
    """What the loader reads from a folder: module stems and figure stems, in order."""
    modules: tuple[str, ...]
    figures: tuple[str, ...]
    declared: bool              # False: no manifest, the old every-file rule


def read_manifest(folder: str | Path) -> Manifest:
    """The folder's manifest, checked: one PluginError line for any problem."""
    folder = Path(folder)
    path = folder / MANIFEST
    if not path.is_file():
        files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix in SUFFIXES
                       and not p.name.startswith("_"))
        return Manifest(tuple(p.stem for p in files if p.suffix == ".py"),
                        tuple(p.stem for p in files if p.suffix == ".toml"), declared=False)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise PluginError(f"{path}: not valid TOML ({e})") from None
    unknown = sorted(set(data) - {"modules", "figures"})
    if unknown:
        raise PluginError(f"{path}: unknown key(s) {unknown}; a manifest has 'modules' and 'figures'")
    out = {}
    for key, suffix in (("modules", ".py"), ("figures", ".toml")):
        names = data.get(key, [])
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise PluginError(f"{path}: '{key}' must be a list of file names without {suffix}")
        if len(names) > MAX_FILES or len(set(names)) != len(names):
            raise PluginError(f"{path}: '{key}' names a file twice or more than {MAX_FILES} files")
        for n in names:
            if not _FILE_STEM.match(n):
                raise PluginError(f"{path}: '{key}' entry {_short(n)} is not a plain file name "
                                  f"(letters, digits, _; no {suffix}, no folders)")
            if not (folder / f"{n}{suffix}").is_file():
                raise PluginError(f"{path}: '{key}' names {n}{suffix}, which is not in {folder}")
        out[key] = tuple(names)
    if not out["modules"] and not out["figures"]:
        raise PluginError(f"{path}: names no modules and no figures")
    return Manifest(out["modules"], out["figures"], declared=True)


def plugin_files(folder: str | Path) -> list[Path]:
    """The files the loader reads (and the digest covers): the manifest and what it names."""
    folder = Path(folder)
    m = read_manifest(folder)
    files = [folder / f"{n}.py" for n in m.modules] + [folder / f"{n}.toml" for n in m.figures]
    return sorted(files + ([folder / MANIFEST] if m.declared else []))


def _digest_of(named_bytes: list[tuple[str, bytes]]) -> str:
    h = hashlib.sha256()
    for name, data in sorted(named_bytes):
        h.update(name.encode() + b"\0" + len(data).to_bytes(8, "little") + data)
    return h.hexdigest()


def folder_digest(folder: str | Path) -> str:
    """SHA-256 over the names and contents of a folder's plugin files."""
    return _digest_of(list(_read(folder).items()))


def _read(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in plugin_files(folder)}


def _import_file(path: Path, tag: str) -> None:
    """Import one plugin module under a name private to its folder (runs its decorators)."""
    modname = f"gpmotion_plugin_{tag}_{path.stem}"
    if modname in sys.modules:
        return
    spec = importlib.util.spec_from_file_location(modname, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[modname] = module
    try:
        spec.loader.exec_module(module)
    except Exception:
        del sys.modules[modname]
        raise


def load_folder(folder: str | Path) -> dict:
    """Load a plugin folder the *user* named; returns its requirement record.

    Imports the modules its manifest names, in order (their decorators register
    primitives and tasks), then registers its figures by file name.  Never call
    this with a path read from a file: that is what :func:`require` is for.
    """
    from .cache import digest
    from .figures import register_figure
    path = Path(os.fspath(folder)).resolve()
    if not path.is_dir():
        raise PluginError(f"--plugins: no such folder: {folder}")
    if path in _FOLDERS:
        return {k: v for k, v in _FOLDERS[path].items() if k != "folder"}
    manifest = read_manifest(path)
    files = _read(path)
    record = {"name": path.name, "digest": _digest_of(list(files.items()))}
    if record["digest"] in _LOADED:           # the same code from another place: loaded already
        return record
    load_builtin()                            # built-ins first, so a clash names the user's file
    if not manifest.declared:
        warnings.warn(f"plugin folder {path} has no {MANIFEST}: loading every *.py and *.toml in "
                      f"it (the old rule, removed in the next release); add a manifest naming "
                      f"them: modules = {list(manifest.modules)}, figures = {list(manifest.figures)}",
                      FutureWarning, stacklevel=2)
    tag = digest(str(path))
    for stem in manifest.modules:
        _import_file(path / f"{stem}.py", tag)
    for stem in manifest.figures:
        register_figure(stem, path / f"{stem}.toml")
    _FOLDERS[path] = _LOADED[record["digest"]] = {**record, "folder": str(path)}
    try:
        _SOURCES[record["digest"]] = {n: b.decode("utf-8") for n, b in files.items()}
    except UnicodeDecodeError:                # loaded here, but cannot travel to workers as text
        pass
    return record


# ---- entry points ------------------------------------------------------------------

def load_entry_points() -> list[dict]:
    """Import the installed ``gpmotion.plugins`` entry points; their requirement records.

    An entry point names a module (imported: its decorators register things) or
    a callable (called once, with no arguments).  Each is loaded once per
    process.  Its digest covers the entry point and the module's file.  One
    that fails to load is reported in a warning and skipped (as Gymnasium
    does), so one broken package does not stop every command; a run that
    needs it then says so.
    """
    from importlib.metadata import entry_points
    records = []
    for ep in sorted(entry_points(group=GROUP), key=lambda e: (e.name, e.value)):
        key = f"{ep.name} = {ep.value}"
        if key not in _ENTRY_POINTS:
            try:
                record = _load_entry_point(ep)
            except Exception as e:  # noqa: BLE001 - a broken installed plugin is reported, not fatal
                warnings.warn(f"gpmotion plugin entry point {key!r} failed to load "
                              f"({type(e).__name__}: {e}); skipped", RuntimeWarning, stacklevel=2)
                continue
            _ENTRY_POINTS[key] = _LOADED[record["digest"]] = record
        records.append(_ENTRY_POINTS[key])
    return records


def _load_entry_point(ep) -> dict:
    obj = ep.load()
    if callable(obj):
        obj()
    module = importlib.import_module(ep.module)
    src = Path(getattr(module, "__file__", "") or "")
    data = src.read_bytes() if src.is_file() else b""
    dist = getattr(ep, "dist", None)
    return {"name": ep.name, "digest": _digest_of([(ep.value, data)]), "entry_point": ep.value,
            "distribution": f"{dist.name}=={dist.version}" if dist else ""}


def activate(folders=()) -> list[dict]:
    """What a command does first: built-ins and entry points, then the ``--plugins`` folders.

    Returns the requirement records of what this command uses (what a new run records).
    """
    if isinstance(folders, (str, os.PathLike)):
        folders = [folders]
    load_builtin()
    records = load_entry_points() + [load_folder(f) for f in folders]
    # this command's plugins only (a long-lived process may have loaded others before)
    unique = {r["digest"]: r for r in records}
    return sorted(unique.values(), key=lambda r: (r["name"], r["digest"]))


def loaded() -> list[dict]:
    """Requirement records of the plugins loaded in this process (sorted by name)."""
    return sorted(({k: v for k, v in r.items() if k != "folder"} for r in _LOADED.values()),
                  key=lambda r: (r["name"], r["digest"]))


# ---- requirements in files ---------------------------------------------------------------

def parse_requirements(value, where: str) -> list[dict]:
    """A file's ``plugins`` field as requirement records (never a path to load).

    A list of ``{"name", "digest"[, "path", ...]}``; the legacy form (a list of
    folder paths) becomes name-only requirements.  A string is not a list.
    """
    if value is None:
        return []
    if not isinstance(value, list):
        raise PluginError(f"{where}: 'plugins' must be a list of plugin records, "
                          f"got {type(value).__name__}")
    if len(value) > MAX_PLUGINS:
        raise PluginError(f"{where}: 'plugins' lists {len(value)} plugins (at most {MAX_PLUGINS})")
    out = []
    for item in value:
        if isinstance(item, str) and 0 < len(item) <= 4096:            # legacy: a folder path
            name = item.replace("\\", "/").rstrip("/").rsplit("/", 1)[-1]
            out.append({"name": name, "digest": None, "path": item})
            continue
        if not (isinstance(item, dict) and isinstance(item.get("name"), str)
                and 0 < len(item["name"]) <= 200 and isinstance(item.get("digest"), str)
                and _HEX.match(item["digest"])
                and isinstance(item.get("path", ""), str) and len(item.get("path", "")) <= 4096):
            raise PluginError(f"{where}: 'plugins' holds a malformed record {_short(item)} "
                              "(expected {\"name\": ..., \"digest\": <sha256 hex>})")
        extra = {k: item[k] for k in ("path", "entry_point", "distribution")
                 if isinstance(item.get(k), str) and item[k] and len(item[k]) <= 4096}
        out.append({"name": item["name"], "digest": item["digest"], **extra})
    return out


def require(value, where: str) -> list[dict]:
    """Check a file's plugin requirements against what is loaded; raise one line if unmet.

    Returns the parsed requirements.  Loads nothing.
    """
    needs = parse_requirements(value, where)
    for need in needs:
        if need["digest"] is not None and need["digest"] in _LOADED:
            continue
        same_name = [r for r in _LOADED.values() if r["name"] == need["name"]]
        if need["digest"] is None and same_name:
            continue                                  # legacy record: name only
        if same_name:
            got = same_name[0]
            raise PluginError(
                f"{where} needs plugin {need['name']!r} with digest {need['digest'][:12]}, but the "
                f"loaded {need['name']!r} ({got.get('folder') or got.get('entry_point')}) has digest "
                f"{got['digest'][:12]}: its code differs from the code the run was made with")
        recorded = f", recorded at {need['path']}" if need.get("path") else ""
        digest = f"digest {need['digest'][:12]}" if need["digest"] else "no digest recorded"
        raise PluginError(f"{where} needs plugin {need['name']!r} ({digest}{recorded}); "
                          f"pass its folder with --plugins DIR (or install the package providing it)")
    return needs


def for_record(records, base: str | Path | None = None) -> list[dict]:
    """Requirement records to write into a file; ``path`` relative to ``base`` (info only)."""
    out = []
    for r in records:
        r = dict(r)
        folder = r.pop("folder", None) or _LOADED.get(r.get("digest"), {}).get("folder")
        if folder and base is not None:
            try:
                r["path"] = os.path.relpath(folder, Path(base).resolve())
            except ValueError:                 # another drive (Windows)
                r["path"] = folder
        out.append(r)
    return out


def _short(v) -> str:
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


# ---- shipping folders to workers ---------------------------------------------------------

def sources_of(records) -> list[dict]:
    """Plain-data copies of the loaded plugin folders a worker needs (entry points ship nothing)."""
    out = []
    for r in records:
        full = _LOADED.get(r.get("digest")) or next(
            (x for x in _LOADED.values() if r.get("digest") is None and x["name"] == r.get("name")), None)
        if full is None or full["digest"] not in _SOURCES:
            continue                          # an entry point: installed on the workers too
        out.append({"name": full["name"], "digest": full["digest"],
                    "files": dict(_SOURCES[full["digest"]])})
    return out


def install_sources(shipped) -> None:
    """Worker side: write shipped folders under the cache (by digest), check, load."""
    from .cache import cache_dir
    for item in shipped or ():
        digest = item["digest"]
        if not _HEX.match(str(digest)):
            raise PluginError(f"bad plugin digest {digest!r}")
        files = item["files"]
        if _digest_of([(n, t.encode("utf-8")) for n, t in files.items()]) != digest:
            raise PluginError(f"plugin {item['name']!r}: shipped files do not match digest {digest[:12]}")
        if digest in _LOADED:
            continue
        folder = cache_dir().parent / "plugins" / digest / _safe_name(item["name"])
        folder.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            if Path(name).name != name or not name.endswith(SUFFIXES) or name.startswith("."):
                raise PluginError(f"plugin {item['name']!r}: bad file name {name!r}")
            target = folder / name
            if not target.exists() or target.read_text(encoding="utf-8") != text:
                tmp = target.with_name(f".{name}.{os.getpid()}.tmp")
                tmp.write_text(text, encoding="utf-8")
                os.replace(tmp, target)
        load_folder(folder)


def _safe_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)[:100].lstrip(".") or "plugin"
