"""The GP family (Gritz & Hahn): one parse tree per controlled actuator.

A genome is a list of token lists (``gpmotion.gp.bytecode``), one per
controlled actuator; it compiles to postfix bytecode the rollout kernel
interprets.  Its search is :class:`gpmotion.search.gp.GPSearch` (DEAP's
operators on the trees), its presets are :mod:`gpmotion.gp.presets`.
"""
from __future__ import annotations

import math
import random

import numpy as np
from deap import gp

from .. import cli_options
from ..cli_options import Option, number
from ..gp import bytecode
from ..gp import targets as gp_targets
from ..gp.operators import creep_constants, make_tree_operators, mutate_one_dof, random_tree
from ..gp.primitives import CLAMP
from ..gp.pset import build_pset
from ..gp.settings import gp_settings, terminal_names
from ..gp.subgoals import subgoal_table, task_subgoals
from ..gp.task_senses import compile_formula, task_senses
from ..search.gp import GPSearch
from .base import Family, register_family

# Gritz & Hahn: crossover-dominant, little mutation, fitness-proportionate
# selection; we keep one elite so the best is never lost.  A task may raise
# them (GPSettings.defaults: herman's population).
GP_DEFAULTS = dict(population=300, generations=40, p_crossover=0.9, p_mutation=0.02,
                   selection="roulette", elitism=1)
BUDGET_POPULATION = 100            # compare's default population under a budget
# Rate mode: a tree's output times RATE_GAIN (1/s) is its target's rate (rad/s),
# so a tree of sense scale (a fingertip 0.1 m off) moves its target ~1 rad/s,
# a reach in under a second, without constants the trees would have to grow.
RATE_GAIN = 10.0
# Pi mode: the integral term removes a sag of 0.1 rad in ~0.2 s (1/PI_GAIN),
# slower than the PD servo's own response, and corrects at most PI_BOUND rad.
PI_GAIN, PI_BOUND = 5.0, 0.5


def _primitives(flag, text):
    from ..gp import primitives
    primitives.load_builtin()
    names = [n.strip() for n in text.split(",")]
    if not any(names):
        raise ValueError(f"{flag}: give a comma list of primitive names (gpmotion list primitives)")
    if not all(names):
        raise ValueError(f"{flag}: an empty name in {text!r} (a stray comma?)")
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


def _targets(flag, text):
    gp_targets.parse(text)             # syntax and mode names; joints are checked by the family
    return text.strip()


def _kinematic_only(args, family):
    from .base import family_class
    act = args.actuation or family_class(family).default_actuation
    if act != "kinematic":
        return (f"it is the time constant of kinematic actuation, and this run uses {act} "
                "(add --actuation kinematic)")
    return None


def _gp_option(flag, target, key, help, what, argparse, check=None, needs=None):
    cli_options.register_option(Option(flag, target, {}, help, what, argparse, check, needs))
    return flag, key


_OWN = dict([
    _gp_option("--selection", "search", "selection",
               "GP selection (default roulette, fitness-proportionate)", "GP parent selection",
               dict(choices=["roulette", "tournament"])),
    _gp_option("--p-crossover", "search", "p_crossover", "GP crossover probability (default 0.9)",
               "a GP breeding probability", dict(type=float), number(0, 1)),
    _gp_option("--p-mutation", "search", "p_mutation", "GP mutation probability (default 0.02)",
               "a GP breeding probability", dict(type=float), number(0, 1)),
    _gp_option("--p-creep", "search", "p_creep",
               "GP constant-creep probability: Gaussian steps on one tree's constants "
               "(default 0, herman tasks 0.1)", "a GP breeding probability",
               dict(type=float), number(0, 1)),
    _gp_option("--islands", "search", "islands",
               "GP island model: demes that breed apart and pass their best around a ring "
               "every 5 generations (default 1)", "the GP island model", dict(type=int),
               number(1, 10_000, True)),
    _gp_option("--elitism", "search", "elitism", "GP elites copied unchanged (default 1)",
               "the GP elite count", dict(type=int), number(0, 10**6, True)),
    _gp_option("--max-size", "search", "max_size", "GP nodes per tree cap (default 200)",
               "the GP tree-size cap", dict(type=int), number(1, 512, True)),
    _gp_option("--primitives", "family", "primitives",
               "GP function set, a comma list (default: the task's own set, shown by "
               "gpmotion show TASK; names: gpmotion list primitives)", "the GP function set",
               dict(type=str, metavar="NAME,..."), _primitives),
    _gp_option("--erc-range", "family", "erc_range",
               "GP random constants are uniform in [LO, HI] (default -1,1; write --erc-range=-2,2)",
               "the range of GP random constants", dict(type=str, metavar="LO,HI"), _range),
    _gp_option("--targets", "family", "targets",
               "what a GP tree's output is: its joint's target angle (angle); the "
               "target's rate of change (rate: integral action); or the joint's angle "
               "reached without the PD servo's sag under gravity (pi: an integral term "
               "corrects the target).  One mode for every joint, or per joint: "
               "MODE,JOINT=MODE,... e.g. rate,elbow_r=angle; default: the task's choice "
               "(gpmotion show TASK)",
               "the GP target mode", dict(type=str, metavar="MODE[,JOINT=MODE...]"), _targets),
    _gp_option("--polish", "search", "polish",
               "GP: the last N generations tune the best controller instead of breeding "
               "(each: the best and population - 1 small variations of it: constant creep, "
               "an output bias, now and then a new subtree; default 0)",
               "the GP final local search", dict(type=int), number(0, 10**6, True)),
    _gp_option("--subgoals", "family", "subgoals",
               "the task's subgoal flags are GP terminals too: 0 until the subgoal is first "
               "met, then 1 (lamp_hop: arrived; lamp_limbo: passed_pole, arrived)",
               "GP subgoal terminals", dict(action="store_const", const=True)),
    _gp_option("--fast-trig", "family", "fast_trig",
               "GP sin and cos inlined (fdlibm's polynomials, within 1 ulp of libm) instead "
               "of libm's calls: faster trees, but not libm's bits, so a search takes another "
               "path (off by default; recorded with the run, its controllers replay with it)",
               "GP fast trigonometry", dict(action="store_const", const=True)),
    _gp_option("--tau", "family", "tau",
               "time constant (s) of GP targets under --actuation kinematic (default 0.1)",
               "the GP target time constant", dict(type=float), number(0.002, 10),
               _kinematic_only),
])


def target_law(task, actuators, spec: str) -> bytecode.TargetLaw | None:
    """The law of a targets spec (gpmotion.gp.targets; None when every tree
    gives an angle): a rate joint's gain and range (its target stays inside),
    a pi joint's gain, angle sense and the integral's bound."""
    fig, m = task.figure, task.figure.model
    names = [fig.actuator_names[a] for a in actuators]
    modes = gp_targets.joint_modes(spec, names)
    if set(modes) == {"angle"}:
        return None
    missing = [n for n, md in zip(names, modes) if md == "pi" and f"angle_{n}" not in fig.sense_names]
    if missing:
        raise ValueError(f"GP targets pi need each such joint's angle sense; "
                         f"{fig.name} has no {', '.join('angle_' + n for n in missing)}")
    dof = m.act_dof[list(actuators)]
    lo, hi = np.maximum(m.lo[dof], -CLAMP), np.minimum(m.hi[dof], CLAMP)   # a free joint: ±CLAMP
    law = {"angle": lambda k: (0.0, 0.0, 0.0),
           "rate": lambda k: (RATE_GAIN, float(lo[k]), float(hi[k])),
           "pi": lambda k: (PI_GAIN, float(fig.sense_names.index(f"angle_{names[k]}")), PI_BOUND)}
    rows = [law[md](k) for k, md in enumerate(modes)]
    return bytecode.TargetLaw(modes, *(tuple(col) for col in zip(*rows)))


def _bias(tokens: list, d: int, info, sigma: float, max_depth: int, max_size: int) -> bool:
    """Tree d's output + a small constant (N(0, sigma)), in place (see
    GPFamily.mutate); False when the tree would pass the size or depth limit."""
    t = tokens[d]
    if t[0] == "add" and isinstance(t[-1], float) and len(t) > 2:
        t[-1] = float(t[-1] + random.gauss(0.0, sigma))       # already biased: creep the bias
        return True
    new = ["add", *t, random.gauss(0.0, sigma)]
    try:
        tree = bytecode.tokens_to_tree(new, info)
    except ValueError:
        return False
    if len(tree) > max_size or tree.height > max_depth:
        return False
    tokens[d] = new
    return True


def _check_erc_range(r):
    """Random constants are drawn uniformly from [lo, hi]: two finite numbers, lo < hi."""
    ok = (isinstance(r, (list, tuple)) and len(r) == 2
          and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in r))
    if not ok or not (np.all(np.isfinite(r)) and -1e6 <= r[0] < r[1] <= 1e6):
        raise ValueError(f"erc_range must be [lo, hi] with finite lo < hi within ±1e6, got {r!r}")


def _check_fast_trig(value, info) -> bool:
    """fast_trig is a bool, and only where a primitive calls math.sin or math.cos."""
    from ..gp.interpreter import trig_primitives
    if not isinstance(value, bool):
        raise ValueError(f"GP fast_trig must be true or false, got {value!r}")
    if value and not trig_primitives(info.function_set):
        raise ValueError(f"GP fast_trig: the function set ({', '.join(info.primitive_names)}) "
                         "calls no math.sin or math.cos, so there is nothing to make fast")
    return value


@register_family
class GPFamily(Family):
    """One tree per actuator (Gritz & Hahn); genome = list of token lists."""
    name = "gp"
    description = "Gritz & Hahn: one GP parse tree per controlled joint, evolved with DEAP"
    search_class = GPSearch
    cli = {"--generations": "generations", "--population": "population", **_OWN}
    takes_population = True
    plot_file = "trees.png"
    legacy_options = {"targets": "angle"}     # before rate targets, every tree gave an angle

    def __init__(self, task, primitives=None, erc_range=(-1.0, 1.0), tau=0.1,
                 terminals=None, subgoals=False, targets=None, fast_trig=False, **options):
        # tau: the fixed time constant of GP targets under `kinematic` actuation
        # (0.1 s = the shortest τ BSR rules may use, so comparisons are fair);
        # terminals: sense names replacing the task's terminal set (a preset's);
        # subgoals: add the task's subgoal flags as terminals (gpmotion.gp.subgoals);
        # fast_trig: the interpreter's sin/cos inlined (gpmotion.gp.fast_trig), recorded
        # only when set: a default run's config does not mention it
        super().__init__(task, primitives=list(primitives) if primitives else None,
                         erc_range=list(erc_range), tau=float(tau), **options)
        if terminals is not None:
            self.options["terminals"] = list(terminals)
        goals = task_subgoals(task) if subgoals else ()
        if subgoals:
            self.options["subgoals"] = True
        self.subgoal_table = subgoal_table(goals, task.figure.sense_names)
        if not 0.002 <= self.options["tau"] <= 10:
            raise ValueError(f"GP tau must be within 0.002..10 s, got {tau}")
        _check_erc_range(self.options["erc_range"])
        settings = gp_settings(task)
        terms = list(terminals) if terminals is not None else terminal_names(task)
        prims = primitives or settings.primitives                 # the task names its set
        declared = {s.name: s for s in (task_senses(task, prims, used=set(terms))
                                         if task.task_senses() else ())}
        used = [declared[t] for t in terms if t in declared]      # computed only if a tree may read it
        self.info = build_pset([t for t in terms if t not in declared], prims,
                               sense_names=task.figure.sense_names, erc_range=tuple(erc_range),
                               flag_names=[g.name for g in goals],
                               task_sense_names=[s.name for s in used])
        self.task_programs = [compile_formula(s.tree, task.figure.sense_names,
                                              self.info.opcode_names) for s in used]
        self.actuators = task.controlled_actuators()
        self.options["targets"] = targets = targets or settings.targets
        self.law = target_law(task, self.actuators, targets)
        self.fast_trig = _check_fast_trig(fast_trig, self.info)
        if self.fast_trig:
            self.options["fast_trig"] = True

    @property
    def pset(self):
        return self.info.pset

    def random(self, rng):
        """Ramped half-and-half trees (depth 2..6), as GPSearch's first generation
        draws them.  DEAP draws from Python's ``random``: seeded here from
        ``rng``, the caller's state put back."""
        outer = random.getstate()
        random.seed(int(rng.integers(2**63)))
        try:
            return [bytecode.tree_to_tokens(random_tree(self.pset, (2, 6), bytecode.MAX_TREE_DEPTH,
                                                        200)) for _ in self.actuators]
        finally:
            random.setstate(outer)

    def mutate(self, genome, rng, extra=None, *, max_depth: int = bytecode.MAX_TREE_DEPTH,
               max_size: int = 200):
        """One small variation of a whole controller, for searches that climb
        from a given one (a composite's phase refinement; GP's own search
        breeds instead).  Half the time constant creep on one tree; a third
        of the time a bias on one tree's output (its root becomes ``add(tree,
        c)``, c ~ N(0, σ); a tree already so biased creeps its c), which
        moves any tree smoothly, constants or not; else a new subtree in one
        tree.  σ is drawn log-uniformly in [0.005, 0.1] each time, so steps
        both coarse and fine are tried.  Within ``max_depth`` and ``max_size``
        (GPSearch's defaults; its polish passes its own).  DEAP draws from
        Python's ``random``: seeded here from ``rng``, the caller's state put
        back."""
        outer = random.getstate()
        random.seed(int(rng.integers(2**63)))
        try:
            tokens = [list(t) for t in genome]
            u = random.random()
            sigma = 10 ** random.uniform(-2.3, -1.0)         # 0.005 .. 0.1: coarse and fine steps
            if u < 1 / 2:
                ind = [bytecode.tokens_to_tree(t, self.info) for t in tokens]
                if creep_constants(ind, sigma)[1] is not None:
                    return [bytecode.tree_to_tokens(t) for t in ind]
            if u < 5 / 6 and _bias(tokens, random.randrange(len(tokens)), self.info, sigma,
                                   max_depth, max_size):
                return tokens
            ind = [bytecode.tokens_to_tree(t, self.info) for t in tokens]
            mutate_one_dof(ind, make_tree_operators(self.pset, max_depth, max_size)[1])
            return [bytecode.tree_to_tokens(t) for t in ind]
        finally:
            random.setstate(outer)

    def encode(self, genomes):
        return bytecode.encode_batch(list(genomes), self.info, self.actuators,
                                     subgoals=self.subgoal_table, law=self.law,
                                     task_programs=self.task_programs, fast_trig=self.fast_trig)

    def copy(self, genome):
        return [list(t) for t in genome]

    def to_json(self, genome):
        return {"kind": "gp", "pset": self.info.hash,
                "trees": [bytecode.tree_to_tokens(t) if isinstance(t, gp.PrimitiveTree) else list(t)
                          for t in genome]}

    def from_json(self, data):
        if not isinstance(data, dict) or data.get("kind") != "gp" or not isinstance(data.get("trees"), list):
            raise ValueError("not a GP controller (expected kind 'gp' with a list of trees)")
        trees = data["trees"]
        if len(trees) != len(self.actuators):
            raise ValueError(f"controller has {len(trees)} trees but {self.task.figure.name} has "
                             f"{len(self.actuators)} actuated joints")
        for t in trees:                       # validate: whitelist, size and depth caps
            bytecode.tokens_to_tree(t, self.info)
        return [list(t) for t in trees]

    def banner_note(self) -> str:
        return gp_targets.note(self.options["targets"])

    def plot(self, path, genome) -> None:
        from ..treeplot import plot_trees
        names = [self.task.figure.actuator_names[i] for i in self.actuators]
        plot_trees(path, self.to_json(genome)["trees"], titles=names,
                   suptitle=f"{self.task.name} ({self.name})")

    # -- search ----------------------------------------------------------------
    @classmethod
    def search_defaults(cls, task) -> dict:
        return {**GP_DEFAULTS, **gp_settings(task).defaults}

    def make_search(self, seed: int, **settings):
        """GPSearch; ring migration fitted to small islands (the user cannot set
        ``migrants``; its default 2 needs islands of 4)."""
        opts = {k: v for k, v in settings.items() if v is not None}
        defaults = self.search_defaults(self.task)
        if "polish" not in opts and defaults.get("polish") and isinstance(opts.get("generations"), int):
            # a task's polish is a share of its generations: --generations N keeps the share
            share = defaults["polish"] / defaults["generations"]
            opts["polish"] = min(round(share * opts["generations"]), max(0, opts["generations"] - 1))
        if "generations" in opts and defaults.get("phase_span"):
            # --generations N runs N generations, the phases over all of them, as before a
            # task's stop criterion (its phase_span and patience) existed
            opts.setdefault("phase_span", 0)
            opts.setdefault("patience", 0)
        if "migrants" not in opts:
            pop = opts.get("population", self.search_defaults(self.task)["population"])
            islands = opts.get("islands", 1)
            if isinstance(pop, int) and isinstance(islands, int) and islands >= 1:
                opts["migrants"] = min(2, pop // islands // 2)
        return super().make_search(seed, **opts)

    def noisy_settings(self) -> dict:
        # copies are re-evaluated on the new starts; the best is the latest generation's
        return {"reuse_costs": False, "fresh_scores": True}

    def budget_settings(self, budget: int, population: int | None = None) -> dict:
        pop = min(population or BUDGET_POPULATION, budget)
        return {"population": pop, "generations": max(1, budget // pop - 1)}

    presets = ("default", "gritz-hahn")

    @classmethod
    def apply_preset(cls, name, task_name, family_options, search):
        from ..gp.presets import apply_preset
        from ..task import get_task
        return apply_preset(name, get_task(task_name) if name else None, family_options, search)
