"""The controller-specific options of ``gpmotion run``, as one table.

Each option names the controller families it applies to and, per family,
the key it sets (in RunConfig.search or RunConfig.family_options).  The
parser is built from this table and one check refuses an option that does
not apply to the chosen family, so no option is ever silently ignored.  A
new family declares its options with :func:`register_option` (a new option)
or :func:`allow` (an existing option, under the family's own key).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

GP = "gp"
BSR = ("bsr-sense", "bsr-time")


@dataclass
class Option:
    flag: str                       # "--population"
    target: str                     # "search" or "family" (RunConfig.search / family_options)
    keys: dict[str, str]            # family -> key it sets; the families it applies to
    help: str
    what: str                       # what it is, for the refusal ("the GP population size")
    argparse: dict = field(default_factory=dict)   # type, choices, metavar
    check: Callable | None = None   # value -> value (raises ValueError: one line)
    needs: Callable | None = None   # (args, family) -> reason it cannot apply, or None

    @property
    def dest(self) -> str:
        return self.flag.lstrip("-").replace("-", "_")

    def families(self) -> list[str]:
        return list(self.keys)


def _number(lo, hi, integer=False):
    def check(flag, v):
        from .records import validate_number
        return validate_number(flag, v, lo=lo, hi=hi, integer=integer)
    return check


def _primitives(flag, text):
    from .gp import primitives
    primitives.load_builtin()
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise ValueError(f"{flag}: give a comma list of primitive names (gpmotion list primitives)")
    if len(set(names)) != len(names):
        raise ValueError(f"{flag}: a primitive is named twice in {text!r}")
    for n in names:
        primitives.get(n)                  # unknown: one line with a suggestion
    return names


def _range(flag, text):
    parts = text.split(",")
    try:
        lo, hi = (float(x) for x in parts)
    except ValueError:
        raise ValueError(f"{flag} expects LO,HI (two numbers), got {text!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi and max(-lo, hi) <= 1e6):
        raise ValueError(f"{flag}: need finite LO < HI within ±1e6, got {text!r}")
    return [lo, hi]


def _kinematic_only(args, family):
    from .families import FAMILIES
    act = args.actuation or FAMILIES[family].default_actuation
    if act != "kinematic":
        return (f"it is the time constant of kinematic actuation, and this run uses {act} "
                "(add --actuation kinematic)")
    return None


OPTIONS: list[Option] = [
    Option("--generations", "search", {GP: "generations", **{b: "n_generations" for b in BSR}},
           "GP generations / serial-search rounds (default: the task's, GP 40, serial 4000)",
           "the number of generations", dict(type=int), _number(1, 10_000_000, True)),
    Option("--population", "search", {GP: "population"},
           "GP population size (default 300, herman tasks 400)", "the GP population size "
           "(the serial search keeps --working controllers)", dict(type=int),
           _number(2, 10_000_000, True)),
    Option("--selection", "search", {GP: "selection"},
           "GP selection (default roulette, fitness-proportionate)", "GP parent selection",
           dict(choices=["roulette", "tournament"])),
    Option("--p-crossover", "search", {GP: "p_crossover"},
           "GP crossover probability (default 0.9)", "a GP breeding probability",
           dict(type=float), _number(0, 1)),
    Option("--p-mutation", "search", {GP: "p_mutation"},
           "GP mutation probability (default 0.02)", "a GP breeding probability",
           dict(type=float), _number(0, 1)),
    Option("--p-creep", "search", {GP: "p_creep"},
           "GP constant-creep probability: Gaussian steps on one tree's constants "
           "(default 0, herman tasks 0.1)", "a GP breeding probability",
           dict(type=float), _number(0, 1)),
    Option("--islands", "search", {GP: "islands"},
           "GP island model: demes that breed apart and pass their best around a ring "
           "every 5 generations (default 1)", "the GP island model", dict(type=int),
           _number(1, 10_000, True)),
    Option("--elitism", "search", {GP: "elitism"}, "GP elites copied unchanged (default 1)",
           "the GP elite count", dict(type=int), _number(0, 10**6, True)),
    Option("--max-size", "search", {GP: "max_size"}, "GP nodes per tree cap (default 200)",
           "the GP tree-size cap", dict(type=int), _number(1, 512, True)),
    Option("--primitives", "family", {GP: "primitives"},
           "GP function set, a comma list (default: the task's own set, shown by "
           "gpmotion show TASK; names: gpmotion list primitives)", "the GP function set",
           dict(type=str, metavar="NAME,..."), _primitives),
    Option("--erc-range", "family", {GP: "erc_range"},
           "GP random constants are uniform in [LO, HI] (default -1,1; write --erc-range=-2,2)",
           "the range of GP random constants", dict(type=str, metavar="LO,HI"), _range),
    Option("--tau", "family", {GP: "tau"},
           "time constant (s) of GP targets under --actuation kinematic (default 0.1)",
           "the GP target time constant", dict(type=float), _number(0.002, 10),
           _kinematic_only),
    Option("--working", "search", {b: "n_working" for b in BSR},
           "serial search: working controllers C (default 10)",
           "the serial search's working set (GP has --population)", dict(type=int),
           _number(2, 10_000_000, True)),
    Option("--reseed-every", "search", {b: "reseed_every" for b in BSR},
           "serial search: reseeding interval in rounds (default 200)",
           "the serial search's reseeding interval", dict(type=int),
           _number(1, 10_000_000, True)),
    Option("--rules", "family", {b: "rules" for b in BSR},
           "BSR rules per controller (default sense 8, time 4)",
           "the number of BSR rules (a GP controller is one tree per joint)", dict(type=int),
           _number(1, 10_000, True)),
    Option("--t-per", "family", {"bsr-time": "t_per"},
           "time-based BSR period in s (default: the episode length)",
           "the period of time-based BSR rules", dict(type=float), _number(1e-3, 1e3)),
    Option("--segments", "family", {"bsr-time": "segments"},
           "time-based BSR segments: equal parts of t_per (default) or variable (evolved dividers)",
           "the segment durations of time-based BSR rules", dict(choices=["equal", "variable"])),
]


def get_option(flag: str) -> Option:
    for o in OPTIONS:
        if o.flag == flag:
            return o
    raise KeyError(flag)


def register_option(option: Option) -> Option:
    """Add a controller-specific option (a new family's own)."""
    if any(o.flag == option.flag for o in OPTIONS):
        raise ValueError(f"option {option.flag} already exists; use allow() to share it")
    OPTIONS.append(option)
    return option


def allow(flag: str, family: str, key: str) -> None:
    """Let an existing option apply to ``family``, setting ``key``."""
    get_option(flag).keys[family] = key


def _tag(o: Option) -> str:
    return "[" + ", ".join(o.families()) + "]"


def add_arguments(parser) -> None:
    """The table's options on a subparser, grouped by the families they apply to."""
    groups = {}
    for o in OPTIONS:
        title = "options for --controller " + ", ".join(o.families())
        g = groups.get(title) or groups.setdefault(title, parser.add_argument_group(title))
        kw = dict(o.argparse)
        if "choices" not in kw:
            kw.setdefault("metavar", {int: "N", float: "X"}.get(kw.get("type"), "VALUE"))
        g.add_argument(o.flag, dest=o.dest, default=None, help=o.help, **kw)


def collect(args, family: str) -> tuple[dict, dict]:
    """(search, family_options) from parsed args for ``family``; a given option
    that does not apply is one error naming why (every refusal in one line)."""
    search, fam, refused = {}, {}, []
    for o in OPTIONS:
        value = getattr(args, o.dest, None)
        if value is None:
            continue
        if family not in o.keys:
            refused.append(f"{o.flag} does not apply to --controller {family}: it sets {o.what} "
                           f"(applies to {', '.join(o.families())})")
            continue
        reason = o.needs(args, family) if o.needs else None
        if reason:
            refused.append(f"{o.flag} does not apply: {reason}")
            continue
        value = o.check(o.flag, value) if o.check else value
        (search if o.target == "search" else fam)[o.keys[family]] = value
    if refused:
        raise ValueError("; ".join(refused))
    return search, fam
