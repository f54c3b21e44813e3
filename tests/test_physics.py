"""The simulator against analytic results and conservation laws."""
import numpy as np
import pytest

import gpmotion
from gpmotion.controllers import schedule
from gpmotion.figures import planar_spec_to_3d
from tests import physics_checks as B
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
    return B.momentum_drift(ref.momentum, fig.model, tr, size=lambda v: np.abs(v).max())


def test_free_figure_conserves_momentum_without_gravity():
    # internal PD torques only: momentum is conserved by the equations; the
    # integrator in joint coordinates conserves it to first order in dt
    B.assert_momentum_drift_is_first_order(_momentum_drift, 0.06)


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


@pytest.mark.parametrize("max_contacts", [0, 2])
def test_a_contact_limit_rests_a_box_on_that_many_points_carrying_its_weight(max_contacts):
    """Four points along the bottom: unlimited, the four share the weight;
    with max_contacts = 2 two points carry it all, sinking twice as deep."""
    spec = F.box(mass=2.0)
    spec["contacts"] += [{"name": f"mid{k}", "body": "b", "position": [x, 0.0]}
                         for k, x in enumerate((-0.07, 0.07))]
    spec["ground"] = {"max_contacts": max_contacts}
    fig = gpmotion.load_figure(spec)
    scene = gpmotion.make_scene(k_ground=5000.0, max_contacts=max_contacts)
    tr = gpmotion.simulate(fig, 3.0, scene=scene)
    assert ((tr.contact_force[0] > 0).sum(axis=1) <= (max_contacts or 4)).all()
    down = (tr.contact_force[0, -1] > 0).sum()
    assert down == (max_contacts or 4)
    assert tr.contact_force[0, -1].sum() == pytest.approx(2.0 * 9.81, rel=1e-3)
    assert np.abs(tr.qd[0, -50:]).max() < 1e-3
    sink = -tr.q[0, -1, 1] if max_contacts == 0 else None
    if sink is not None:
        assert sink == pytest.approx(2.0 * 9.81 / (4 * 5000.0), rel=1e-3)


def test_a_contact_limit_is_refused_where_it_cannot_apply():
    with pytest.raises(ValueError, match="max_contacts"):
        gpmotion.make_scene(max_contacts=-1)
    with pytest.raises(ValueError, match="max_contacts"):
        gpmotion.make_scene(max_contacts=1.5)
    spec3 = planar_spec_to_3d(F.box(mass=2.0))
    with pytest.raises(gpmotion.SpecError, match="planar figures only"):
        gpmotion.load_figure({**spec3, "ground": {"max_contacts": 2}})
    with pytest.raises(ValueError, match="planar figures only"):
        gpmotion.simulate(gpmotion.load_figure(spec3), 0.01, scene=gpmotion.make_scene(max_contacts=2))


def _rebound_speed(k, c, m, v0):
    """A mass m striking a spring-damper (k, c) that never pulls at speed v0:
    the speed it leaves with (the closed-form motion until k·p + c·ṗ = 0)."""
    wn, zeta = np.sqrt(k / m), c / (2 * np.sqrt(k * m))
    t = np.linspace(0.0, 10 / wn, 200001)[1:]
    if zeta < 1:
        wd = wn * np.sqrt(1 - zeta ** 2)
        p = v0 / wd * np.exp(-zeta * wn * t) * np.sin(wd * t)
        pd = v0 * np.exp(-zeta * wn * t) * (np.cos(wd * t) - zeta * wn / wd * np.sin(wd * t))
    else:
        r1, r2 = wn * (-zeta + np.sqrt(zeta ** 2 - 1)), wn * (-zeta - np.sqrt(zeta ** 2 - 1))
        p = v0 / (r1 - r2) * (np.exp(r1 * t) - np.exp(r2 * t))
        pd = v0 / (r1 - r2) * (r1 * np.exp(r1 * t) - r2 * np.exp(r2 * t))
    end = np.flatnonzero((k * p + c * pd <= 0) | (p <= 0))[0]
    return -pd[end]


@pytest.mark.parametrize("c", [60.0, 200.0])
def test_the_ground_returns_the_speed_its_damping_predicts(c):
    """Restitution of the penalty ground: a box dropped flat at 1 m/s without
    gravity leaves at the speed of the closed-form spring-damper that never
    pulls (0.35 m/s at the default c = 60 for 1 kg a point; 0.08 at 200), to
    2 % at dt = 0.25 ms (the step's error is first order: 8 % at 1 ms, c = 200)."""
    fig = gpmotion.load_figure(F.box(mass=2.0, z0=0.0005))
    qd0 = np.zeros(fig.nq)
    qd0[1] = -1.0
    tr = gpmotion.simulate(fig, 0.3, scene=gpmotion.make_scene(gravity=0.0, c_ground=c), qd0=qd0,
                           record_every=4, dt=2.5e-4)
    assert tr.contact_force[0].any() and not tr.contact_force[0, -1].any()
    assert tr.qd[0, -1, 1] == pytest.approx(_rebound_speed(5000.0, c, 1.0, 1.0), rel=0.02)


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


# ---- implicit PD ("stable PD"): the servo's armature a = dt·(kd + dt·kp) ----
def _servo_link(dims, **joint):
    """A light rod (30 g, 10 cm: I = 1e-4 kg·m² about its joint) on one servo."""
    spec = F.pendulum(actuated=True, mass=0.03, length=0.1, **joint)
    return gpmotion.load_figure(spec if dims == 2 else planar_spec_to_3d(spec))


def _step_matrix(I, kp, kd, dt, arm):
    """One semi-implicit Euler step of I θ̈ = −kp·e − kd·θ̇ (e = θ − θ*) with
    armature ``arm``, on (dt·θ̇, e): dt·θ̇⁺ = (1 − α)·dt·θ̇ − β·e,  e⁺ = e + dt·θ̇⁺,
    with α = kd·dt/(I + arm) and β = kp·dt²/(I + arm)."""
    al, be = kd * dt / (I + arm), kp * dt * dt / (I + arm)
    return np.array([[1 - al, -be], [1 - al, 1 - be]])


@pytest.mark.parametrize("dims", [2, 3])
def test_light_link_servo_settles_with_implicit_pd(dims):
    """kd·dt/I = 10: an explicit PD servo diverges, the implicit one settles.

    The step matrix A (:func:`_step_matrix`) has det A = 1 − α, tr A = 2 − α − β.
    Explicit (no armature): α = kd·dt/I = 10, det A = −9, so one eigenvalue is
    ≤ −3: the error triples and flips sign every step.  Implicit (armature
    dt·(kd + dt·kp)): α + β = dt·(kd + dt·kp)/(I + dt·(kd + dt·kp)) < 1, so
    |det A| < 1, 1 − tr A + det A = β > 0 and 1 + tr A + det A = 4 − 2α − β > 0
    (Jury): both eigenvalues inside the unit circle for every I > 0 and any gains.
    """
    I, dt, kp, kd, target = 1e-4, 1e-3, 20.0, 1.0, 0.5
    assert kd * dt / I == pytest.approx(10.0)
    explicit = np.abs(np.linalg.eigvals(_step_matrix(I, kp, kd, dt, 0.0))).max()
    implicit = np.abs(np.linalg.eigvals(_step_matrix(I, kp, kd, dt, dt * (kd + dt * kp)))).max()
    assert explicit > 3.0 and implicit < 0.99
    fig = _servo_link(dims, kp=kp, kd=kd)
    m = fig.model
    com = m.com[0]
    icom = m.icom[0] if dims == 2 else m.icom[0, 1, 1]
    assert icom + m.mass[0] * (com @ com) == pytest.approx(I)
    tr = gpmotion.rollout(fig, gpmotion.make_scene(gravity=0.0, ground=False),
                          schedule.constant([target]), n_steps=1000, dt=dt, record_every=1)
    theta = tr.q[0, :, 0]
    assert not tr.diverged[0]
    assert abs(theta[-1] - target) < 1e-6 and abs(tr.qd[0, -1, 0]) < 1e-6
    # overdamped (poles −kp/kd and −kd/I): a monotone approach, no overshoot, no rattle
    assert np.all(np.diff(theta) >= 0.0) and theta.max() <= target


@pytest.mark.parametrize("dims", [2, 3])
@pytest.mark.parametrize("tau_max", [100.0, 0.05])
def test_one_servo_step_is_the_implicit_update(dims, tau_max):
    """From rest, one step toward θ*: θ̇⁺ = dt·kp·θ*/(I + dt·kd + dt²·kp) when the
    servo is not saturated; a saturated one (kp·θ* > τ_max) acts explicitly,
    θ̇⁺ = dt·τ_max/I."""
    I, dt, kp, kd, target = 1e-4, 1e-3, 20.0, 1.0, 0.5
    fig = _servo_link(dims, kp=kp, kd=kd, torque_limit=tau_max)
    tr = gpmotion.rollout(fig, gpmotion.make_scene(gravity=0.0, ground=False),
                          schedule.constant([target]), n_steps=1, dt=dt, record_every=1)
    if kp * target < tau_max:
        expected = dt * kp * target / (I + dt * kd + dt * dt * kp)
    else:
        expected = dt * tau_max / I
    assert tr.qd[0, 1, 0] == pytest.approx(expected, rel=1e-12)
    assert tr.q[0, 1, 0] == pytest.approx(dt * expected, rel=1e-12)


def _pendulum_constants():
    """(I about the joint, m·g·(L/2), the hanging angle's offset from straight down
    — the spec's −1.5708 is not quite −π/2)."""
    m = gpmotion.load_figure(F.pendulum(actuated=True)).model
    return (m.icom[0] + m.mass[0] * (m.com[0] @ m.com[0]), m.mass[0] * 9.81 * m.com[0, 0],
            m.xtree[0, 0] + np.pi / 2)


def _pendulum_step_response(dt, seconds, target, kp, kd, implicit=True):
    """θ(t) of the actuated pendulum (1 kg, 1 m rod, hanging) stepped to ``target``
    by semi-implicit Euler in numpy: I θ̈ = u − m g (L/2) sin(θ + off), u = kp(θ* − θ)
    − kd θ̇, with (``implicit``) or without the servo's armature."""
    I, mgc, off = _pendulum_constants()
    arm = dt * (kd + dt * kp) if implicit else 0.0
    th = w = 0.0
    out = [th]
    for _ in range(int(round(seconds / dt))):
        w += dt * (kp * (target - th) - kd * w - mgc * np.sin(th + off)) / (I + arm)
        th += dt * w
        out.append(th)
    return np.array(out)


def _pendulum_exact(seconds, target, kp, kd, h=1e-4):
    """The same ODE by RK4 at a small step (the continuous-time answer)."""
    I, mgc, off = _pendulum_constants()

    def f(y):
        return np.array([y[1], (kp * (target - y[0]) - kd * y[1] - mgc * np.sin(y[0] + off)) / I])
    y = np.zeros(2)
    out = [0.0]
    for _ in range(int(round(seconds / h))):
        k1 = f(y)
        k2 = f(y + 0.5 * h * k1)
        k3 = f(y + 0.5 * h * k2)
        k4 = f(y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(y[0])
    return np.array(out)


def test_pd_step_response_is_the_explicit_one_to_first_order():
    """Modest gains (the test pendulum's kp 50, kd 2: kd·dt/I = 0.006): the
    implicit servo's step response is the kernel's numpy recursion, and it
    differs from the exact response, and from the explicit servo's, by O(dt)."""
    kp, kd, target, T = 50.0, 2.0, 0.3, 3.0
    exact = _pendulum_exact(T, target, kp, kd)[::100]            # every 10 ms
    err, gap = [], []
    for dt, every in ((1e-3, 10), (5e-4, 20)):
        fig, tr = run(F.pendulum(actuated=True), T, dt=dt, record_every=every,
                      targets=np.array([target]))
        theta = tr.q[0, :, 0]
        assert np.abs(theta - _pendulum_step_response(dt, T, target, kp, kd)[::every]).max() < 1e-12
        err.append(np.abs(theta - exact).max())
        gap.append(np.abs(theta - _pendulum_step_response(dt, T, target, kp, kd, False)[::every]).max())
    assert err[0] < 0.01 * target and gap[0] < 0.01 * target
    assert 0.4 < err[1] / err[0] < 0.6 and 0.4 < gap[1] / gap[0] < 0.6


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
    B.assert_a_batch_equals_its_episodes_run_alone(gpmotion.load_figure("lamp"), 1500)


def test_divergence_flags_one_episode_and_spares_the_rest():
    B.assert_divergence_flags_one_episode_and_spares_the_rest(gpmotion.load_figure("lamp"), 0)
