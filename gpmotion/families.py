"""Controller families on one harness: GP trees and BSR rule tables.

A family turns plain-data genomes into a ControllerBatch for a task, draws
random genomes, and reads/writes its genomes as safe JSON.  Everything a
search or an evaluator needs to know about a controller type is here.
"""
from __future__ import annotations

import numpy as np
from deap import gp

from .bsr import genome as bsr_genome
from .bsr import mutation as bsr_mutation
from .gp import bytecode
from .gp.pset import build_pset
from .gp.subgoals import subgoal_table, task_subgoals
from .task import Task

MAX_TREES = 64


class Family:
    name = ""
    default_actuation = "pd"
    needs_senses = False          # evaluator records normalized senses for extras

    def __init__(self, task: Task, **options):
        self.task = task
        self.options = options

    def encode(self, genomes):
        raise NotImplementedError

    def to_json(self, genome):
        raise NotImplementedError

    def from_json(self, data):
        raise NotImplementedError

    def config(self) -> dict:
        return {"family": self.name, **self.options}

    @property
    def default_tau(self) -> float:
        """τ for `kinematic` actuation when the controller does not set one."""
        return float(self.options.get("tau") or 0.1)


def _check_erc_range(r):
    """Random constants are drawn uniformly from [lo, hi]: two finite numbers, lo < hi."""
    ok = (isinstance(r, (list, tuple)) and len(r) == 2
          and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in r))
    if not ok or not (np.all(np.isfinite(r)) and -1e6 <= r[0] < r[1] <= 1e6):
        raise ValueError(f"erc_range must be [lo, hi] with finite lo < hi within ±1e6, got {r!r}")


class GPFamily(Family):
    """One tree per actuator (Gritz & Hahn); genome = list of token lists."""
    name = "gp"

    def __init__(self, task: Task, primitives=None, erc_range=(-1.0, 1.0), tau=0.1,
                 terminals=None, subgoals=False, **options):
        # tau: the fixed time constant of GP targets under `kinematic` actuation
        # (0.1 s = the shortest τ BSR rules may use, so comparisons are fair);
        # terminals: sense names replacing the task's terminal set (a preset's);
        # subgoals: add the task's subgoal flags as terminals (gpmotion.gp.subgoals)
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
        self.info = build_pset(list(terminals) if terminals is not None else task.terminal_names(),
                               primitives or task.primitives,     # the task names its set
                               sense_names=task.figure.sense_names, erc_range=tuple(erc_range),
                               flag_names=[g.name for g in goals])
        self.actuators = task.controlled_actuators()

    @property
    def pset(self):
        return self.info.pset

    def encode(self, genomes):
        return bytecode.encode_batch(list(genomes), self.info, self.actuators,
                                     subgoals=self.subgoal_table)

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


class BSRFamily(Family):
    """Auslander et al.'s sense- or time-based stimulus-response controllers."""
    default_actuation = "kinematic"
    kind = ""

    # Table 2's τ range is [2Δt, T/4]; Δt here is the controller tick.  At
    # 50 ms, τ ≥ 0.1 s: kinematic joints have unlimited torque, and the paper
    # (footnote 2) restricts τ to ranges that give acceptable behaviour.
    # Like GP, a rule drives only the task's controlled actuators (θ₀ has one
    # column per driven joint); the others hold the neutral pose with the
    # rollout's default τ, exactly as under a GP controller.
    def __init__(self, task: Task, rules=None, bsr_dt=0.05, **options):
        super().__init__(task, rules=rules, bsr_dt=bsr_dt, **options)
        if not isinstance(bsr_dt, (int, float)) or not 0.001 <= float(bsr_dt) <= 1.0:
            # a tick of 1e-9 s lets unlimited-torque joints fling a figure metres (not travel)
            raise ValueError(f"bsr_dt (the BSR controller tick) must be within 0.001..1 s, got {bsr_dt!r}")
        self.actuators = task.controlled_actuators()
        self.limits = task.figure.actuator_limits()[self.actuators]
        if not np.all(np.isfinite(self.limits)):
            raise ValueError(f"BSR needs finite joint limits on every driven actuator of {task.figure.name}")
        self.bsr_dt = min(float(bsr_dt), task.seconds / 8)   # short episodes keep a τ range

    def encode(self, genomes):
        return bsr_genome.encode_batch(list(genomes), self.sense_indices, len(self.actuators),
                                       self.actuators)

    def to_json(self, genome):
        return genome.to_dict()

    def from_json(self, data):
        g = bsr_genome.genome_from_dict(data)
        if g.kind != self.kind or g.n_act != len(self.actuators):
            raise ValueError(f"controller is a {g.kind}-based BSR for {g.n_act} joints; "
                             f"expected {self.kind}-based for the {len(self.actuators)} "
                             f"joints {self.task.name} drives")
        return g

    def mutate(self, genome, rng, extra=None):
        return bsr_mutation.mutate(genome, rng, extra)


class BSRSenseFamily(BSRFamily):
    name = "bsr-sense"
    kind = "sense"
    needs_senses = True

    def __init__(self, task, rules=None, **options):
        super().__init__(task, rules=rules or 8, **options)
        self.sense_indices = bsr_genome.table1_sense_indices(task.figure.sense_names)
        if task.figure.dimensions == 3:  # §4.2's filtered figure-centric senses, contain
            from .bsr.family3d import use_3d_senses
            use_3d_senses(self)

    def random(self, rng):
        return bsr_genome.random_sense_genome(rng, self.options["rules"], len(self.sense_indices),
                                              self.limits, self.bsr_dt, self.task.seconds)

    def normalized(self, senses):
        m = self.task.figure.model
        return bsr_mutation.normalized_sense_trajectory(senses, m.sense_lo, m.sense_hi,
                                                        self.sense_indices)


class BSRTimeFamily(BSRFamily):
    name = "bsr-time"
    kind = "time"

    def __init__(self, task, rules=None, t_per=None, segments="equal", **options):
        # segments: "equal" (R equal parts of t_per) or "variable" (the paper's
        # R − 1 dividers per period, evolved with the rules)
        super().__init__(task, rules=rules or 4, t_per=t_per or task.seconds,
                         segments=segments, **options)
        self.sense_indices = None
        if not 0 < float(self.options["t_per"]) <= 1e3:
            raise ValueError(f"t_per must be in (0, 1000] s, got {t_per}")
        if segments not in ("equal", "variable"):
            raise ValueError(f"segments must be 'equal' or 'variable', got {segments!r}")

    def random(self, rng):
        return bsr_genome.random_time_genome(rng, self.options["rules"], self.limits, self.bsr_dt,
                                             self.task.seconds, float(self.options["t_per"]),
                                             self.options["segments"])


FAMILIES = {f.name: f for f in (GPFamily, BSRSenseFamily, BSRTimeFamily)}


def make_family(name: str, task: Task, **options) -> Family:
    if name not in FAMILIES:
        from .names import unknown
        raise ValueError(unknown("controller family", name, FAMILIES))
    return FAMILIES[name](task, **{k: v for k, v in options.items() if v is not None})
