"""Sense-based BSR (Auslander et al.): the rule whose hyperrectangle in
normalized sense space scores highest sets the target pose and τ."""
from __future__ import annotations

from ..bsr import genome as bsr_genome
from ..bsr import mutation as bsr_mutation
from ._bsr import BSRFamily
from .base import register_family


@register_family
class BSRSenseFamily(BSRFamily):
    name = "bsr-sense"
    description = "Auslander et al.: sense-based stimulus-response rules, serial search"
    kind = "sense"
    needs_senses = True           # the relevance heuristic mutates along a rule's senses

    def __init__(self, task, rules=None, **options):
        super().__init__(task, rules=rules or 8, **options)
        self.sense_indices = bsr_genome.table1_sense_indices(task.figure.sense_names)
        if task.figure.dimensions == 3:  # §4.2's filtered figure-centric senses, contain
            from ..bsr.family3d import use_3d_senses
            use_3d_senses(self)

    def random(self, rng):
        return bsr_genome.random_sense_genome(rng, self.options["rules"], len(self.sense_indices),
                                              self.limits, self.bsr_dt, self.task.seconds)

    def normalized(self, senses):
        m = self.task.figure.model
        return bsr_mutation.normalized_sense_trajectory(senses, m.sense_lo, m.sense_hi,
                                                        self.sense_indices)

    def extras(self, traj) -> list:
        return [self.normalized(traj.senses[e]) for e in range(traj.senses.shape[0])]
