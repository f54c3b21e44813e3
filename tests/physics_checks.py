"""Checks the physics tests run on planar and 3-D figures alike."""
import numpy as np

import gpmotion
from gpmotion.controllers import schedule


def momentum_drift(momentum, model, traj, size=np.linalg.norm):
    """Largest change of linear and of angular momentum over episode 0, each
    relative to its start (``momentum(model, q, qd)`` -> (P, L); ``size``: the
    norm it is measured in)."""
    mom = [momentum(model, q, qd) for q, qd in zip(traj.q[0], traj.qd[0])]
    P = np.array([p for p, _ in mom])
    L = np.array([l_ for _, l_ in mom])
    return np.abs(P - P[0]).max() / size(P[0]), np.abs(L - L[0]).max() / size(L[0])


def assert_momentum_drift_is_first_order(drift, bound):
    """``drift(dt)`` -> (linear, angular): both below ``bound`` at 1 ms, and
    halved with the step (the integrator conserves momentum to first order)."""
    p1, l1 = drift(1e-3)
    p2, l2 = drift(5e-4)
    assert p1 < bound and l1 < bound
    assert 0.4 < p2 / p1 < 0.6 and 0.4 < l2 / l1 < 0.6


def assert_a_batch_equals_its_episodes_run_alone(fig, n_steps):
    """Four sine-driven episodes in one batch are bit for bit each one run alone
    (the figure drives three actuators)."""
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
