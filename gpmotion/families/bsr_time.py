"""Time-based BSR (Auslander et al.): R time segments of a period t_per,
one rule (target pose and τ) each."""
from __future__ import annotations

from .. import cli_options
from ..bsr import genome as bsr_genome
from ..cli_options import Option, number
from ._bsr import BSRFamily
from .base import register_family

cli_options.register_option(Option(
    "--t-per", "family", {}, "time-based BSR period in s (default: the episode length)",
    "the period of time-based BSR rules", dict(type=float), number(1e-3, 1e3)))
cli_options.register_option(Option(
    "--segments", "family", {},
    "time-based BSR segments: equal parts of t_per (default) or variable (evolved dividers)",
    "the segment durations of time-based BSR rules", dict(choices=["equal", "variable"])))


@register_family
class BSRTimeFamily(BSRFamily):
    name = "bsr-time"
    description = "Auslander et al.: time-based stimulus-response rules, serial search"
    kind = "time"
    cli = {**BSRFamily.cli, "--t-per": "t_per", "--segments": "segments"}

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
