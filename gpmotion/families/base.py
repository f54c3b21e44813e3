"""The controller-family protocol and its registry (DESIGN.md point 8).

A family is everything the harness needs to know about one kind of
controller; nothing outside a family's module names a family.  A family
class declares:

* ``name`` (what users type after ``--controller``), ``description``;
* ``default_actuation`` (``pd`` or ``kinematic``) and ``default_tau``;
* genomes as plain data: ``random(rng)``, ``encode(genomes)`` (to the rollout
  kernel's :class:`~gpmotion.controllers.ControllerBatch`), ``to_json`` /
  ``from_json`` (safe JSON, validated on the way in), ``copy``;
* variation: ``mutate(genome, rng, extra)`` where its search uses it, and for
  what climbs from a given controller (a composite's phase refinement, GP's
  ``polish``); a family without it cannot be refined (a clear error);
* its search: ``search_class`` (a :class:`gpmotion.search.base.Search`),
  ``search_defaults(task)``, ``make_search(seed, **settings)`` and
  ``budget_settings(budget, population)`` (what ``compare`` runs under an
  evaluation budget);
* its command-line options: ``cli`` maps an option flag of
  :mod:`gpmotion.cli_options` to the key it sets for this family (a family's
  own new options are registered with ``cli_options.register_option`` in its
  module);
* optionally ``needs_senses`` + ``extras(traj)`` (per-genome data a search
  keeps beside a genome, e.g. BSR's normalized sense trajectories),
  ``plot_file`` + ``plot(path, genome)`` (a picture of a controller), and
  ``presets``.

``register_family`` (a class decorator) adds a family; ``make_family(name,
task, **options)`` builds one; ``family_names()`` lists them.
"""
from __future__ import annotations

import copy
import inspect

from ..names import unknown

_FAMILIES: dict[str, type] = {}


class Family:
    """Base class of every controller family (see the module docstring)."""
    name = ""
    description = ""
    default_actuation = "pd"
    needs_senses = False          # the evaluator records senses for ``extras``
    search_class = None           # a gpmotion.search.base.Search subclass
    cli: dict[str, str] = {}      # option flag -> the key it sets (search or family option)
    takes_population = False      # ``compare --population`` applies
    plot_file: str | None = None  # artifact name of ``plot`` (e.g. trees.png)
    presets: tuple = ()           # names ``apply_preset`` knows
    # option -> the value a record written before the option existed meant
    # (its default now may differ, e.g. come from the task): see recorded_options
    legacy_options: dict = {}

    def __init__(self, task, **options):
        self.task = task
        self.options = options

    # -- genomes ---------------------------------------------------------------
    def random(self, rng):
        raise NotImplementedError

    def encode(self, genomes):
        raise NotImplementedError

    def to_json(self, genome):
        raise NotImplementedError

    def from_json(self, data):
        raise NotImplementedError

    def copy(self, genome):
        return genome.copy() if hasattr(genome, "copy") else copy.deepcopy(genome)

    def mutate(self, genome, rng, extra=None):
        raise NotImplementedError(f"{self.name} varies its genomes inside its search")

    def extras(self, traj) -> list | None:
        """Per-genome data of a rollout the search keeps (None: nothing)."""
        return None

    # -- description -------------------------------------------------------------
    def config(self) -> dict:
        return {"family": self.name, **self.options}

    @property
    def default_tau(self) -> float:
        """τ for `kinematic` actuation when the controller does not set one."""
        return float(self.options.get("tau") or 0.1)

    def plot(self, path, genome) -> None:
        raise ValueError(f"a {self.name} controller has no structure to draw")

    def banner_note(self) -> str:
        """A short fact for a run's banner (e.g. GP's target mode); "" for none."""
        return ""

    # -- search ----------------------------------------------------------------
    @classmethod
    def search_defaults(cls, task) -> dict:
        """Search settings a run starts from (the user's win)."""
        return {}

    @classmethod
    def setting_names(cls) -> set[str]:
        """The search settings a run's config may set."""
        return cls.search_class.setting_names()

    def make_search(self, seed: int, **settings):
        """This family's search for its task; ``settings`` (None: default) win."""
        given = {k: v for k, v in settings.items() if v is not None}
        return self.search_class(self, seed=seed, task=self.task,
                                 **{**self.search_defaults(self.task), **given})

    def noisy_settings(self) -> dict:
        """Search settings for evaluations that change between generations (robust
        starts redrawn each generation): a search must not reuse an old cost."""
        return {}

    def budget_settings(self, budget: int, population: int | None = None) -> dict:
        """Search settings that spend about ``budget`` evaluations (``compare``)."""
        raise NotImplementedError

    @classmethod
    def apply_preset(cls, name: str, task_name: str, family_options: dict,
                     search: dict) -> tuple[dict, dict]:
        """(family options, search settings) of preset ``name`` under the given ones."""
        with_presets = [n for n, c in _FAMILIES.items() if c.presets]
        raise ValueError(f"--preset {name}: {cls.name} has no presets; a preset applies to "
                         f"--controller {', '.join(with_presets) or '(none)'}")


# ------------------------------------------------------------------ registry

def register_family(cls):
    """Class decorator: add a family under ``cls.name`` (a duplicate is an
    error naming both files) and let the options in ``cls.cli`` apply to it."""
    from .. import cli_options
    if not isinstance(cls, type) or not issubclass(cls, Family) or not cls.name:
        raise ValueError(f"register_family: {cls!r} is not a named Family subclass")
    old = _FAMILIES.get(cls.name)
    if old is not None and _source(old) != _source(cls):
        raise ValueError(f"controller family {cls.name!r} is registered twice: in "
                         f"{_source(old)} and {_source(cls)}")
    for flag, key in cls.cli.items():
        cli_options.allow(flag, cls.name, key)
    _FAMILIES[cls.name] = cls
    return cls


def _source(cls) -> str:
    try:
        return inspect.getsourcefile(cls) or cls.__module__
    except (TypeError, OSError):
        return cls.__module__


def unregister_family(name: str) -> None:
    """Remove a family (tests that register a throwaway one)."""
    from .. import cli_options
    _FAMILIES.pop(name, None)
    cli_options.disallow(name)


def family_names() -> list[str]:
    return list(_FAMILIES)


def family_class(name: str) -> type:
    if name not in _FAMILIES:
        raise ValueError(unknown("controller family", name, _FAMILIES))
    return _FAMILIES[name]


def recorded_options(name: str, recorded: dict | None, given: dict | None = None) -> dict:
    """The options that rebuild a recorded family: ``given`` (a run's own
    options), then for each of the family's ``legacy_options`` the value the
    record holds (``recorded``: its family config or a controller's options),
    or the legacy value when the record predates the option."""
    recorded, out = dict(recorded or {}), dict(given or {})
    for key, legacy in family_class(name).legacy_options.items():
        if out.get(key) is None:
            out[key] = recorded.get(key, legacy)
    return out


def make_family(name: str, task, **options) -> Family:
    """Family ``name`` for ``task``; options that are None take the family's default."""
    return family_class(name)(task, **{k: v for k, v in options.items() if v is not None})
