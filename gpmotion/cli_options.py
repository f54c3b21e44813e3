"""The controller-specific options of ``gpmotion run``, as one table.

Each option names the controller families it applies to and, per family,
the key it sets (in RunConfig.search or RunConfig.family_options).  The
parser is built from this table and one check refuses an option that does
not apply to the chosen family, so no option is ever silently ignored.

This module names no family: it holds the options several families share
(``--generations``, ``--population``); a family's module registers its own
with :func:`register_option`, and :func:`gpmotion.families.register_family`
lets the flags in a family's ``cli`` table apply to it (:func:`allow`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable


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


def number(lo, hi, integer=False):
    """A check: a number within [lo, hi] (an integer if asked)."""
    def check(flag, v):
        from .records import validate_number
        return validate_number(flag, v, lo=lo, hi=hi, integer=integer)
    return check


OPTIONS: list[Option] = [
    Option("--generations", "search", {},
           "generations (rounds) of the search (default: the family's and the task's)",
           "the number of generations", dict(type=int), number(1, 10_000_000, True)),
    Option("--population", "search", {},
           "population size of a population-based search (default: the family's and the task's)",
           "a population size (the serial search keeps --working controllers)", dict(type=int),
           number(2, 10_000_000, True)),
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


def disallow(family: str) -> None:
    """Forget ``family`` in every option (an unregistered family)."""
    for o in OPTIONS:
        o.keys.pop(family, None)


def _tag(o: Option) -> str:
    return "[" + ", ".join(o.families()) + "]"


def add_arguments(parser) -> None:
    """The table's options on a subparser, grouped by the families they apply to."""
    groups = {}
    for o in OPTIONS:
        if not o.keys:
            continue
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
