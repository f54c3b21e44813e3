"""Checks a batched rollout must pass on any figure, planar or 3-D (shared by
the physics tests); the figure drives three actuators."""
import numpy as np

import gpmotion
from gpmotion.controllers import schedule


def assert_a_batch_equals_its_episodes_run_alone(fig, n_steps):
    """Four sine-driven episodes in one batch are bit for bit each one run alone."""
    rng = np.random.default_rng(1)
    off = fig.model.neutral + rng.uniform(-0.3, 0.3, (4, 3))
    ctrl = schedule.sines(off, 0.4, rng.uniform(3, 12, (4, 3)), 0.0)
    scene = gpmotion.make_scene()
    batch = gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps)
    for e in range(4):
        one = schedule.sines(off[e], 0.4, ctrl.cf[e, 6:9], 0.0)
        single = gpmotion.rollout(fig, scene, one, n_steps=n_steps)
        assert np.array_equal(batch.q[e], single.q[0])
        assert np.array_equal(batch.contact_force[e], single.contact_force[0])


def assert_divergence_flags_one_episode_and_spares_the_rest(fig, velocity):
    """Episode 1 of three starts absurdly far out and fast (``qd[velocity]``):
    it alone is flagged, within a few steps, and the other two run as twins."""
    q0 = np.tile(fig.q_default, (3, 1))
    qd0 = np.zeros((3, fig.nv))
    q0[1, 0], qd0[1, velocity] = 9990.0, 5000.0        # leaves the sane box in a few ms
    ctrl = schedule.stack([schedule.constant(fig.model.neutral)] * 3)
    tr = gpmotion.rollout(fig, gpmotion.make_scene(), ctrl, n_steps=500, q0=q0, qd0=qd0)
    assert list(tr.diverged) == [False, True, False]
    assert 0 <= tr.diverged_step[1] < 10
    assert np.array_equal(tr.q[0], tr.q[2]) and np.all(np.isfinite(tr.q))
