"""What the two BSR families share (Auslander et al.): rule tables over the
controlled joints, searched by the serial search of the paper's Fig. 3."""
from __future__ import annotations

import numpy as np

from .. import cli_options
from ..bsr import genome as bsr_genome
from ..bsr import mutation as bsr_mutation
from ..cli_options import Option, number
from ..records import validate_number
from ..search.serial import SerialSearch, serial_generations
from .base import Family

SERIAL_DEFAULTS = dict(n_working=10, n_generations=4000, reseed_every=200, phase_steps=20)
BUDGET_WORKING = 10              # compare: working controllers under a budget

for _option in (
        Option("--working", "search", {}, "serial search: working controllers C (default 10)",
               "the serial search's working set (GP has --population)", dict(type=int),
               number(2, 10_000_000, True)),
        Option("--reseed-every", "search", {},
               "serial search: reseeding interval in rounds (default 200)",
               "the serial search's reseeding interval", dict(type=int),
               number(1, 10_000_000, True)),
        Option("--restart-after", "search", {},
               "serial search: restart the whole working set from fresh random controllers "
               "when its best has not improved (by more than --restart-delta) for N rounds "
               "(default 0: never)",
               "the serial search's restart interval", dict(type=int),
               number(0, 10_000_000, True)),
        Option("--restart-delta", "search", {},
               "serial search: an improvement of the working set's best smaller than this "
               "does not put off a restart (cost units; default 0)",
               "the serial search's restart threshold", dict(type=float), number(0.0, 1e300)),
        Option("--rules", "family", {}, "BSR rules per controller (default sense 8, time 4)",
               "the number of BSR rules (a GP controller is one tree per joint)", dict(type=int),
               number(1, bsr_genome.MAX_RULES, True))):
    cli_options.register_option(_option)


class BSRFamily(Family):
    """Auslander et al.'s sense- or time-based stimulus-response controllers."""
    default_actuation = "kinematic"
    kind = ""
    search_class = SerialSearch
    cli = {"--generations": "n_generations", "--working": "n_working",
           "--reseed-every": "reseed_every", "--restart-after": "restart_after",
           "--restart-delta": "restart_delta", "--rules": "rules"}

    # Table 2's τ range is [2Δt, T/4]; Δt here is the controller tick.  At
    # 50 ms, τ ≥ 0.1 s: kinematic joints have unlimited torque, and the paper
    # (footnote 2) restricts τ to ranges that give acceptable behaviour.
    # Like GP, a rule drives only the task's controlled actuators (θ₀ has one
    # column per driven joint); the others hold the neutral pose with the
    # rollout's default τ, exactly as under a GP controller.
    def __init__(self, task, rules=None, bsr_dt=0.05, **options):
        if rules is not None:
            validate_number("rules", rules, lo=1, hi=bsr_genome.MAX_RULES, integer=True)
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

    @classmethod
    def search_defaults(cls, task) -> dict:
        return dict(SERIAL_DEFAULTS)

    def noisy_settings(self) -> dict:
        return {"fresh_scores": True}          # parents re-scored on each round's starts

    def budget_settings(self, budget: int, population: int | None = None) -> dict:
        return {"n_working": BUDGET_WORKING,
                "n_generations": serial_generations(self.task, budget, BUDGET_WORKING)}
