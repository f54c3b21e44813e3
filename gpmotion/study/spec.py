"""A study spec (TOML): what to run and how to judge it, parsed and checked.

Every problem is one :class:`SpecError` line naming the key
(``configurations.star-hop.search.n_generations must be an integer ≥ 1``);
unknown keys are refused, nothing in the file is run as code.  The layout::

    [study]                       name, title, tune_seeds, report_seeds
    [defaults]                    laid under every configuration
    [quick]                       seeds and a small search for CI (--quick)
    [configurations.NAME]         task, family, params, figure, options,
                                  budget | search, actuation, robust,
                                  judge, expect, starts, label, stages

``stages`` (a list of tables with the same keys as a configuration, less
judge/expect/stages) chains searches: each stage's task starts from the end
of the earlier stages' controllers; the configuration's judge sees them run
as one composite.  The digest of the parsed spec binds a study directory
to the spec it was run from (docs/studies.md).
"""
from __future__ import annotations

import copy
import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10
    import tomli as tomllib

from ..records import ConfigError

MAX_SEEDS = 10_000
MAX_STARTS = 100
MAX_BYTES = 1 << 20
_NAME = re.compile(r"^[a-z0-9][a-z0-9_.-]{0,79}$")


class SpecError(ConfigError):
    """A study spec is malformed; the message is one line naming the key."""


STUDY_KEYS = {"name", "title", "description", "tune_seeds", "report_seeds"}
RUN_KEYS = {"task", "family", "params", "figure", "options", "budget", "search", "preset",
            "actuation", "robust", "starts"}
CONFIG_KEYS = RUN_KEYS | {"label", "judge", "expect", "stages"}
STAGE_KEYS = RUN_KEYS | {"name"}
QUICK_KEYS = {"seeds", "budget", "search", "starts"}


@dataclass
class Stage:
    """One search of a configuration (an unstaged configuration has one)."""
    name: str
    task: str
    family: str
    params: dict
    options: dict
    search: dict
    budget: int | None
    actuation: str | None
    robust: dict
    starts: int


@dataclass
class Configuration:
    name: str
    label: str
    judge: str
    expect: list
    starts: int
    stages: list[Stage]
    staged: bool = False          # written with ``stages`` (judged as a composite)


@dataclass
class Spec:
    name: str
    title: str
    description: str
    tune_seeds: list[int]
    report_seeds: list[int]
    configurations: dict[str, Configuration]
    source: dict = field(repr=False, default_factory=dict)     # the parsed TOML
    quick: bool = False

    @property
    def seeds(self) -> list[int]:
        return self.tune_seeds + self.report_seeds

    def seed_set(self, seed: int) -> str:
        return "report" if seed in self.report_seeds else "tune"

    def digest(self) -> str:
        """sha256 of what fixes the results: the parsed spec (and --quick)."""
        body = {"spec": self.source, "quick": self.quick}
        text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
        return hashlib.sha256(text.encode()).hexdigest()


def plain_name(text, what: str) -> str:
    """A name that becomes part of a file name: the run-directory layer's plain
    name (gpmotion.rundir.plain_name), and here lower-case letters, digits,
    ``-``, ``_`` and ``.``, starting with a letter or digit (stable on every
    file system)."""
    from ..rundir import plain_name as plain
    try:
        plain(text, what)
    except ValueError as e:
        raise SpecError(str(e)) from None
    if not _NAME.match(text) or ".." in text:
        raise SpecError(f"{what} must be a plain name (a-z, 0-9, '-', '_', '.'; at most 80), "
                        f"got {_short(text)}")
    return text


def _short(x) -> str:
    r = repr(x)
    return r if len(r) <= 40 else r[:37] + "..."


# ------------------------------------------------------------------ reading

def load(path: str | Path, *, quick: bool = False) -> Spec:
    """Read and check a spec file (``quick``: its [quick] form)."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_BYTES + 1)
    except OSError as e:
        raise SpecError(f"{path}: cannot read ({e.strerror or e})") from None
    if len(data) > MAX_BYTES:
        raise SpecError(f"{path}: larger than the {MAX_BYTES}-byte limit of a spec")
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise SpecError(f"{path}: not a TOML file ({e})") from None
    try:
        return parse(doc, quick=quick)
    except SpecError as e:
        raise SpecError(f"{path}: {e}") from None


def parse(doc: dict, *, quick: bool = False) -> Spec:
    """Check a parsed TOML document; every problem is one SpecError line."""
    _keys(doc, {"study", "defaults", "quick", "configurations"}, "the spec")
    study = _table(doc, "study", required=True)
    _keys(study, STUDY_KEYS, "study")
    name = plain_name(study.get("name"), "study.name")
    tune = _seeds(study.get("tune_seeds", []), "study.tune_seeds")
    report = _seeds(study.get("report_seeds", []), "study.report_seeds")
    both = sorted(set(tune) & set(report))
    if both:
        raise SpecError(f"study.report_seeds: seeds {both} are tune seeds too; a rate is "
                        "reported only on seeds no setting was chosen on")
    if not tune + report:
        raise SpecError("study: give tune_seeds or report_seeds (lists of seeds)")
    defaults = _table(doc, "defaults")
    _keys(defaults, CONFIG_KEYS - {"stages", "label"}, "defaults")
    quick_t = _table(doc, "quick")
    _keys(quick_t, QUICK_KEYS, "quick")
    if quick and not quick_t:
        raise SpecError("quick: this spec has no [quick] form")
    configs = _table(doc, "configurations", required=True)
    if not configs:
        raise SpecError("configurations: a study needs at least one configuration")
    out = {}
    for cname, body in configs.items():
        where = f"configurations.{cname}"
        plain_name(cname, f"{where} (its name)")
        if not isinstance(body, dict):
            raise SpecError(f"{where} must be a table")
        merged = _merged(copy.deepcopy(defaults), body)
        out[cname] = _configuration(cname, merged, where)    # as written, --quick or not
        if quick:
            out[cname] = _configuration(cname, _quick(merged, quick_t), where)
    if quick_t:
        quick_seeds = _quick_seeds(quick_t, tune, report)     # checked with or without --quick
        _quick(dict(defaults), quick_t)
    if quick:
        tune, report = quick_seeds
    return Spec(name=name, title=_str(study, "title", "study", name),
                description=_str(study, "description", "study", ""),
                tune_seeds=tune, report_seeds=report, configurations=out,
                source=copy.deepcopy(doc), quick=quick)


def _merged(under: dict, over: dict) -> dict:
    """``over`` laid over ``under``; the tables params, options and search merge
    key by key (a configuration changes one search setting of the defaults)."""
    out = dict(under)
    for k, v in over.items():
        if k in ("params", "options", "search") and isinstance(v, dict) \
                and isinstance(out.get(k), dict):
            out[k] = {**out[k], **v}
        else:
            out[k] = copy.deepcopy(v)
    return out


def _quick(cfg: dict, quick: dict) -> dict:
    """The [quick] form laid over a configuration (and each of its stages)."""
    over = {k: copy.deepcopy(v) for k, v in quick.items() if k != "seeds"}
    if "search" in over and not isinstance(over["search"], dict):
        raise SpecError("quick.search must be a table")

    def lay(t: dict) -> dict:
        t = dict(t)
        for k, v in over.items():
            t[k] = {**t.get(k, {}), **v} if k == "search" and isinstance(t.get(k), dict) else v
        if "budget" in over and "search" not in over:     # a small budget, not the big search
            t.pop("search", None)
        return t
    cfg = lay(cfg)
    if isinstance(cfg.get("stages"), list):
        cfg["stages"] = [lay(s) if isinstance(s, dict) else s for s in cfg["stages"]]
    return cfg


def _quick_seeds(quick: dict, tune: list, report: list) -> tuple[list, list]:
    seeds = _seeds(quick.get("seeds", (tune + report)[:2]), "quick.seeds")
    unknown = [s for s in seeds if s not in tune + report]
    if unknown:
        raise SpecError(f"quick.seeds: {unknown} are not among the study's seeds")
    return [s for s in seeds if s in tune], [s for s in seeds if s in report]


def _configuration(name: str, body: dict, where: str) -> Configuration:
    _keys(body, CONFIG_KEYS, where)
    from .judge import get_judge
    judge = body.get("judge", "task")
    try:
        j = get_judge(judge)
    except KeyError as e:
        raise SpecError(f"{where}.judge: {e.args[0]}") from None
    expect = body.get("expect", [])
    if not isinstance(expect, list) or not all(isinstance(x, str) for x in expect):
        raise SpecError(f"{where}.expect must be a list of labels")
    bad = [x for x in expect if x not in j.labels]
    if bad:
        raise SpecError(f"{where}.expect: {bad} are not labels of judge {judge!r} "
                        f"({', '.join(j.labels)})")
    if j.composite != ("stages" in body):
        want = "needs stages" if j.composite else "judges one search, not stages"
        raise SpecError(f"{where}.judge: {judge!r} {want}")
    starts = _int(body.get("starts", 1), f"{where}.starts", 1, MAX_STARTS)
    base = {k: v for k, v in body.items() if k in RUN_KEYS and k != "starts"}
    if "stages" in body:
        stages = body["stages"]
        if not isinstance(stages, list) or not stages or not all(isinstance(s, dict) for s in stages):
            raise SpecError(f"{where}.stages must be a list of tables ([[...stages]])")
        built, names = [], set()
        for i, s in enumerate(stages):
            sw = f"{where}.stages[{i}]"
            _keys(s, STAGE_KEYS, sw)
            st = _stage(_merged(base, s), sw, plain_name(s.get("name", f"stage{i}"), f"{sw}.name"))
            if st.name in names:
                raise SpecError(f"{sw}.name: {st.name!r} names two stages")
            names.add(st.name)
            built.append(st)
        if starts != 1:
            raise SpecError(f"{where}.starts: a staged configuration takes starts per stage")
    else:
        built = [_stage({**base, "starts": 1}, where, "search")]
    label = _str(body, "label", where, name)
    return Configuration(name, label, judge, list(expect), starts, built, "stages" in body)


def _stage(body: dict, where: str, name: str) -> Stage:
    from ..families import family_names
    from ..task import task_ids, task_names
    task = body.get("task")
    if not isinstance(task, str) or task not in task_names() + task_ids():
        from ..names import unknown
        raise SpecError(f"{where}.task: " + (unknown("task", task, task_names())
                                            if isinstance(task, str) else "missing or not a name"))
    family = body.get("family")
    if family not in family_names():
        raise SpecError(f"{where}.family: must be one of {', '.join(family_names())}, "
                        f"got {_short(family)}")
    params = _plain_table(body, "params", where, (str, int, float, bool))
    if "figure" in params:
        raise SpecError(f"{where}.params.figure: give the figure as {where}.figure")
    if "figure" in body:
        params["figure"] = _figure(body["figure"], f"{where}.figure")
    options = _plain_table(body, "options", where, (str, int, float, bool, list))
    from ..runconfig import option_names
    unknown = sorted(set(options) - option_names(family))
    if unknown:
        raise SpecError(f"{where}.options: unknown option(s) {unknown} for {family}; "
                        f"known: {sorted(option_names(family))}")
    search = _plain_table(body, "search", where, (str, int, float, bool, list))
    from ..runconfig import search_keys
    unknown = sorted(set(search) - search_keys(family))
    if unknown:
        raise SpecError(f"{where}.search: unknown setting(s) {unknown} for {family}; "
                        f"known: {sorted(search_keys(family))}")
    budget = body.get("budget")
    if budget is not None:              # none: the family's own settings (as `gpmotion run`)
        budget = _int(budget, f"{where}.budget", 20, 10**9)
    if "preset" in body:                # the family's named settings, the spec's over them
        if not isinstance(body["preset"], str):
            raise SpecError(f"{where}.preset must be a preset's name")
        from ..families import family_class
        try:
            fam_opts, fam_search = family_class(family).apply_preset(body["preset"], task, {}, {})
        except (ValueError, KeyError) as e:
            raise SpecError(f"{where}.preset: {e}") from None
        options, search = {**fam_opts, **options}, {**fam_search, **search}
    actuation = body.get("actuation")
    if actuation not in (None, "pd", "kinematic"):
        raise SpecError(f"{where}.actuation must be 'pd' or 'kinematic', got {_short(actuation)}")
    robust = _plain_table(body, "robust", where, (str, int, float, bool, list, dict))
    starts = _int(body.get("starts", 1), f"{where}.starts", 1, MAX_STARTS)
    return Stage(name, task, family, params, options, search, budget, actuation, robust, starts)


def _figure(value, where: str):
    """A registered figure's name, or a variant table (``extends = "NAME"`` and
    the parts it changes), resolved as ``gpmotion run --figure`` stores it."""
    from ..figures import figure_names, resolve_spec
    if isinstance(value, str):
        if value not in figure_names():
            from ..names import unknown
            raise SpecError(f"{where}: {unknown('figure', value, figure_names())}")
        return value
    if isinstance(value, dict):
        if not isinstance(value.get("extends"), str) or not isinstance(value.get("name"), str):
            raise SpecError(f"{where}: a variant table needs extends = \"FIGURE\" and a name")
        plain_name(value["name"], f"{where}.name")
        if value["name"] in figure_names():       # rows would label two figures alike
            raise SpecError(f"{where}.name: {value['name']!r} is a registered figure; a "
                            "variant needs a name of its own (figure = \"NAME\" runs the "
                            "figure itself)")
        try:
            return resolve_spec(copy.deepcopy(value))
        except ValueError as e:
            raise SpecError(f"{where}: {e}") from None
    raise SpecError(f"{where} must be a figure name or a variant table, got {_short(value)}")


# ------------------------------------------------------------------ checks

def _keys(t: dict, known: set, where: str) -> None:
    unknown = sorted(set(t) - known)
    if unknown:
        raise SpecError(f"{where}: unknown key(s) {unknown}; known: {', '.join(sorted(known))}")


def _table(doc: dict, key: str, required: bool = False) -> dict:
    if key not in doc:
        if required:
            raise SpecError(f"[{key}]: missing")
        return {}
    if not isinstance(doc[key], dict):
        raise SpecError(f"{key} must be a table")
    return doc[key]


def _plain_table(body: dict, key: str, where: str, types: tuple) -> dict:
    v = body.get(key, {})
    if not isinstance(v, dict):
        raise SpecError(f"{where}.{key} must be a table")
    for k, x in v.items():
        if not isinstance(x, types) or (isinstance(x, float) and x != x):
            raise SpecError(f"{where}.{key}.{k}: unsupported value {_short(x)}")
    return copy.deepcopy(v)


def _int(v, where: str, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise SpecError(f"{where} must be an integer in {lo}..{hi}, got {_short(v)}")
    return v


def _str(t: dict, key: str, where: str, default: str) -> str:
    v = t.get(key, default)
    if not isinstance(v, str):
        raise SpecError(f"{where}.{key} must be a string, got {_short(v)}")
    return v


def _seeds(v, where: str) -> list[int]:
    if not isinstance(v, list):
        raise SpecError(f"{where} must be a list of seeds, got {_short(v)}")
    seeds = [_int(s, f"{where}[{i}]", 0, 2**31 - 1) for i, s in enumerate(v)]
    if len(set(seeds)) != len(seeds):
        raise SpecError(f"{where}: a seed is listed twice")
    if len(seeds) > MAX_SEEDS:
        raise SpecError(f"{where}: more than {MAX_SEEDS} seeds")
    return seeds


def select_seeds(spec: Spec, text: str | None) -> list[int]:
    """``--seeds``: tune, report, all (default) or a comma list of the spec's seeds."""
    if text in (None, "all"):
        return spec.seeds
    if text == "tune":
        return list(spec.tune_seeds)
    if text == "report":
        return list(spec.report_seeds)
    try:
        seeds = [int(s) for s in str(text).split(",") if s.strip()]
    except ValueError:
        raise SpecError(f"--seeds: give tune, report, all or a comma list of seeds, "
                        f"got {_short(text)}") from None
    unknown = [s for s in seeds if s not in spec.seeds]
    if unknown or not seeds:
        raise SpecError(f"--seeds: {unknown or 'none'} not among the spec's seeds "
                        f"(tune {spec.tune_seeds}, report {spec.report_seeds})")
    return seeds
