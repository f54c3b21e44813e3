"""``Trajectory.site(name)`` alone gives the numbers ``sites()`` gives for that
site, bit for bit, on planar and 3-D figures (a score reading one site pays
for one point; the pictures and other scores still read all of them)."""
from dataclasses import replace

import numpy as np
import pytest

from gpmotion.replay import load_controller, replay_genome
from gpmotion.study import SHIPPED

CONTROLLERS = [
    "gritz-hahn-lamp/controllers/hop-seed100.json",            # the planar lamp
    "gritz-hahn-lamp/controllers/hop-3d-seed100.json",         # the 3-D lamp
    "auslander-2d/controllers/beryl-periodic-seed0.json",      # a planar traveller
    "herman/controllers/grasp-seed100.json",                   # the humanoid
    "creatures/controllers/bob-bsr-sense-seed100-start0.json",  # a free-root biped
]


@pytest.mark.parametrize("rel", CONTROLLERS, ids=lambda r: r.split("/")[-1][:-5])
def test_one_site_is_the_same_as_that_site_of_all_sites(rel):
    task, family, actuation, genome, _ = load_controller(SHIPPED / rel)
    traj, _, _, _ = replay_genome(task, family, actuation, genome)
    names = traj.figure.site_names
    assert names
    alone = {}
    for n in names:
        fresh = replace(traj, q=traj.q.copy())          # nothing memoized for this q
        alone[n] = fresh.site(n)
    whole = replace(traj, q=traj.q.copy())
    every = whole.sites()
    for k, n in enumerate(names):
        assert alone[n].tobytes() == np.ascontiguousarray(every[..., k, :]).tobytes()
        assert whole.site(n) is not None and np.array_equal(whole.site(n), every[..., k, :])
