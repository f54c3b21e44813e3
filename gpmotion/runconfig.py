"""What fixes a run (config.json's ``run`` section), checked field by field
when read back, and the run identity that binds config, checkpoint and log.

A hand-edited config gives one line naming the field, never a traceback;
``run --resume`` with settings that differ from the recorded ones is refused
(it would silently keep the old values), naming the option.
"""
from __future__ import annotations

import hashlib
import json
import secrets
from dataclasses import dataclass, field
from pathlib import Path

from .families import DEFAULT_FAMILY
from .records import ConfigError, FormatError


@dataclass
class RunConfig:
    """Everything that fixes a run (written to config.json)."""
    task: str
    family: str = DEFAULT_FAMILY
    seed: int = 0
    params: dict = field(default_factory=dict)          # task parameters
    family_options: dict = field(default_factory=dict)  # rules, t_per, primitives...
    search: dict = field(default_factory=dict)          # population, generations...
    actuation: str | None = None
    workers: int = 0
    scheduler: str | None = None
    threads: int | None = None
    plugins: list = field(default_factory=list)
    robust: dict = field(default_factory=dict)          # perturbed starts (gpmotion.robust); {} off

    def to_json(self) -> dict:
        return dict(task=self.task, family=self.family, seed=self.seed, params=self.params,
                    family_options=self.family_options, search=self.search,
                    actuation=self.actuation, workers=self.workers, scheduler=self.scheduler,
                    threads=self.threads, plugins=self.plugins,
                    **({"robust": self.robust} if self.robust else {}))   # older configs: none

    @classmethod
    def from_json(cls, d, source: str = "config.json") -> "RunConfig":
        """Checked inverse of :meth:`to_json`: every problem is one FormatError line."""
        if d is None:
            raise FormatError(f"{source}: no 'run' section (the run's task, family, seed and "
                              "settings); not a gpmotion run config")
        if not isinstance(d, dict):
            raise FormatError(f"{source}: 'run' must be an object, got {type(d).__name__}")
        unknown = sorted(set(d) - set(_TYPES))
        if unknown:
            raise FormatError(f"{source}: run has unknown key(s) {unknown}")
        missing = [k for k in ("task", "family", "seed") if k not in d]
        if missing:
            raise FormatError(f"{source}: run lacks {missing}")
        for k, v in d.items():
            _check_type(source, f"run.{k}", v, _TYPES[k])
        from .families import family_names
        if d["family"] not in family_names():
            raise FormatError(f"{source}: run.family {_short(d['family'])} is not one of "
                              f"{', '.join(family_names())}")
        for k, v in d.get("params", {}).items():     # a figure variant is an object
            _check_type(source, f"run.params.{k}", v, (str, int, float, bool, dict))
        for k, v in d.get("family_options", {}).items():
            _check_type(source, f"run.family_options.{k}", v, (str, int, float, bool, list, None))
        unknown = sorted(set(d.get("family_options", {})) - option_names(d["family"]))
        if unknown:
            raise FormatError(f"{source}: run.family_options has unknown option(s) {unknown} "
                              f"for {d['family']}; known: {sorted(option_names(d['family']))}")
        _check_search(source, d["family"], d.get("search", {}))
        _check_bounds(source, d)
        for i, p in enumerate(d.get("plugins", [])):  # requirement records (plugins.require)
            _check_type(source, f"run.plugins[{i}]", p, (str, dict))
        return cls(**d)


_TYPES = {"task": (str,), "family": (str,), "seed": (int,), "params": (dict,),
          "family_options": (dict,), "search": (dict,), "actuation": (str, None),
          "workers": (int,), "scheduler": (str, None), "threads": (int, None),
          "plugins": (list,), "robust": (dict,)}
_NAMES = {str: "a string", int: "an integer", float: "a number", bool: "true/false",
          dict: "an object", list: "a list", None: "null"}


def _check_type(source: str, where: str, v, types: tuple) -> None:
    ok = any((v is None) if t is None else
             (isinstance(v, t) and not (t in (int, float) and isinstance(v, bool)))
             for t in types)
    if isinstance(v, float) and v != v:
        ok = False
    if not ok:
        want = " or ".join(_NAMES[t] for t in types)
        raise FormatError(f"{source}: {where} must be {want}, got {_short(v)}")


def search_keys(family: str) -> set[str]:
    """The search settings a config may set for a family."""
    from .families import family_class
    return family_class(family).setting_names()


def option_names(family: str) -> set[str]:
    """The options a family takes: its constructors' named parameters and the
    command-line options that set one (a family stores any keyword it is given,
    so an unknown one would be recorded and silently mean nothing)."""
    import inspect

    from .cli_options import OPTIONS
    from .families import family_class
    names = {o.keys[family] for o in OPTIONS if o.target == "family" and family in o.keys}
    for cls in family_class(family).__mro__:
        init = cls.__dict__.get("__init__")
        if init is not None:
            names |= {p.name for p in inspect.signature(init).parameters.values()
                      if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    return names - {"self", "task"}


def _check_search(source: str, family: str, search: dict) -> None:
    known = search_keys(family)
    unknown = sorted(set(search) - known)
    if unknown:
        raise FormatError(f"{source}: run.search has unknown setting(s) {unknown} for "
                          f"{family}; known: {sorted(known)}")
    for k, v in search.items():
        _check_type(source, f"run.search.{k}", v, (int, float, str, bool, list, None))


ACTUATIONS = ("pd", "kinematic")


def _check_bounds(source: str, d: dict) -> None:
    """The command line's bounds, applied to what config.json records: a hand-edited
    population of 10^9 or 0 threads is refused as `gpmotion run` refuses it."""
    from .cli_options import OPTIONS
    from .records import validate_number
    if d.get("actuation") is not None and d["actuation"] not in ACTUATIONS:
        raise FormatError(f"{source}: run.actuation must be one of {', '.join(ACTUATIONS)}, "
                          f"got {_short(d['actuation'])}")
    bounds = (("workers", 0, 10_000_000, False), ("threads", 1, 10_000_000, True),
              ("seed", 0, None, False))
    try:
        for key, lo, hi, none in bounds:
            if key in d:
                validate_number(f"run.{key}", d[key], lo=lo, hi=hi, integer=True,
                                allow_none=none)
        for section, target in (("search", "search"), ("family_options", "family")):
            for key, value in (d.get(section) or {}).items():
                for o in OPTIONS:
                    if o.target == target and o.keys.get(d["family"]) == key and o.check \
                            and value is not None:
                        if isinstance(value, list):          # as the flag takes it: A,B
                            value = ",".join(str(v) for v in value)
                        o.check(f"run.{section}.{key} ({o.flag})", value)
    except (ValueError, TypeError, AttributeError) as e:
        raise FormatError(f"{source}: {e}") from None


def _short(x) -> str:
    r = repr(x)
    return r if len(r) <= 40 else r[:37] + "..."


# ------------------------------------------------------------------ identity

def new_run_id() -> str:
    return secrets.token_hex(8)


def config_digest(doc: dict) -> str:
    """sha256 of config.json's content (less its envelope and a recorded
    extension, which only ever raises the generation total)."""
    body = {k: v for k, v in doc.items()
            if k not in ("format", "version", "extended_generations")}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _same(a, b) -> bool:
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool) \
            and not isinstance(b, bool):
        return float(a) == float(b)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def settings_mismatch(expected: dict, got, total_key: str, totals: set) -> str:
    """'' when a checkpoint's search settings are config.json's (the total may be
    the configured one or an extension's), else what differs."""
    if not isinstance(got, dict):
        return "it records no search settings"
    diff = []
    for k in sorted(set(expected) | set(got)):
        if k == total_key:
            if not any(_same(got.get(k), t) for t in totals):
                diff.append(f"{k} {_short(got.get(k))} ≠ {max(totals)}")
        elif not _same(expected.get(k), got.get(k)):
            diff.append(f"{k} {_short(got.get(k))} ≠ {_short(expected.get(k))}")
    return ", ".join(diff[:3]) + (" …" if len(diff) > 3 else "")


# ------------------------------------------------------------------ resume

_FLAGS = {"generations": "--generations", "n_generations": "--generations",
          "n_working": "--working", "population": "--population", "seed": "--seed",
          "t_per": "--t-per"}


def _flag(key: str) -> str:
    return _FLAGS.get(key, "--" + key.replace("_", "-"))


def check_resume_request(given: RunConfig, stored: RunConfig, doc: dict, search,
                         path: Path) -> None:
    """``run --resume`` continues the recorded run: any setting given on the
    command line must be the recorded one (backend options excepted)."""
    def refuse(flag, recorded, asked):
        hint = (f"; `gpmotion resume {path} --extend-generations N` adds N generations"
                if flag == "--generations" else "; use a new --out (or --force) for another run")
        raise ConfigError(f"{path}: --resume continues the run recorded in config.json, but "
                          f"{flag} differs (recorded {_short(recorded)}, given {_short(asked)})"
                          + hint)
    for k in ("task", "family", "seed"):
        if getattr(given, k) != getattr(stored, k):
            refuse("--controller" if k == "family" else "task" if k == "task" else _flag(k),
                   getattr(stored, k), getattr(given, k))
    if given.params:
        from .task import get_task
        now = get_task(given.task, **given.params).params
        rec = (doc.get("task_config") or {}).get("params") or {}
        for k in given.params:
            if not _same(now.get(k), rec.get(k)):
                refuse(f"--param {k}", rec.get(k), given.params[k])
    fam = {**(doc.get("family_config") or {}), **stored.family_options}
    for k, v in given.family_options.items():
        if not _same(v, fam.get(k)):
            refuse(_flag(k), fam.get(k), v)
    eff = search.config()
    for k, v in given.search.items():
        if v is not None and not _same(v, eff.get(k, stored.search.get(k))):
            refuse(_flag(k), eff.get(k, stored.search.get(k)), v)
    if given.actuation and given.actuation != doc.get("actuation"):
        refuse("--actuation", doc.get("actuation"), given.actuation)
    for k, v in (given.robust or {}).items():              # --robust-starts, --perturb ...
        if not _same(v, stored.robust.get(k)):
            refuse(f"robust {k}", stored.robust.get(k), v)
