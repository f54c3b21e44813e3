"""The simulator against analytic results and conservation laws."""
import numpy as np
import pytest

import gpmotion
from gpmotion.controllers import schedule
from tests import figures_for_tests as F
from tests.reference import planar_ref as ref

NO_GROUND = dict(ground=False)


def run(spec_or_fig, seconds, scene=None, **kw):
    fig = gpmotion.load_figure(spec_or_fig)
    return fig, gpmotion.simulate(fig, seconds, scene=scene or gpmotion.make_scene(**NO_GROUND), **kw)


def test_pendulum_period_matches_compound_pendulum_formula():
    L, m, g = 1.0, 1.0, 9.81
    fig, tr = run(F.pendulum(initial=0.05), 10.0, record_every=1)
    theta = tr.q[0, :, 0]
    crossings = np.where(np.diff(np.sign(theta)) != 0)[0]
    # linear interpolation of each zero crossing
    tc = [tr.times[i] - theta[i] * (tr.times[i + 1] - tr.times[i]) / (theta[i + 1] - theta[i]) for i in crossings]
    period = 2 * np.mean(np.diff(tc))
    expected = 2 * np.pi * np.sqrt((m * L ** 2 / 3) / (m * g * L / 2))
    assert abs(period - expected) / expected < 0.005


def _energy_drift(n_links, amplitude, dt):
    """Largest |E(t) − E(0)| over 10 s, relative to the energy of motion E(0) − E_rest."""
    fig, tr = run(F.pendulum(n_links=n_links, initial=amplitude), 10.0, dt=dt,
                  record_every=int(round(0.02 / dt)))
    e = np.array([ref.energy(fig.model, 9.81, q, qd) for q, qd in zip(tr.q[0], tr.qd[0])])
    rest = ref.energy(fig.model, 9.81, np.zeros(fig.nq), np.zeros(fig.nq))
    assert not tr.diverged[0]
    return np.abs(e - e[0]).max() / (e[0] - rest)


@pytest.mark.parametrize("n_links, amplitude", [(1, 1.2), (2, 0.5), (3, 0.3)])
def test_passive_chains_conserve_energy_at_the_default_step(n_links, amplitude):
    assert _energy_drift(n_links, amplitude, 1e-3) < 0.005


def test_energy_error_is_first_order_in_dt():
    # a chaotic swing (double pendulum from 1.2 rad): semi-implicit Euler is
    # not exactly symplectic for a configuration-dependent mass matrix, so
    # the drift must shrink linearly with the step
    d1, d2 = _energy_drift(2, 1.2, 1e-3), _energy_drift(2, 1.2, 5e-4)
    assert 0.4 < d2 / d1 < 0.6


def _momentum_drift(dt):
    fig = gpmotion.load_figure(F.free_star())
    scene = gpmotion.make_scene(gravity=0.0, ground=False)
    qd0 = np.zeros(fig.nq)
    qd0[:3] = [0.3, -0.2, 0.5]
    ctrl = schedule.sines([0.2, -0.3], [0.8, 0.6], [7.0, 11.0], [0.0, 1.0])
    tr = gpmotion.rollout(fig, scene, ctrl, n_steps=int(3 / dt), qd0=qd0, dt=dt,
                          record_every=int(0.1 / dt))
    assert np.abs(tr.q[0, -1, 3:] - tr.q[0, 0, 3:]).max() > 0.1   # it really moved its joints
    mom = [ref.momentum(fig.model, q, qd) for q, qd in zip(tr.q[0], tr.qd[0])]
    P = np.array([p for p, _ in mom])
    L = np.array([l for _, l in mom])
    return np.abs(P - P[0]).max() / np.abs(P[0]).max(), np.abs(L - L[0]).max() / abs(L[0])


def test_free_figure_conserves_momentum_without_gravity():
    # internal PD torques only: momentum is conserved by the equations; the
    # integrator in joint coordinates conserves it to first order in dt
    p1, l1 = _momentum_drift(1e-3)
    p2, l2 = _momentum_drift(5e-4)
    assert p1 < 0.06 and l1 < 0.06
    assert 0.4 < p2 / p1 < 0.6 and 0.4 < l2 / l1 < 0.6


def test_tumbling_rigid_body_keeps_momentum_exactly():
    fig = gpmotion.load_figure(F.box())
    qd0 = np.array([0.7, 0.4, 3.0])
    tr = gpmotion.simulate(fig, 2.0, scene=gpmotion.make_scene(gravity=0.0, ground=False), qd0=qd0)
    assert np.abs(tr.qd[0] - qd0).max() < 1e-12


def test_box_rests_at_the_height_the_springs_predict():
    spec = F.box(mass=2.0)
    fig = gpmotion.load_figure(spec)
    scene = gpmotion.make_scene(k_ground=5000.0)
    tr = gpmotion.simulate(fig, 3.0, scene=scene)
    sink = 2.0 * 9.81 / (2 * 5000.0)
    assert tr.q[0, -1, 1] == pytest.approx(-sink, rel=1e-3)
    assert np.abs(tr.qd[0, -50:]).max() < 1e-6          # no jitter at rest
    assert tr.contact_force[0, -1].sum() == pytest.approx(2.0 * 9.81, rel=1e-4)


def test_sliding_box_decelerates_at_mu_g():
    mu, v0 = 0.5, 2.0
    fig = gpmotion.load_figure(F.box(mass=2.0, z0=-0.002))
    scene = gpmotion.make_scene(mu=mu)
    qd0 = np.zeros(fig.nq)
    qd0[0] = v0
    tr = gpmotion.simulate(fig, 1.5, scene=scene, qd0=qd0, record_every=1)
    vx = tr.qd[0, :, 0]
    sliding = (tr.times > 0.1) & (vx > 0.3)
    slope = np.polyfit(tr.times[sliding], vx[sliding], 1)[0]
    assert slope == pytest.approx(-mu * 9.81, rel=0.02)
    stop = v0 ** 2 / (2 * mu * 9.81)
    assert tr.q[0, -1, 0] == pytest.approx(stop, rel=0.03)
    assert abs(vx[-1]) < 1e-3                           # and then it stays put


def test_pd_servo_holds_with_the_static_error_gravity_demands():
    m, L, kp = 1.0, 1.0, 50.0
    # horizontal arm: gravity torque m g L/2 against the spring kp (θd − θ)
    fig, tr = run(F.pendulum(actuated=True, angle=0.0), 6.0, targets=np.array([0.0]))
    err = -tr.q[0, -1, 0]
    # small-angle static balance: kp·err = m g (L/2) cos(θ)
    assert err == pytest.approx(m * 9.81 * L / 2 * np.cos(err) / kp, rel=1e-3)
    assert np.abs(tr.qd[0, -20:]).max() < 1e-6


def test_kinematic_actuation_follows_the_tau_law():
    tau, th0, thi = 0.1, 0.8, 0.0
    fig, tr = run(F.pendulum(actuated=True, angle=0.0), 1.0, record_every=1,
                  targets=schedule.constant([th0], taus=[tau]), actuation="kinematic")
    t = tr.times
    exact = th0 + (thi - th0) * (1 + t / tau) * np.exp(-t / tau)
    assert np.abs(tr.q[0, :, 0] - exact).max() < 0.01 * abs(th0 - thi)


def test_joint_limit_stops_a_falling_link():
    m, L, k = 1.0, 1.0, 2000.0
    spec = F.pendulum(angle=0.0)
    spec["joints"][0]["limits"] = [-0.3, 0.3]
    spec["limits"] = {"stiffness": k, "damping": 20.0}
    fig, tr = run(spec, 3.0, record_every=1)
    # the limit spring stores at most the energy of the fall (plus a little more fall)
    fall = m * 9.81 * L / 2 * np.sin(0.35)
    assert tr.q[0, :, 0].min() > -0.3 - np.sqrt(2 * fall / k) - m * 9.81 * L / 2 / k
    assert tr.q[0, -1, 0] == pytest.approx(-0.3 - m * 9.81 * L / 2 * np.cos(0.3) / k, abs=2e-4)


def test_pole_collision_pushes_back_and_reports_the_hit():
    fig = gpmotion.load_figure(F.box(z0=1.0))
    scene = gpmotion.make_scene(poles=[[0.0, 0.5, 0.05]])
    tr = gpmotion.simulate(fig, 1.5, scene=scene)
    assert tr.pole_hit[0].max() > 0
    assert tr.q[0, -1, 1] > 0.5            # rests on the pole, above it
    assert tr.pole_hit[0, -1] == pytest.approx(2 * 9.81 / 5000.0, rel=0.05)


@pytest.mark.parametrize("name", ["lamp", "starman", "beryl"])
def test_shipped_figures_come_to_rest_without_sinking(name):
    fig = gpmotion.load_figure(name)
    tr = gpmotion.simulate(fig, 10.0 if name == "beryl" else 3.0)
    assert not tr.diverged[0]
    assert np.abs(tr.qd[0, -30:]).max() < 1e-3          # no jitter
    sites = tr.segments()[0, -1]
    assert sites[..., 1].min() > -0.01                  # nothing sunk below 1 cm
    assert tr.contact_force[0, -1].sum() == pytest.approx(fig.total_mass * 9.81, rel=1e-3)


def test_a_batch_equals_its_episodes_run_alone():
    fig = gpmotion.load_figure("lamp")
    rng = np.random.default_rng(1)
    off = fig.model.neutral + rng.uniform(-0.3, 0.3, (4, 3))
    ctrl = schedule.sines(off, 0.4, rng.uniform(3, 12, (4, 3)), 0.0)
    scene = gpmotion.make_scene()
    batch = gpmotion.rollout(fig, scene, ctrl, n_steps=1500)
    for e in range(4):
        one = schedule.sines(off[e], 0.4, ctrl.cf[e, 6:9], 0.0)
        single = gpmotion.rollout(fig, scene, one, n_steps=1500)
        assert np.array_equal(batch.q[e], single.q[0])
        assert np.array_equal(batch.contact_force[e], single.contact_force[0])


def test_divergence_flags_one_episode_and_spares_the_rest():
    fig = gpmotion.load_figure("lamp")
    q0 = np.tile(fig.q_default, (3, 1))
    qd0 = np.zeros((3, fig.nq))
    q0[1, 0], qd0[1, 0] = 9990.0, 5000.0        # absurd: leaves the sane box in a few ms
    ctrl = schedule.stack([schedule.constant(fig.model.neutral)] * 3)
    tr = gpmotion.rollout(fig, gpmotion.make_scene(), ctrl, n_steps=500, q0=q0, qd0=qd0)
    assert list(tr.diverged) == [False, True, False]
    assert 0 <= tr.diverged_step[1] < 10
    assert np.array_equal(tr.q[0], tr.q[2]) and np.all(np.isfinite(tr.q))
