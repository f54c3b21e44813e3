"""BSR controllers: rule scoring, kernels vs reference, genomes, mutation, Table 3."""
import importlib.util
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from gpmotion.bsr import genome as G
from gpmotion.bsr import mutation as M
from gpmotion.bsr import secondary as S
from gpmotion.bsr import sense_kernel, time_kernel

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("bsr_ref", HERE / "reference" / "bsr_ref.py")
ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ref)

LIMITS3 = np.array([[-1.0, 1.0], [0.0, 2.0], [-0.5, 0.5]])


def two_rule_genome():
    """Rule 0: box [0.3, 1.3]², λ=2, W=2 ln 4.  Rule 1: box [0, 0.4]², λ=5, W=2 ln 10."""
    return G.SenseGenome(mu=[[0.8, 0.8], [0.2, 0.2]], lam=[[2.0, 2.0], [5.0, 5.0]],
                         theta0=[[0.1], [-0.2]], tau=[0.05, 0.2],
                         limits=[[-1.0, 1.0]], tau_range=[0.02, 0.5])


def run_sense(batch, rows, n_act, senses_size=None):
    ci, cf = batch.ci[0], batch.cf[0]
    cstate = np.zeros(batch.cstate_size)
    sense_kernel.init(ci, cf, cstate)
    out = []
    for step, s in enumerate(rows):
        targets, taus = np.full(n_act, 9.0), np.full(n_act, 9.0)
        sense_kernel.control(ci, cf, s, s, 0.01 * step, cstate, targets, taus)
        out.append((targets, taus, int(cstate[0])))
    return out


# -- rule scoring -------------------------------------------------------------
def test_scores_hand_computed():
    g = two_rule_genome()
    np.testing.assert_allclose(g.weights(), [2 * math.log(4), 2 * math.log(10)])
    sc = ref.rule_scores(g.mu, g.lam, np.array([0.1, 0.1]))
    # rule 0: λ(S−μ) = 2·(−0.7) → 1 − 1.96; rule 1: 5·(−0.1) → 1 − 0.25
    np.testing.assert_allclose(sc, [2 * math.log(4) * (1 - 1.96), 2 * math.log(10) * 0.75])


def test_kernel_rule_sequence_and_keep_previous():
    g = two_rule_genome()
    batch = G.encode_batch([g], sense_indices=[0, 1], n_act=1)
    rows = [np.array(r) for r in ([0.1, 0.1],   # first call: rule 0 (Fig. 2), no scoring
                                  [0.1, 0.1],   # only rule 1 positive
                                  [0.0, 1.0],   # none positive -> keep rule 1
                                  [0.9, 0.9],   # only rule 0 positive
                                  [0.0, 1.0],   # none positive -> keep rule 0
                                  [0.25, 0.3])]  # both positive: 0.84·2ln4 < 0.75·2ln10
    out = run_sense(batch, rows, 1)
    assert [o[2] for o in out] == [0, 1, 1, 0, 0, 1]
    for targets, taus, active in out:
        assert targets[0] == g.theta0[active, 0] and taus[0] == g.tau[active]


def test_min_lambda_rule_never_wins():
    # W = Σ log(λ/λ_min) = 0 for the biggest box: its score is never positive.
    mu = [[0.5, 0.5], [0.5, 0.5]]
    lam = [[G.LAMBDA_MIN, G.LAMBDA_MIN], [1.0, 1.0]]
    g = G.SenseGenome(mu, lam, [[0.0], [0.5]], [0.1, 0.1], [[-1, 1]], [0.02, 0.5])
    assert G.SenseGenome.weights(g)[0] == 0.0
    out = run_sense(G.encode_batch([g], [1, 0], 1), [np.array([0.5, 0.5])] * 3, 1)
    assert [o[2] for o in out] == [0, 1, 1]
    # outside rule 1's box, inside rule 0's: rule 0 scores exactly 0 (not
    # positive), rule 1 negative -> rule 1 stays (raw value 1.9 to leave box 1)
    rows = [np.array([0.5, 0.5])] * 2 + [np.array([0.5, 1.9])]
    out = run_sense(G.encode_batch([g], [1, 0], 1), rows, 1)
    assert [o[2] for o in out] == [0, 1, 1]


def test_kernel_matches_reference_random():
    rng = np.random.default_rng(7)
    for trial in range(20):
        V, n_act, R = int(rng.integers(1, 8)), int(rng.integers(1, 5)), int(rng.integers(1, 8))
        limits = np.sort(rng.uniform(-2, 2, (n_act, 2)), axis=1)
        g = G.random_sense_genome(rng, R, V, limits, 0.01, 4.0)
        idx = rng.permutation(V + 3)[:V]
        wide = rng.uniform(0, 1, (60, V + 3))
        batch = G.encode_batch([g], idx, n_act)
        got = run_sense(batch, wide, n_act)
        want = ref.sense_controller_run(g.mu, g.lam, g.theta0, g.tau, wide[:, idx])
        for (t1, u1, a1), (t2, u2, a2) in zip(got, want):
            assert a1 == a2
            np.testing.assert_array_equal(t1, t2)
            np.testing.assert_array_equal(u1, u2)


def test_time_segments():
    for t, r in [(0.0, 0), (0.25, 1), (0.74, 2), (0.99, 3), (1.0, 0), (2.3, 1), (7.999, 3)]:
        assert time_kernel.segment(t, 1.0, 4) == r == ref.time_segment(t, 1.0, 4)
    rng = np.random.default_rng(3)
    g = G.random_time_genome(rng, 5, LIMITS3, 0.01, 2.0, t_per=0.7)
    batch = G.encode_batch([g], None, 3)
    cstate = np.zeros(batch.cstate_size)
    time_kernel.init(batch.ci[0], batch.cf[0], cstate)
    for t in rng.uniform(0, 3, 200):
        targets, taus = np.zeros(3), np.zeros(3)
        time_kernel.control(batch.ci[0], batch.cf[0], targets, targets, t, cstate, targets, taus)
        r = ref.time_segment(t, 0.7, 5)
        np.testing.assert_array_equal(targets, g.theta0[r])
        assert np.all(taus == g.tau[r]) and cstate[0] == r


def test_kernels_without_jit_subprocess():
    code = f"""
import sys, importlib.util, numpy as np
spec = importlib.util.spec_from_file_location('bsr_ref', {str(HERE / 'reference' / 'bsr_ref.py')!r})
ref = importlib.util.module_from_spec(spec); spec.loader.exec_module(ref)
import numba
from gpmotion.bsr import genome as G, sense_kernel as K, time_kernel as TK
assert not hasattr(K.control, 'py_func'), 'jit still on'
rng = np.random.default_rng(1)
g = G.random_sense_genome(rng, 6, 4, [[-1, 1], [0, 1]], 0.01, 2.0)
b = G.encode_batch([g], [0, 1, 2, 3], 2)
cs = np.zeros(b.cstate_size); K.init(b.ci[0], b.cf[0], cs)
rows = rng.uniform(0, 1, (50, 4))
want = ref.sense_controller_run(g.mu, g.lam, g.theta0, g.tau, rows)
for s, (tw, uw, aw) in zip(rows, want):
    t, u = np.zeros(2), np.zeros(2)
    K.control(b.ci[0], b.cf[0], s, s, 0.0, cs, t, u)
    assert int(cs[0]) == aw and np.array_equal(t, tw) and np.array_equal(u, uw)
tg = G.random_time_genome(rng, 3, [[-1, 1]], 0.01, 2.0, 1.5)
tb = G.encode_batch([tg], None, 1)
cs = np.zeros(1); TK.init(tb.ci[0], tb.cf[0], cs)
t, u = np.zeros(1), np.zeros(1)
TK.control(tb.ci[0], tb.cf[0], t, t, 1.2, cs, t, u)
assert t[0] == tg.theta0[ref.time_segment(1.2, 1.5, 3), 0]
print('ok')
"""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, cwd=HERE.parent, timeout=120)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr


# -- parameter counts ----------------------------------------------------------
@pytest.mark.parametrize("N", [2, 3, 5, 8])
def test_parameter_counts(N):
    rng = np.random.default_rng(N)
    R = 10
    limits = np.tile([-1.0, 1.0], (N - 1, 1))
    g = G.random_sense_genome(rng, R, 2 * N + 2, limits, 0.01, 2.0)   # Table 1: V = 2N+2
    assert g.n_parameters == (5 * N + 4) * R
    b = G.encode_batch([g], np.arange(2 * N + 2), N - 1)
    assert b.cf.shape[1] == (5 * N + 4 + 1) * R          # + the precomputed W per rule
    n_joints = N - 1
    tg = G.random_time_genome(rng, 4, limits, 0.01, 2.0, 0.5)
    assert tg.n_parameters == (n_joints + 1) * 4


def test_encode_batch_pads_and_checks():
    rng = np.random.default_rng(0)
    gs = [G.random_sense_genome(rng, R, 3, LIMITS3, 0.01, 2.0) for R in (2, 5)]
    b = G.encode_batch(gs, [4, 0, 2], 3)
    assert b.ci.shape == (2, 9) and b.ci.dtype == np.int64 and b.cf.dtype == np.float64
    assert b.cf.shape[1] == 5 * (2 + 6 + 3) and np.all(b.cf[0, 2 * 11:] == 0)
    assert Path(b.module).is_absolute() and b.module.endswith("sense_kernel.py")
    with pytest.raises(ValueError, match="sense_indices"):
        G.encode_batch(gs, [0, 1], 3)
    with pytest.raises(ValueError, match="n_act"):
        G.encode_batch(gs, [0, 1, 2], 4)
    with pytest.raises(ValueError, match="mixed"):
        G.encode_batch([gs[0], G.random_time_genome(rng, 2, LIMITS3, .01, 2., 1.)], [0, 1, 2], 3)


# -- initial distributions ---------------------------------------------------------
def test_initial_distributions_table2():
    rng = np.random.default_rng(11)
    dt, T = 0.005, 4.0
    parts = [G.random_sense_genome(rng, G.MAX_RULES, 3, LIMITS3, dt, T) for _ in range(4)]
    g = SimpleNamespace(**{k: np.concatenate([getattr(p, k) for p in parts])
                           for k in ("mu", "lam", "tau", "theta0")})     # 4,000 rules' draws
    side = 2.0 / g.lam
    assert g.mu.min() >= -0.5 and g.mu.max() <= 1.5 and abs(g.mu.mean() - 0.5) < 0.02
    assert side.min() >= 0.4 - 1e-12 and side.max() <= 4.0 + 1e-12
    # log-uniform: median at the geometric mean sqrt(0.4·4) (uniform would give 2.2)
    assert abs(np.median(side) - math.sqrt(1.6)) < 0.06
    assert abs(np.log(side).std() - math.log(10) / math.sqrt(12)) < 0.02
    assert g.tau.min() >= 2 * dt and g.tau.max() <= T / 4
    assert abs(np.median(g.tau) - math.sqrt(2 * dt * T / 4)) < 0.02
    assert np.all(g.theta0 >= LIMITS3[:, 0]) and np.all(g.theta0 <= LIMITS3[:, 1])
    np.testing.assert_allclose(g.theta0.mean(axis=0), LIMITS3.mean(axis=1), atol=0.05)
    with pytest.raises(ValueError, match="tau range"):
        G.random_sense_genome(rng, 2, 3, LIMITS3, dt=1.0, T=1.0)


# -- genome serialization ------------------------------------------------------
def test_genome_round_trip_json():
    rng = np.random.default_rng(5)
    for g in (G.random_sense_genome(rng, 4, 6, LIMITS3, 0.01, 2.0),
              G.random_time_genome(rng, 4, LIMITS3, 0.01, 2.0, 0.8)):
        d = json.loads(json.dumps(g.to_dict()))
        h = G.genome_from_dict(d)
        assert type(h) is type(g) and h.to_dict() == g.to_dict()
        for name in ("theta0", "tau", "limits", "tau_range"):
            np.testing.assert_array_equal(getattr(h, name), getattr(g, name))


def _bad(d, **changes):
    d = dict(d)
    for k, v in changes.items():
        if v is None:
            d.pop(k)
        else:
            d[k] = v
    return d


@pytest.mark.parametrize("change, message", [
    ({"format": "bsr-sense-v0"}, "unknown genome format"),
    ({"mu": None}, "missing field"),
    ({"mu": [[0.5, 0.5]]}, "shape"),
    ({"lam": [[2.0, float("nan")], [5.0, 5.0]]}, "non-finite"),
    ({"lam": [[2.0, 9.0], [5.0, 5.0]]}, "lam: values outside"),
    ({"mu": [[0.8, 7.0], [0.2, 0.2]]}, "mu: values outside"),
    ({"theta0": [[1.5], [0.0]]}, "outside joint limits"),
    ({"tau": [0.05, 0.9]}, "tau: values outside"),
    ({"tau": ["fast", 0.1]}, "not an array of numbers"),
    ({"limits": [[1.0, -1.0]]}, "lower joint limit"),
])
def test_genome_rejects_bad_data(change, message):
    d = _bad(two_rule_genome().to_dict(), **change)
    with pytest.raises(ValueError, match=message):
        G.genome_from_dict(d)


def test_time_genome_rejects_bad_period_and_non_dict():
    d = G.random_time_genome(np.random.default_rng(0), 2, LIMITS3, 0.01, 2.0, 1.0).to_dict()
    with pytest.raises(ValueError, match="t_per"):
        G.genome_from_dict(_bad(d, t_per=0.0))
    with pytest.raises(ValueError, match="unknown genome format"):
        G.genome_from_dict([1, 2])
    with pytest.raises(ValueError, match="JSON object"):
        G.TimeGenome.from_dict("x")


# -- mutation ------------------------------------------------------------------
def test_relevance_heuristic_puts_corner_on_trajectory():
    rng = np.random.default_rng(2)
    V = 5
    g = G.random_sense_genome(rng, 6, V, LIMITS3, 0.01, 2.0)
    for _ in range(50):
        traj = rng.uniform(0, 1, (int(rng.integers(1, 40)), V))
        h = M.reinit_rule(g, rng, rule=3, trajectory=traj)
        lo, hi = h.mu[3] - 1 / h.lam[3], h.mu[3] + 1 / h.lam[3]
        on_corner = (np.isclose(traj, lo) | np.isclose(traj, hi)).all(axis=1)
        assert on_corner.any()
        # the box is really "touching": nudging the corner inward makes it score > 0
        p = traj[np.flatnonzero(on_corner)[0]]
        inside = p + 1e-6 * np.sign(h.mu[3] - p)
        assert ref.rule_scores(h.mu[3:4], h.lam[3:4], inside)[0] > 0
        assert np.all((2 / h.lam[3] >= 0.4 - 1e-12) & (2 / h.lam[3] <= 4 + 1e-12))
        for name in ("mu", "lam", "theta0", "tau"):       # other rules untouched
            keep = np.arange(6) != 3
            np.testing.assert_array_equal(getattr(h, name)[keep], getattr(g, name)[keep])
    # a random Table 2 box with no trajectory: corner generally off any point
    h = M.reinit_rule(g, rng, rule=0, trajectory=None)
    G.SenseGenome.from_dict(h.to_dict())
    with pytest.raises(ValueError, match="senses per frame"):
        M.reinit_rule(g, rng, rule=0, trajectory=np.zeros((3, V + 1)))


def test_relevance_skips_nonfinite_frames():
    rng = np.random.default_rng(4)
    traj = np.full((10, 2), np.nan)
    traj[6] = [0.3, 0.7]
    mu, lam, point, frame = M.relevant_stimulus(rng, traj)
    assert frame == 6 and np.array_equal(point, traj[6])
    assert M.relevant_stimulus(rng, np.full((3, 2), np.nan)) is None


@pytest.mark.parametrize("kind", ["sense", "time"])
def test_creep_changes_one_rule_and_stays_valid(kind):
    rng = np.random.default_rng(9)
    if kind == "sense":
        g = G.random_sense_genome(rng, 5, 4, LIMITS3, 0.01, 2.0)
    else:
        g = G.random_time_genome(rng, 5, LIMITS3, 0.01, 2.0, 1.0)
    h = M.creep_rule(g, rng, rule=2)
    changed = np.any(h.theta0 != g.theta0, axis=1) | (h.tau != g.tau)
    assert changed.tolist() == [False, False, True, False, False]
    assert np.max(np.abs(h.theta0 - g.theta0)) < 0.5      # "slightly"
    for _ in range(300):                                  # large creeps stay in range
        h = M.creep_rule(h, rng, scale=20.0)
        h = M.mutate(h, rng, rng.uniform(0, 1, (5, 4)) if kind == "sense" else None)
    G.genome_from_dict(json.loads(json.dumps(h.to_dict())))   # validates ranges


def test_time_reinit_redraws_one_segment():
    rng = np.random.default_rng(1)
    g = G.random_time_genome(rng, 4, LIMITS3, 0.01, 2.0, 1.0)
    h = M.reinit_rule(g, rng, rule=1)
    assert np.all(h.theta0[[0, 2, 3]] == g.theta0[[0, 2, 3]])
    assert np.all(h.theta0[1] != g.theta0[1]) and h.t_per == g.t_per


# -- Table 3 secondary terms -----------------------------------------------------------
def test_secondary_terms():
    assert S.max_height([0.5, 1.2, 0.9]) == 1.2
    np.testing.assert_array_equal(S.max_height([[0, 1], [3, 2]]), [1, 3])
    force = np.array([[1, 0], [1, 1], [1, 1], [0, 1], [1, 1]], float)
    x = np.array([[0, 0], [1, 5], [3, 6], [9, 8], [10, 8.5]], float)
    # point 0: frames 0-1 (+1), 1-2 (+2), lifts off at 3; point 1: 1-2 (+1), 2-3 (+2), 3-4 (+0.5)
    assert S.contact_distance(force, x) == pytest.approx(6.5)
    batch = S.contact_distance(np.stack([force, force]), np.stack([x, 2 * x]))
    np.testing.assert_allclose(batch, [6.5, 13.0])
    with pytest.raises(ValueError):
        S.contact_distance(force, x[:, :1])
    theta = np.linspace(0, -2.6 * 2 * np.pi, 400)
    wrapped = np.angle(np.exp(1j * theta))
    assert S.rotations(wrapped) == 2.0
    assert S.rotations(wrapped, whole=False) == pytest.approx(2.6)
    assert S.rotations(np.stack([wrapped, np.zeros(400)])).tolist() == [2.0, 0.0]


def test_grounded_distance_is_com_travel_while_some_point_touches():
    """Frames 0-2 grounded (com 0 → 0.3), 3-4 airborne (→ 0.9), 5-6 grounded
    (→ 1.2): the steps with a point down at both ends are 0→1, 1→2 and 5→6
    (the landing step 4→5 and the flight earn nothing)."""
    x = np.array([0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.2])
    force = np.zeros((7, 2))
    force[[0, 1, 2], 0] = 10.0
    force[[5, 6], 1] = 10.0
    assert S.grounded_distance(force, x) == pytest.approx(0.1 + 0.2 + 0.3)
    assert S.grounded_distance(force, x, direction=-1.0) == pytest.approx(-0.6)
    assert S.grounded_distance(np.full((7, 2), 10.0), x) == pytest.approx(1.2)   # a shuffle: all of it
    assert S.grounded_distance(np.stack([force, 0 * force]), np.stack([x, x])).tolist() == pytest.approx([0.6, 0.0])
    with pytest.raises(ValueError):
        S.grounded_distance(force, x[:-1])


def test_contact_distance_is_distance_traversed_not_jitter():
    # a foot sliding to and fro in place for 10 frames traverses nothing
    # (the old per-frame |Δx| sum paid 0.9 m for it)
    jitter = (np.arange(10) % 2 * 0.1)[:, None]
    touching = np.ones_like(jitter)
    assert S.contact_distance(touching, jitter) == pytest.approx(0.1)        # net of the stretch
    assert S.contact_distance(touching, jitter - jitter[-1]) == pytest.approx(0.1)
    assert S.contact_distance(np.r_[touching, [[1.0]]], np.r_[jitter, [[0.0]]], direction=1.0) == 0.0
    # two stretches: 2 m back, lift off, 3 m forward
    x = np.array([0, -1, -2, 5, 6, 8], float)[:, None]
    f = np.array([1, 1, 1, 0, 1, 1], float)[:, None]
    assert S.contact_distance(f, x) == pytest.approx(4.0)                  # |−2| + |+2|
    assert S.contact_distance(f, x, direction=1.0) == pytest.approx(0.0)   # −2 + 2
    assert S.contact_distance(f, x, direction=-1.0) == pytest.approx(0.0)
    np.testing.assert_allclose(S.contact_distance(np.stack([f, f]), np.stack([x, 3 * x]),
                                                  direction=1.0), [0.0, 0.0])
    np.testing.assert_allclose(S.contact_distance(np.stack([f, f]), np.stack([x, 3 * x])), [4.0, 12.0])


def test_travel_contact_distance_pays_forward_travel_only():
    from gpmotion.tasks._travel import travel_measures
    from gpmotion.task import get_task
    task = get_task("starman_travel")

    class Traj:                           # two recorded frames of one episode
        figure = task.figure
        com = np.zeros((1, 3, 4))
        contact_force = np.ones((1, 3, len(task.figure.contact_names)))
        _q = np.repeat(task.figure.q_default[None, None], 3, axis=1)

        def poses(self):
            from gpmotion.sim import geometry
            return geometry.link_poses(task.figure.model, self._q)

        def base(self):
            return self.poses()[..., task.figure.model.base_link, :]

    t = Traj()
    t._q[0, :, 0] = [0.0, -0.3, 0.0]      # slid back and forth: nothing traversed
    assert travel_measures(t)["contact_distance"][0] == pytest.approx(0.0)
    t._q[0, :, 0] = [0.0, -0.3, -0.5]     # every point slid 0.5 m left: a cost
    n = len(task.figure.contact_names)
    assert travel_measures(t)["contact_distance"][0] == pytest.approx(-0.5 * n)


def test_travel_validate_is_pure():
    from gpmotion.task import get_task
    task = get_task("beryl_travel", w_rotations=2.0)
    before = dict(vars(task))
    task.validate()
    assert vars(task) == before and all(vars(task)[k] is v for k, v in before.items())
    assert [t.weight for t in task.terms] == [-1.0, -0.0, -0.0, -2.0, -0.0]


def test_table1_indices_and_normalized_trajectory():
    names = ["px", "com_z", "com_vz", "angle_a", "angle_b", "rate_a", "rate_b",
             "force_1", "force_2", "force_3"]
    idx = G.table1_sense_indices(names)
    assert idx.tolist() == [3, 4, 7, 8, 9, 1, 2]        # angles, forces, com_z, com_vz
    with pytest.raises(ValueError, match="com_vz"):
        G.table1_sense_indices(names[:2])
    lo, hi = np.zeros(10), np.full(10, 2.0)
    hi[0] = 0.0                                          # empty range -> 0.5
    raw = np.tile(np.arange(10.0) / 4, (2, 5, 1))        # [E, F, n_senses]
    y = M.normalized_sense_trajectory(raw, lo, hi, [0, 1, 9])
    assert y.shape == (2, 5, 3)
    np.testing.assert_allclose(y[0, 0], [0.5, 0.125, 1.0])


# -- variable segment durations (the paper's R − 1 dividers) ---------------------------
def test_variable_segments_follow_their_durations():
    rng = np.random.default_rng(4)
    g = G.random_time_genome(rng, 4, LIMITS3, 0.01, 2.0, t_per=0.8, segments="variable")
    assert g.durations.shape == (4,) and g.n_parameters == 4 * 3 + 4 + 3
    g.durations = np.array([1.0, 3.0, 0.5, 0.5])             # segments 0.16, 0.48, 0.08, 0.08 s
    edges = np.array([0.0, 0.16, 0.64, 0.72, 0.8])
    batch = G.encode_batch([g], None, 3)
    cstate = np.zeros(batch.cstate_size)
    for t in np.concatenate([rng.uniform(0, 3, 300), edges[1:-1] + 1e-9, edges[1:-1] + 0.8 + 1e-9]):
        targets, taus = np.zeros(3), np.zeros(3)
        time_kernel.control(batch.ci[0], batch.cf[0], targets, targets, t, cstate, targets, taus)
        want = int(np.searchsorted(edges, t % 0.8, side="right")) - 1
        assert cstate[0] == want, t
        np.testing.assert_array_equal(targets, g.theta0[want])
        assert np.all(taus == g.tau[want])


def test_equal_durations_match_equal_segments():
    rng = np.random.default_rng(5)
    g = G.random_time_genome(rng, 5, LIMITS3, 0.01, 2.0, t_per=1.0)
    assert g.durations is None and g.n_parameters == 5 * 3 + 5
    v = g.copy()
    v.durations = np.ones(5)
    be, bv = G.encode_batch([g], None, 3), G.encode_batch([v], None, 3)
    for t in rng.uniform(0, 4, 300):
        c1, c2 = np.zeros(1), np.zeros(1)
        x = np.zeros(3)
        time_kernel.control(be.ci[0], be.cf[0], x, x, t, c1, np.zeros(3), np.zeros(3))
        time_kernel.control(bv.ci[0], bv.cf[0], x, x, t, c2, np.zeros(3), np.zeros(3))
        assert c1[0] == c2[0]


def test_variable_segments_mutate_and_round_trip():
    rng = np.random.default_rng(6)
    g = G.random_time_genome(rng, 4, LIMITS3, 0.01, 2.0, 1.0, segments="variable")
    h = M.creep_rule(g, rng, rule=2)
    assert (h.durations != g.durations).tolist() == [False, False, True, False]
    h = M.reinit_rule(h, rng, rule=0)
    assert h.durations[0] != g.durations[0] and h.durations[1] == g.durations[1]
    for _ in range(300):
        h = M.mutate(M.creep_rule(h, rng, scale=30.0), rng)
    back = G.genome_from_dict(json.loads(json.dumps(h.to_dict())))
    np.testing.assert_array_equal(back.durations, h.durations)
    assert "durations" not in G.random_time_genome(rng, 2, LIMITS3, .01, 2., 1.).to_dict()
    d = g.to_dict()
    d["durations"] = [1.0, 1.0]
    with pytest.raises(ValueError, match="durations"):
        G.genome_from_dict(d)
    d["durations"] = [1.0, 1.0, 0.0, 1.0]
    with pytest.raises(ValueError, match="durations"):
        G.genome_from_dict(d)
    with pytest.raises(ValueError, match="segments"):
        G.random_time_genome(rng, 2, LIMITS3, .01, 2., 1., segments="uneven")


def test_rollouts_import_the_kernels_under_their_package_names():
    # numba's cache beside the file records the module name: a kernel compiled
    # by a rollout under another name broke later direct imports of the kernel
    from gpmotion import cache
    assert cache.import_file(G.SENSE_KERNEL) is sense_kernel
    assert cache.import_file(G.TIME_KERNEL) is time_kernel


def test_the_old_kernel_alias_still_resolves():
    import sys

    from gpmotion import cache
    cache.import_file(G.SENSE_KERNEL)
    assert sys.modules["gpmotion_cache_sense_kernel"] is sense_kernel


def test_starman_senses_are_table1_with_the_hub():
    # Table 1: V = 2N + 2 for N rods; Star-Man's 5 rods have 6 endpoints
    # (five tips and the shared hub), so a sense-based rule has (5N + 4) = 29 parameters
    from gpmotion import load_figure
    fig = load_figure("starman")
    idx = G.table1_sense_indices(fig.sense_names)
    assert len(idx) == 2 * 5 + 2 and "hub" in fig.contact_names
    g = G.random_sense_genome(np.random.default_rng(0), 10, len(idx), fig.actuator_limits(), 0.05, 3.0)
    assert g.n_parameters == (5 * 5 + 4) * 10


def test_starman_legs_can_swing_over_the_top():
    # a cartwheel carries the legs past the horizontal towards the head
    from gpmotion import load_figure
    fig = load_figure("starman")
    names = fig.actuator_names
    lim = fig.actuator_limits()
    offsets = {"leg_l": 2.7416, "leg_r": -2.7416}            # rest angles from the head rod
    for leg, rest in offsets.items():
        lo, hi = lim[names.index(leg)]
        reach = min(abs(rest + lo), abs(rest + hi))          # closest approach to the head
        assert reach < 0.5, (leg, reach)


def test_beryl_can_tuck():
    # a tumble needs the knees to the chest: at full hip flexion the thigh is
    # within 0.8 rad of the torso and the knee above the hip (before: 1.0 rad of
    # flexion, the knee 0.2 m below the hip, and Beryl only hopped)
    import gpmotion
    from gpmotion.sim import geometry
    fig = gpmotion.load_figure("beryl")
    m = fig.model
    q = fig.q_default.copy()
    for j, name in enumerate(fig.actuator_names):
        if name.startswith("hip"):
            q[m.act_dof[j]] = fig.actuator_limits()[j, 1]
    pts = geometry.points_world(m, geometry.link_poses(m, q[None]), m.cp_link, m.cp_pos)[0]
    z = dict(zip(fig.contact_names, pts[:, 1]))
    assert z["knee_l"] > z["hip"] + 0.25 and z["knee_r"] > z["hip"] + 0.25


def test_bsr_variation_uses_the_c_librarys_exp_bit_for_bit():
    """numpy's float64 exp has its own SIMD path on AVX-512 machines that
    rounds some results differently from the C library's: genome.exp goes
    element by element through math.exp, so a seed breeds the same genome on
    every machine (a golden run's tau differed by one ulp)."""
    from gpmotion.bsr.genome import exp, log_uniform
    x = np.random.default_rng(0).normal(0.0, 3.0, (7, 5))
    assert [float(v) for v in exp(x).ravel()] == [math.exp(v) for v in x.ravel().tolist()]
    assert exp(x).shape == x.shape and exp(0.5).shape == ()
    rng_a, rng_b = np.random.default_rng(3), np.random.default_rng(3)
    got = log_uniform(rng_a, 0.02, 0.25, 6)
    u = rng_b.uniform(math.log(0.02), math.log(0.25), 6)
    assert got.tolist() == [min(max(math.exp(v), 0.02), 0.25) for v in u.tolist()]
