"""The 3-D creatures (Cujo, Rex, Bob), fixed and 2-DOF joints, 3-D BSR."""
import copy
from pathlib import Path

import numpy as np
import pytest

import gpmotion
from gpmotion.bsr import contain, secondary3d as s3, senses3d
from gpmotion.bsr.genome import random_sense_genome, random_time_genome
from gpmotion.bsr.mutation import relevant_stimulus
from gpmotion.controllers import schedule
from gpmotion.inprocess import InProcessEvaluator
from gpmotion.families import make_family
from gpmotion.figures import load_figure, load_spec
from gpmotion.sim import spatial3d as K
from tests.reference import spatial3d_ref as ref
from tests.replay_checks import same_numbers
from tests.test_physics3d import random_state, scratch

FIGURES = Path(gpmotion.__file__).parent / "figures"
CREATURES = ("cujo", "rex", "bob")


def n_rods(fig):
    return len(fig.body_names)


# ---------------------------------------------------------------- figures
@pytest.mark.parametrize("name, rods, free", [("cujo", 7, 9), ("rex", 15, 10), ("bob", 9, 10)])
def test_creatures_have_the_papers_rods_and_free_angles(name, rods, free):
    fig = load_figure(name)
    assert fig.name == name                       # (a body loop once shadowed the name)
    assert n_rods(fig) == rods and len(fig.actuator_names) == free
    slots = 2 * (rods - 1)                        # θ and ψ per joint (Fig. 6)
    fixed = slots - free
    if name == "rex":                             # "about two thirds ... fixed"
        assert abs(fixed / slots - 2 / 3) < 0.05
    if name == "bob":                             # "roughly one third ... fixed"
        assert abs(fixed / slots - 1 / 3) < 0.05


def test_average_joint_ranges_are_the_papers():
    def mean_span_deg(name):
        m = load_figure(name).model
        return np.degrees(m.hi[m.act_dof] - m.lo[m.act_dof]).mean()
    assert abs(mean_span_deg("cujo") - 25) < 1          # "average joint-angle range of 25°"
    assert abs(mean_span_deg("rex") - 40) < 1           # "average range of 40°"
    assert 20 < mean_span_deg("bob") < 25               # "a little less than 25°"


def test_fixed_joint_moves_exactly_like_a_hinge_held_still():
    """A welded rod (type = "fixed") against the same rod on a hinge whose
    kinematic actuation holds it at 0: same motion to rounding."""
    spec = load_spec(FIGURES / "rex.toml")
    hinged = copy.deepcopy(spec)
    hinged["name"] = "rex_hinged"
    for j in hinged["joints"]:
        if j.get("type") == "fixed":
            j.update(type="hinge", axis=[0.0, 1.0, 0.0], limits=[-1.0, 1.0], kp=1.0, torque_limit=1.0)
    a, b = load_figure(spec), load_figure(hinged)
    assert len(b.model.parent) == len(a.model.parent) + 7          # 7 welded joints
    scene = gpmotion.make_scene(mu=0.3)
    qd = np.zeros(a.nv)
    qd[:6] = [0.3, -0.5, 0.2, 0.1, 0.2, 0.0]                       # tumble and drop
    ta = gpmotion.rollout(a, scene, schedule.constant(a.model.neutral), n_steps=400, qd0=qd,
                          actuation="kinematic", default_tau=0.1)
    qdb = np.zeros(b.nv)
    qdb[:6] = qd[:6]
    tb = gpmotion.rollout(b, scene, schedule.constant(b.model.neutral), n_steps=400, qd0=qdb,
                          actuation="kinematic", default_tau=0.1)
    assert np.abs(ta.com[0, -1, :3] - ta.com[0, 0, :3]).max() > 0.05     # it moved
    assert np.allclose(ta.q[0, :, :7], tb.q[0, :, :7], atol=1e-9)
    assert np.allclose(ta.com, tb.com, atol=1e-9)


def test_fixed_joint_combines_mass_com_and_inertia():
    spec = {"dimensions": 3, "name": "weld", "root": {"type": "free", "body": "a"},
            "bodies": [{"name": "a", "mass": 2.0, "segment": [[0, 0, 0], [1, 0, 0]], "inertia": [1, 2, 3]},
                       {"name": "b", "mass": 1.0, "segment": [[0, 0, 0], [0, 0, 1]], "inertia": [0.5, 0.5, 0.1]}],
            "joints": [{"name": "w", "parent": "a", "child": "b", "type": "fixed", "offset": [1, 0, 0],
                        "rotation_deg": [90, 0, 0]}]}
    m = load_figure(spec).model
    assert len(m.parent) == 1 and m.mass[0] == 3.0
    cb = np.array([1.0, -0.5, 0.0])                  # b's com, rotated 90° about x
    assert np.allclose(m.com[0], (2 * np.array([0.5, 0, 0]) + cb) / 3)
    Ib = np.diag([0.5, 0.1, 0.5])                    # b's inertia in a's axes
    c = m.com[0]

    def shift(mass, d):
        return mass * (d @ d * np.eye(3) - np.outer(d, d))
    want = np.diag([1.0, 2, 3]) + shift(2, np.array([0.5, 0, 0]) - c) + Ib + shift(1, cb - c)
    assert np.allclose(m.icom[0], want)
    assert np.allclose(m.seg_b[1], [1.0, -1.0, 0.0])   # b's rod drawn in a's frame


@pytest.mark.parametrize("name", CREATURES)
def test_creature_dynamics_match_the_rnea_crba_reference(name):
    """The 2-DOF (Euler-chain) and welded joints through ABA against the numpy twin."""
    fig = load_figure(name)
    M = fig.model
    nl, nv = len(M.parent), fig.nv
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, qd = random_state(fig, rng)
        tau = rng.normal(0, 5, nv)
        fext = rng.normal(0, 5, (nl, 6))
        presc, presc_qdd, arm = np.zeros(nv, np.int64), np.zeros(nv), np.zeros(nv)
        s = scratch(fig)
        K.kinematics(M, q, qd, s["R"], s["pos"], s["E"], s["r"], s["v"], s["c"])
        qdd, t = np.zeros(nv), tau.copy()
        K.aba(M, qd, s["E"], s["r"], s["v"], s["c"], t, fext, presc, presc_qdd, arm, 9.81,
              np.zeros((nl, 6, 6)), np.zeros((nl, 6)), np.zeros((nl, 6)), np.zeros(nl),
              np.zeros(nl), np.zeros((nl, 6)), qdd, np.zeros((3, 6, 6)), np.zeros((3, 6)))
        qdd_ref, _ = ref.forward_dynamics(M, q, qd, tau, 9.81, fext, presc, presc_qdd, arm)
        assert np.allclose(qdd, qdd_ref, rtol=1e-9, atol=1e-8)


def test_cujo_conserves_momentum_while_moving_its_2dof_joints_in_free_fall():
    fig = load_figure("cujo")
    qd0 = np.zeros(fig.nv)
    qd0[:6] = [0.3, -0.2, 0.4, 0.2, 0.1, -0.3]
    n = fig.n_act
    ctrl = schedule.sines(np.full(n, 0.2), np.linspace(0.6, 1.4, n), np.linspace(3, 9, n), np.arange(n))
    tr = gpmotion.rollout(fig, gpmotion.make_scene(gravity=0.0, ground=False), ctrl, n_steps=2000,
                          qd0=qd0, record_every=100)
    assert np.abs(tr.q[0, -1, 7:] - tr.q[0, 0, 7:]).max() > 0.05
    mom = [ref.momentum(fig.model, q, qd) for q, qd in zip(tr.q[0], tr.qd[0])]
    P = np.array([p for p, _ in mom])
    L = np.array([l_ for _, l_ in mom])
    # semi-implicit Euler: first-order drift (test_physics3d checks the order)
    assert np.abs(P - P[0]).max() < 0.01 * np.linalg.norm(P[0])
    assert np.abs(L - L[0]).max() < 0.01 * np.linalg.norm(L[0])


@pytest.mark.parametrize("name", CREATURES)
def test_creatures_stand_under_kinematic_joints_except_bob(name):
    tr = gpmotion.simulate(name, 2.0, actuation="kinematic", default_tau=0.1)
    drift = np.abs(tr.com[0, -1, :2] - tr.com[0, 0, :2]).max()
    if name == "bob":          # point feet: he topples, as the paper says
        assert tr.com[0, -1, 2] < 0.6 * tr.com[0, 0, 2]
    else:
        assert drift < 0.05 and tr.com[0, -1, 2] > 0.9 * tr.com[0, 0, 2]


# ---------------------------------------------------------------- parameter counts
def test_rex_time_based_controller_has_47_free_variables():
    """§4.1: 2NR − 1 = 119 variables for N = 15 rods, R = 4; 47 of them free."""
    task = gpmotion.get_task("rex_walk")
    fam = make_family("bsr-time", task, rules=4, segments="variable")
    g = fam.random(np.random.default_rng(0))
    N, R = n_rods(task.figure), 4
    assert 2 * N * R - 1 == 119
    assert (R - 1) + (2 * N - 2) * R + R == 119
    assert g.n_parameters == 47
    assert random_time_genome(np.random.default_rng(0), 4, fam.limits, 0.05, 4.0, 4.0).n_parameters == 44


def test_3d_sense_based_rule_size():
    """V = 10 body senses + one force per contact + one angle per driven joint;
    a rule has 2V + n_act + 1 numbers (μ, λ, θ₀, τ)."""
    for name, task in (("bob", "bob_walk"), ("rex", "rex_walk")):
        t = gpmotion.get_task(task)
        fam = make_family("bsr-sense", t, rules=10)
        V = 10 + len(t.figure.contact_names) + len(t.figure.actuator_names)
        assert fam.senses3d.plan.n_senses == V
        g = fam.random(np.random.default_rng(0))
        assert g.n_parameters == 10 * (2 * V + len(t.figure.actuator_names) + 1)


# ---------------------------------------------------------------- the filter
def test_low_pass_step_response():
    alpha = senses3d.filter_alpha(0.02, 0.05)
    assert alpha == pytest.approx(1 - np.exp(-0.4))
    x = np.zeros((60, 1))
    x[10:] = 1.0
    y = senses3d.low_pass(x, alpha)[:, 0]
    k = np.arange(50)
    assert np.allclose(y[10:], 1 - (1 - alpha) ** (k + 1))
    assert y[10 + 1] < 1 - np.exp(-1) < y[10 + 2]        # 63 % after τ_f = 2.5 samples of input
    # a 25 Hz chatter passes at under a third, a 1 Hz gait at over 95 %
    t = np.arange(500) * 0.02
    for f, lo, hi in ((25.0, 0.0, 0.33), (1.0, 0.95, 1.0)):
        y = senses3d.low_pass(np.sin(2 * np.pi * f * t)[:, None], alpha)[100:, 0]
        assert lo < np.abs(y).max() <= hi


def test_sense_kernel_filters_and_selects_as_its_numpy_twin():
    task = gpmotion.get_task("bob_walk", seconds=1.0)
    fam = make_family("bsr-sense", task)
    ev = gpmotion.inprocess.InProcessEvaluator(task, fam)
    rng = np.random.default_rng(3)
    gs = [fam.random(rng) for _ in range(3)]
    for _ in range(3):                      # contain rules: several rules get to fire
        tr = ev.rollout(gs, record_senses=True)
        gs = [contain.contain_rule(g, rng, fam.normalized(tr.senses[e])) for e, g in enumerate(gs)]
    tr = ev.rollout(gs, record_senses=True)
    fired = set()
    for e, g in enumerate(gs):
        active = senses3d.select_rules(g, fam.normalized(tr.senses[e]))
        fired |= set(active.tolist())
        assert np.array_equal(tr.targets[e][:, fam.actuators], g.theta0[active])
    assert len(fired) > 1


def test_senses_are_in_the_heading_frame():
    fig = load_figure("rex")
    plan = senses3d.sense_plan(fig, range(fig.n_act), 20, 1e-3)
    raw = np.zeros((1, len(fig.sense_names)))
    names = fig.sense_names
    raw[0, names.index("yaw")] = np.pi / 2                 # facing +y, moving +y, up tilted to +y
    raw[0, names.index("vy")] = 1.0
    raw[0, names.index("up_y")] = 0.5
    raw[0, names.index("wz")] = 2.0
    d = dict(zip(plan.names, plan.derived(raw)[0]))
    assert d["v_fwd"] == pytest.approx(1.0) and d["v_left"] == pytest.approx(0.0, abs=1e-12)
    assert d["up_fwd"] == pytest.approx(0.5) and d["w_up"] == 2.0


# ---------------------------------------------------------------- contain
def test_contain_boxes_contain_their_point_and_corner_boxes_do_not():
    rng = np.random.default_rng(0)
    traj = rng.uniform(0, 1, (40, 30))
    for _ in range(200):
        mu, lam, p, f = contain.containing_stimulus(rng, traj)
        assert np.allclose(p, traj[f])
        assert np.all(np.abs(lam * (p - mu)) < 1)               # inside on every sense
        mu2, lam2, p2, _ = relevant_stimulus(rng, traj)         # 2-D: a corner on the point
        assert np.allclose(np.abs(lam2 * (p2 - mu2)), 1)


def test_a_contained_rule_is_a_candidate_at_its_point():
    rng = np.random.default_rng(1)
    g = random_sense_genome(rng, 8, 30, np.array([[-1.0, 1.0]] * 4), 0.05, 4.0)
    traj = rng.uniform(0, 1, (50, 30))
    for _ in range(20):
        new = contain.contain_rule(g, rng, traj, rule=5)
        inside = np.all(np.abs(new.lam[5] * (traj - new.mu[5])) < 1, axis=1)
        assert inside.any()                                     # some frame lies in the box
        assert not np.shares_memory(new.mu, g.mu)


def test_3d_bsr_sense_search_starts_from_the_best_of_100_enriched_controllers():
    task = gpmotion.get_task("bob_walk", seconds=0.2)
    fam = make_family("bsr-sense", task)
    s = fam.make_search(0, n_working=10, n_generations=2)
    assert isinstance(s, contain.EnrichedSerialSearch)
    ev = InProcessEvaluator(task, fam)
    sizes = []
    while not s.done:
        cand = s.ask()
        sizes.append(len(cand))
        s.tell(ev.evaluate(cand))
        if len(sizes) == 2:                  # checkpoint mid-enrichment and resume
            s2 = fam.make_search(5, n_working=10, n_generations=2)
            s2.load_state_dict(s.state_dict())
            assert s2.round == 1 and len(s2.pool[0]) == 100
            assert [g.to_dict() for g in s2.ask()] == [g.to_dict() for g in s.ask()]
    assert sizes == [100, 100, 100, 100, 10, 10]
    assert s.evaluations == 420 and len(s.working) == 10


# ---------------------------------------------------------------- secondary terms
def test_heading_sideways_and_rotation():
    yaw = np.linspace(0, 3 * np.pi, 50)                       # 1.5 turns: unwrapped
    quat = np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], -1)
    assert np.allclose(s3.heading(quat), yaw)
    assert s3.net_rotation(s3.heading(quat)) == pytest.approx(3 * np.pi)
    xy = np.stack([np.linspace(0, 1, 5), np.linspace(0, 1, 5)], -1)[None]
    d = s3.in_start_frame(xy, np.array([np.pi / 4]))
    assert d[0, -1, 0] == pytest.approx(np.sqrt(2)) and d[0, -1, 1] == pytest.approx(0, abs=1e-12)


def test_fallen_and_steps():
    up = np.array([1.0, 1.0, 0.9, 0.3, 1.0])
    com = np.ones(5)
    fell = s3.fallen(up, com, np.zeros((5, 0)))
    assert fell.tolist() == [False, False, False, True, True]           # stays fallen
    assert s3.fall_fraction(fell) == pytest.approx(0.4)
    # Rex's stricter thresholds: a trunk pitched 37° (up_z 0.8) or a com 30 % low has fallen
    assert s3.fallen(np.array([1.0, 0.8]), np.ones(2), np.zeros((2, 0)), np.radians(30), 0.75)[-1]
    assert s3.fallen(np.ones(2), np.array([1.0, 0.7]), np.zeros((2, 0)), np.radians(30), 0.75)[-1]
    assert not s3.fallen(np.array([1.0, 0.8]), np.array([1.0, 0.7]), np.zeros((2, 0)))[-1]
    assert gpmotion.get_task("rex_walk").max_tilt == pytest.approx(np.radians(30))
    # two feet alternate touchdowns, each landing 0.2 m ahead of the other
    force = np.array([[1, 1], [0, 1], [1, 1], [1, 0], [1, 1], [0, 1], [1, 1]], float)
    fwd = np.array([[0, 0], [0, 0], [0.2, 0], [0.2, 0], [0.2, 0.4], [0.2, 0.4], [0.6, 0.4]])
    ok = np.zeros(7, bool)
    assert s3.count_steps(force, fwd, ok, np.zeros(7)) == 3
    assert s3.count_steps(force, fwd, np.arange(7) >= 3, np.zeros(7)) == 1   # falls after the first
    assert s3.count_steps(force, fwd, ok, np.r_[0.0, np.full(6, 1.0)]) == 0     # turned away


# ---------------------------------------------------------------- tasks
TASKS = ["cujo_travel", "rex_walk", "rex_turn", "bob_walk"]


@pytest.mark.parametrize("task", TASKS)
def test_creature_tasks_pass_the_contract_checks(task):
    gpmotion.check_task(task)


@pytest.mark.parametrize("task", TASKS)
@pytest.mark.parametrize("family", ["bsr-time", "bsr-sense"])
def test_bsr_families_score_creature_tasks_deterministically(task, family):
    t = gpmotion.get_task(task, seconds=0.5)
    fam = make_family(family, t)
    gs = [fam.random(np.random.default_rng(k)) for k in range(3)]
    ev = InProcessEvaluator(t, fam)
    a, b = ev.evaluate(gs), ev.evaluate(gs)
    assert np.all(np.isfinite(a.costs)) and np.array_equal(a.costs, b.costs)
    if family == "bsr-sense":
        frames = t.n_steps // t.record_every + 1       # 0.5 s (+ rex's 1 s hold)
        assert a.extras[0].shape == (frames, fam.senses3d.plan.n_senses)


def test_a_stage_starts_where_the_previous_stage_ended(tmp_path):
    from gpmotion.controller_file import save_controller
    walk = gpmotion.get_task("rex_walk", seconds=0.5)
    fam = make_family("bsr-time", walk, segments="variable", t_per=0.5)
    g = fam.random(np.random.default_rng(2))
    path = tmp_path / "walk.json"
    save_controller(path, walk, g, family=fam)
    ev = InProcessEvaluator(walk, fam)
    end = ev.rollout([g])
    turn = gpmotion.get_task("rex_turn", after=str(path))
    q0, qd0 = turn.initial_state()
    k = round(0.5 / (walk.dt * walk.record_every))       # the walk's motion ends at 0.5 s;
    assert walk.seconds == 1.5 and walk.motion_seconds == 0.5     # its 1 s hold is not handed on
    assert np.allclose(q0, end.q[0, k]) and np.allclose(qd0, end.qd[0, k])
    assert not np.allclose(q0, end.q[0, -1])
    with pytest.raises(ValueError, match="after"):
        gpmotion.get_task("rex_turn", after=str(tmp_path / "missing.json")).initial_state()


@pytest.mark.parametrize("name, param", [("rex_walk", "w_fall"), ("rex_turn", "w_sideways"),
                                         ("cujo_travel", "w_fall"), ("bob_walk", "w_fall")])
def test_creature_weights_are_parameters_and_validate_is_pure(name, param):
    """Weights come from the parameters when the task is built; validate() changes nothing."""
    t = gpmotion.get_task(name, **{param: 7.0})
    terms = t.terms
    assert any(x.weight == 7.0 for x in terms)
    t.params[param] = 1.0
    t.validate()
    assert t.terms is terms


def test_creature_reports_read_their_facts_in_order():
    m = {"distance": np.array([1.234]), "sideways": np.array([0.05]), "turn": np.array([np.pi / 2]),
         "rotation": np.array([np.pi / 4]), "steps": np.array([3.0]), "fall": np.array([0.25]),
         "facing": np.array([np.pi / 6])}
    fallen = "fallen 25% of the time"
    assert gpmotion.get_task("rex_walk").describe(None, m) == [
        f"forward 1.23 m, sideways 0.05 m, heading change 90°, 3 forward steps, {fallen}"]
    assert gpmotion.get_task("rex_turn-v2").describe(None, m) == [
        f"heading change 90°, forward 1.23 m, {fallen}"]
    assert gpmotion.get_task("rex_turn").describe(None, {**m, "spin": np.array([np.radians(12)])}) == [
        f"heading change 90°, spinning 12°/s at the handover, forward 1.23 m, {fallen}"]
    assert gpmotion.get_task("bob_walk-v1").describe(None, m) == [
        f"3 forward steps, forward 1.23 m, sideways 0.05 m, rotation 45°, {fallen}"]
    assert gpmotion.get_task("bob_walk-v2").describe(None, m) == [
        f"3 forward steps, forward 1.23 m, sideways 0.05 m, facing 30° away on average, {fallen}"]
    assert gpmotion.get_task("bob_walk").describe(None, {**m, "touchdowns": np.array([4.0])}) == [
        f"3 forward steps, 4 touchdowns ahead, forward 1.23 m, sideways 0.05 m, "
        f"facing 30° away on average, {fallen}"]


def _settled_turn(**params):
    """A recorded settled turn (seed 0, from its walk), replayed under rex_turn-v3."""
    from gpmotion.replay import load_controller, replay_genome
    d = Path(__file__).parent / "data" / "rex_turn_v3"
    _, fam, act, genome, rec = load_controller(d / "turn.json")
    task = gpmotion.get_task("rex_turn-v3", after=str(d / "walk.json"), **params)
    _, costs, m, ok = replay_genome(task, make_family(fam.name, task, **fam.options), act, genome)
    return rec, costs, m, ok


def test_rex_turn_v3_scores_the_settled_turn_it_was_searched_under():
    """rex_turn-v3 is the plugin rex_turn_settled shipped: the turn its
    search found (90°, 4°/s at the handover) scores its recorded cost
    (tests/replay_checks.py)."""
    rec, costs, m, ok = _settled_turn()
    same_numbers(float(costs[0]), rec["cost"])
    assert ok[0]
    assert round(np.degrees(m["turn"][0])) == 90 and m["overshoot"][0] == 0.0
    assert round(np.degrees(m["spin"][0])) == 4


def test_rex_turn_v3_pays_up_to_the_target_and_charges_what_is_past_it():
    _, costs, m, _ = _settled_turn(target_degrees=45.0, w_spin=0.0)
    assert m["turn_credit"][0] == pytest.approx(np.radians(45))
    assert m["overshoot"][0] == pytest.approx(m["turn"][0] - np.radians(45))
    with pytest.raises(ValueError, match="w_spin"):
        gpmotion.get_task("rex_turn", w_spin=-1.0)


def test_a_walk_that_topples_after_its_last_frame_fails_rex_walk_v2():
    """rex_walk-v1 took a lunge for a walk: this controller (seed 0, 10,000
    evaluations) covers 1.07 m in 3 s upright and topples 0.1 s later.  v2
    runs it 1 s longer (``hold``): the distance is still taken at 3 s (the
    same number), the fall is not forgiven, and it no longer solves."""
    from gpmotion.replay import load_controller, replay_genome
    path = Path(__file__).parent / "data" / "rex_walk_v1_lunge.json"
    v1, fam1, act, genome, _ = load_controller(path)
    assert v1.id == "rex_walk-v1" and v1.seconds == 3.0
    _, _, m1, ok1 = replay_genome(v1, fam1, act, genome)
    v2 = gpmotion.get_task("rex_walk")
    assert v2.id == "rex_walk-v2" and v2.seconds == 4.0 and v2.n_steps == 4000
    traj, _, m2, ok2 = replay_genome(v2, make_family(fam1.name, v2, **fam1.options), act, genome)
    assert ok1[0] and m1["distance"][0] >= 1.0 and m1["fall"][0] == 0
    assert m2["distance"][0] == pytest.approx(m1["distance"][0], abs=1e-9)
    assert m2["fall"][0] > 0.1 and not ok2[0]
    assert traj.q.shape[1] == 4000 // v2.record_every + 1
    with pytest.raises(ValueError, match="hold must be"):
        gpmotion.get_task("rex_walk", hold=-1.0)


def test_facing_away_is_the_mean_heading_error_and_sees_a_waddle():
    from gpmotion.bsr import secondary3d as s3
    t = np.linspace(0.0, 4.0, 4001)
    waddle = 0.9 * np.sin(2 * np.pi * t)                 # ±52°, net rotation 0
    assert s3.net_rotation(waddle) == pytest.approx(0.0, abs=1e-12)
    assert s3.facing_away(waddle) == pytest.approx(2 * 0.9 / np.pi, rel=1e-3)   # mean |A sin|
    assert s3.facing_away(np.full(5, 0.3)) == 0.0


def test_bob_walk_v2_charges_the_waddle_v1_did_not_see():
    """This bsr-time controller (bob_walk-v1, seed 1, 10,000 evaluations) steps
    L R L R L R L but swings its pelvis ±50°: v1 counts 1 step and charges
    14° of net rotation; v2 charges the mean heading error as well."""
    from gpmotion.replay import load_controller, replay_genome
    v1, fam1, act, genome, _ = load_controller(Path(__file__).parent / "data" / "bob_walk_v1_waddle.json")
    assert v1.id == "bob_walk-v1"
    _, c1, m1, _ = replay_genome(v1, fam1, act, genome)
    v2 = gpmotion.get_task("bob_walk-v2")
    _, c2, m2, _ = replay_genome(v2, make_family(fam1.name, v2, **fam1.options), act, genome)
    assert m1["steps"][0] == 1 and np.degrees(m1["rotation"][0]) < 20
    assert np.degrees(m2["facing"][0]) > 15
    extra = 1.0 * m2["facing"] + (10.0 - 2.0) * m2["fall"]          # v2's added charges
    assert c2[0] == pytest.approx(c1[0] + extra[0], rel=1e-9)


def test_alternating_steps_do_not_count_a_foot_that_bounces_or_limps_ahead():
    """v1/v2 count every touchdown of a foot ≥ 5 cm ahead of the other; a
    foot that bounces in place ahead, or lands ahead again after the other
    foot stepped back, counts each time.  ``alternate`` (bob_walk-v3) counts
    a step only when the feet take turns."""
    # L lands 0.2 m ahead, then bounces three times in place; R never moves
    force = np.array([[1, 1], [0, 1], [1, 1], [0, 1], [1, 1], [0, 1], [1, 1], [0, 1], [1, 1]], float)
    fwd = np.array([[0, 0]] * 2 + [[0.2, 0]] * 7, float)
    ok, yaw = np.zeros(9, bool), np.zeros(9)
    assert s3.count_steps(force, fwd, ok, yaw) == 4                   # the old count: 4 "steps"
    assert s3.count_steps(force, fwd, ok, yaw, alternate=True) == 1
    # then R passes L and lands 0.2 m ahead of it: a second step
    force2 = np.vstack([force, [[1, 0], [1, 1]]])
    fwd2 = np.vstack([fwd, [[0.2, 0.2], [0.2, 0.4]]])
    assert s3.count_steps(force2, fwd2, np.zeros(11, bool), np.zeros(11), alternate=True) == 2
    # a limp: L steps ahead, R steps back (behind L: not a step), L lands ahead again
    force = np.array([[1, 1], [0, 1], [1, 1], [1, 0], [1, 1], [0, 1], [1, 1]], float)
    fwd = np.array([[0, 0], [0, 0], [0.3, 0], [0.3, 0], [0.3, 0.1], [0.3, 0.1], [0.25, 0.1]])
    assert s3.count_steps(force, fwd, np.zeros(7, bool), np.zeros(7)) == 2
    assert s3.count_steps(force, fwd, np.zeros(7, bool), np.zeros(7), alternate=True) == 1
    # alternating feet count as before, and batches count per episode
    force = np.array([[1, 1], [0, 1], [1, 1], [1, 0], [1, 1], [0, 1], [1, 1]], float)
    fwd = np.array([[0, 0], [0, 0], [0.2, 0], [0.2, 0], [0.2, 0.4], [0.2, 0.4], [0.6, 0.4]])
    batch = [np.stack([force, force]), np.stack([fwd, fwd]), np.zeros((2, 7), bool),
             np.stack([np.zeros(7), np.r_[0.0, np.full(6, 1.0)]])]
    assert s3.count_steps(*batch, alternate=True).tolist() == [3, 0]


def test_bob_walk_v3_counts_alternating_steps_and_rewards_them():
    """This bsr-time controller (bob_walk-v2, seed 0, 10,000 evaluations)
    scored "3 forward steps" under v2: R lands 9 cm ahead, L 27 cm ahead, R
    lands back behind L, and L lands 16 cm ahead of R but 5 cm behind where
    it last landed.  v3 counts the first two (the feet took turns), keeps
    v2's count as ``touchdowns``, and rewards 0.2 per step on top of v2's
    cost."""
    from gpmotion.replay import load_controller, replay_genome
    v2, fam2, act, genome, _ = load_controller(Path(__file__).parent / "data" / "bob_walk_v2_limp.json")
    assert v2.id == "bob_walk-v2"
    _, c2, m2, _ = replay_genome(v2, fam2, act, genome)
    v3 = gpmotion.get_task("bob_walk")
    assert v3.id == "bob_walk-v3"
    _, c3, m3, ok3 = replay_genome(v3, make_family(fam2.name, v3, **fam2.options), act, genome)
    assert m2["steps"][0] == 3 and m3["touchdowns"][0] == 3 and m3["steps"][0] == 2
    assert c3[0] == pytest.approx(c2[0] - 0.2 * 2, rel=1e-9)
    assert not ok3[0]
    assert gpmotion.get_task("bob_walk", success_steps=2.0).success(None, m3)[0]


def test_a_stage_run_alone_is_the_composite_phase_exactly(tmp_path):
    """``after=`` hands on the whole physical state a composite carries (q,
    q̇ and the contacts' friction anchors): a turn run alone from the walk's
    end follows the composite's turn phase exactly.  (With q and q̇ alone the
    two parted from the first frame, 3e-4 rad after 20 ms.)"""
    from gpmotion.compose import composite
    from gpmotion.controller_file import save_controller
    paths = []
    for name, seed in (("rex_walk", 2), ("rex_turn", 3)):
        task = gpmotion.get_task(name, seconds=0.6, hold=0.2)
        fam = make_family("bsr-time", task, segments="variable", t_per=0.5)
        paths.append(tmp_path / f"{name}.json")
        save_controller(paths[-1], task, fam.random(np.random.default_rng(seed)), family=fam)
    traj, bounds = composite.run(composite.from_controllers(paths))
    k = int(bounds[0, 1])
    from gpmotion.replay import load_controller, replay_genome
    _, fam, act, genome, rec = load_controller(paths[1])
    turn = gpmotion.get_task("rex_turn", seconds=0.6, hold=0.2, after=str(paths[0]))
    assert turn.initial_contact() is not None and np.any(turn.initial_contact() != 0)
    alone, *_ = replay_genome(turn, make_family("bsr-time", turn, **fam.options), act, genome)
    n = traj.q.shape[1] - k
    assert n > 20
    assert np.array_equal(alone.q[0, :n], traj.q[0, k:])
