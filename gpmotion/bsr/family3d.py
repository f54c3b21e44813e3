"""Sense-based BSR on 3-D figures: what ``bsr-sense`` does differently there.

The family stays ``bsr-sense``; on a 3-D figure it reads §4.2's senses in
the figure-centric frame, low-pass filtered (:mod:`gpmotion.bsr.senses3d`,
kernel ``sense3d_kernel``), places new rules by the *contain* heuristic and
starts the serial search from enriched controllers
(:mod:`gpmotion.bsr.contain`).  :func:`use_3d_senses` rebinds the family's
encode / normalized / mutate to a picklable helper, so nothing outside the
family names the difference.
"""
from __future__ import annotations

import numpy as np

from gpmotion.bsr import contain, senses3d


class Senses3D:
    """The 3-D parts of a bsr-sense family (picklable: plain data + methods)."""

    def __init__(self, plan: senses3d.SensePlan, actuators):
        self.plan, self.actuators = plan, list(actuators)

    def encode(self, genomes):
        return senses3d.encode_batch(genomes, self.plan, self.actuators)

    def normalized(self, senses):
        return self.plan.normalized(senses)

    def mutate(self, genome, rng, extra=None):
        return contain.mutate(genome, rng, extra)


def use_3d_senses(family, filter_tau: float = senses3d.FILTER_TAU) -> None:
    task = family.task
    plan = senses3d.sense_plan(task.figure, family.actuators, task.record_every, task.dt, filter_tau)
    helper = Senses3D(plan, family.actuators)
    family.senses3d = helper
    family.sense_indices = np.arange(plan.n_senses)        # V stimulus columns
    family.encode, family.normalized, family.mutate = helper.encode, helper.normalized, helper.mutate
    family.search_class = contain.EnrichedSerialSearch     # starts from enriched controllers
