"""Each njit kernel of gpmotion.sim.planar against its plain-numpy twin.

Random states on every shipped figure and on random trees (planar root,
fixed root with contacts on the root body, and a tilted root whose slide
joints are turned), then one short rollout with the JIT disabled, so the
kernels' Python source runs too and agrees with the compiled code.
"""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import gpmotion
from gpmotion.sim import planar
from tests.reference import planar_ref as ref

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def random_tree_spec(seed, n_bodies=6, root="planar"):
    """A random planar tree of rods, each joint on a random earlier body."""
    rng = np.random.default_rng(seed)
    bodies, joints, contacts = [], [], []
    lengths = rng.uniform(0.1, 0.6, n_bodies)
    for b in range(n_bodies):
        L = float(lengths[b])
        bodies.append({"name": f"b{b}", "mass": float(rng.uniform(0.2, 2.0)),
                       "segment": [[0.0, 0.0], [L, 0.0]], "radius": 0.02,
                       "com": [float(rng.uniform(0, L)), float(rng.uniform(-0.05, 0.05))]})
        contacts.append({"name": f"c{b}", "body": f"b{b}",
                         "position": [L, float(rng.uniform(-0.03, 0.03))]})
        if b:
            parent = int(rng.integers(0, b))
            joints.append({"name": f"j{b}", "parent": f"b{parent}", "child": f"b{b}",
                           "offset": [float(rng.uniform(0, lengths[parent])), float(rng.uniform(-0.05, 0.05))],
                           "angle": float(rng.uniform(-2, 2)), "limits": [-3.0, 3.0],
                           "kp": 20.0, "kd": 1.0, "torque_limit": 30.0,
                           "damping": float(rng.uniform(0, 0.2))})
    contacts.append({"name": "root_tip", "body": "b0", "position": [0.0, -0.02]})
    return {"name": f"tree{seed}_{root}", "root": {"type": root, "body": "b0", "position": [0.1, 0.5]},
            "bodies": bodies, "joints": joints, "contacts": contacts}


def _figures():
    out = [(n, gpmotion.load_figure(n).model) for n in ("lamp", "starman", "beryl")]
    for seed, root in ((1, "planar"), (2, "planar"), (3, "fixed")):
        fig = gpmotion.load_figure(random_tree_spec(seed, root=root))
        out.append((fig.name, fig.model))
    # slide joints turned by their xtree angle (the kernel's general slide path)
    m = gpmotion.load_figure(random_tree_spec(4)).model
    xtree = m.xtree.copy()
    xtree[0, 0], xtree[1, 0] = 0.4, -0.7
    out.append(("tree4_tilted", m._replace(xtree=xtree)))
    return out


FIGURES = _figures()
IDS = [n for n, _ in FIGURES]


def random_state(M, rng):
    n = len(M.parent)
    q = rng.uniform(-1.5, 1.5, n)
    qd = rng.uniform(-3.0, 3.0, n)
    return q, qd


def run_kinematics(M, q, qd):
    n = len(q)
    pose, X, v, cbias, cs = (np.zeros((n, 3)), np.zeros((n, 4)), np.zeros((n, 3)),
                             np.zeros((n, 3)), np.zeros((n, 2)))
    planar.kinematics(M, q, qd, pose, X, v, cbias, cs)
    return pose, X, v, cbias, cs


def close(a, b, rel=1e-9):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.abs(a - b).max(initial=0.0) <= rel * max(1.0, np.abs(b).max(initial=0.0))


@pytest.mark.parametrize("name, M", FIGURES, ids=IDS)
def test_kinematics_matches_reference(name, M):
    rng = np.random.default_rng(10)
    for _ in range(20):
        q, qd = random_state(M, rng)
        pose, X, v, cbias, cs = run_kinematics(M, q, qd)
        rpose, rv = ref.poses_and_velocities(M, q, qd)
        assert close(pose, rpose, 1e-12) and close(v, rv, 1e-12)
        assert close(cs, np.stack([np.cos(pose[:, 0]), np.sin(pose[:, 0])], axis=1), 1e-12)
        for i, (Xr, S) in enumerate(ref.transforms(M, q)):
            assert close(X[i], [Xr[1, 1], Xr[1, 2], Xr[1, 0], Xr[2, 0]], 1e-12)
            assert close(cbias[i], ref.crm(v[i]) @ (S * qd[i]), 1e-12)


@pytest.mark.parametrize("name, M", FIGURES, ids=IDS)
def test_aba_matches_dense_hybrid_dynamics(name, M):
    rng = np.random.default_rng(11)
    n = len(M.parent)
    mattered = 0                    # trials where the armature changed q̈
    for trial in range(20):
        q, qd = random_state(M, rng)
        pose, X, v, cbias, cs = run_kinematics(M, q, qd)
        tau = rng.normal(0, 5, n)
        fext = rng.normal(0, 3, (n, 3)) if trial % 2 else np.zeros((n, 3))
        presc = (rng.random(n) < 0.4).astype(np.int64) if trial >= 5 else np.zeros(n, np.int64)
        if presc.all():
            presc[rng.integers(n)] = 0
        presc_qdd = rng.normal(0, 10, n)
        # implicit-PD armature on about half the dofs from trial 10 on (big
        # enough to matter: the links' own inertias are ~0.01–0.5)
        arm = np.where(rng.random(n) < 0.5, rng.uniform(0.0, 0.5, n), 0.0) if trial >= 10 \
            else np.zeros(n)
        qdd, tau_k = np.zeros(n), tau.copy()
        planar.aba(M, qd, X, v, cbias, tau_k, fext, presc, presc_qdd, arm, 9.81,
                   np.zeros((n, 6)), np.zeros((n, 3)), np.zeros(n), np.zeros((n, 3)), qdd)
        rqdd, rtau = ref.forward_dynamics(M, q, qd, tau, 9.81, fext, presc.astype(bool), presc_qdd,
                                          arm)
        assert close(qdd, rqdd), (name, trial, np.abs(qdd - rqdd).max())
        assert close(tau_k, rtau), (name, trial)   # prescribed: the torque; armature: τ − a·q̈
        plain = (presc == 0) & (arm == 0)
        assert np.array_equal(tau_k[plain], tau[plain])          # other free dofs: untouched
        no_arm = ref.forward_dynamics(M, q, qd, tau, 9.81, fext, presc.astype(bool), presc_qdd)[0]
        mattered += not close(qdd, no_arm, 1e-6)
    assert mattered >= 5


def _contacts_match_reference(M, scene, rng):
    """One random state, the ground at a random contact point's height (± a few
    cm), random friction state: kernel and twin agree.  Returns the anchors in,
    the twin's normal forces and anchors out."""
    n, nc = len(M.parent), len(M.cp_link)
    q, qd = random_state(M, rng)
    pose, X, v, cbias, cs = run_kinematics(M, q, qd)
    heights = [planar.point_world(pose, cs, l, *p)[1] if l >= 0 else
               planar.fixed_point_world(*M.fixed_pose, *p)[1] for l, p in zip(M.cp_link, M.cp_pos)]
    sc = scene._replace(ground_z=float(rng.choice(heights) + rng.uniform(-0.02, 0.05)))
    anchor = rng.uniform(-1, 1, nc)
    touching = (rng.random(nc) < 0.5).astype(float)
    fext, cforce = np.zeros((n, 3)), np.zeros(nc)
    a_k, t_k = anchor.copy(), touching.copy()
    planar.ground_contacts(M, sc, pose, cs, v, a_k, t_k, fext, cforce)
    rf, rc, ra, rt = ref.ground_contacts(M, sc, q, qd, anchor, touching)
    assert close(fext, rf) and close(cforce, rc) and close(a_k, ra) and np.array_equal(t_k, rt)
    return anchor, rc, ra


@pytest.mark.parametrize("name, M", FIGURES, ids=IDS)
def test_ground_contacts_match_reference(name, M):
    rng = np.random.default_rng(12)
    scene = gpmotion.make_scene(mu=0.6, k_tangent=4000.0)
    n, nc = len(M.parent), len(M.cp_link)
    hits = slips = 0
    for _ in range(40):
        anchor, rc, ra = _contacts_match_reference(M, scene, rng)
        hits += int((rc > 0).sum())
        slips += int((np.abs(ra - anchor) > 0).sum())
    assert hits > 10 and slips > 5          # the cases were exercised
    # no ground: no force, whatever the state
    pose, X, v, cbias, cs = run_kinematics(M, *random_state(M, rng))
    fext, cforce = np.zeros((n, 3)), np.ones(nc)
    planar.ground_contacts(M, scene._replace(ground=0, ground_z=100.0), pose, cs, v,
                           np.zeros(nc), np.zeros(nc), fext, cforce)
    assert not fext.any() and not cforce.any()


@pytest.mark.parametrize("name, M", FIGURES, ids=IDS)
def test_ground_contacts_with_a_contact_limit_match_reference(name, M):
    """Auslander's "only two endpoints can be in contact": the kernel lets the
    N deepest points touch, as the twin does; the cases were exercised."""
    rng = np.random.default_rng(14)
    nc = len(M.cp_link)
    limited = 0
    for n_max in (1, 2):
        scene = gpmotion.make_scene(mu=0.6, k_tangent=4000.0, max_contacts=n_max)
        for _ in range(40):
            q, qd = random_state(M, rng)
            pose, X, v, cbias, cs = run_kinematics(M, q, qd)
            sc = scene._replace(ground_z=float(rng.uniform(-0.1, 0.6)))
            anchor, touching = rng.uniform(-1, 1, nc), (rng.random(nc) < 0.5).astype(float)
            fext, cforce = np.zeros((len(M.parent), 3)), np.zeros(nc)
            a_k, t_k = anchor.copy(), touching.copy()
            planar.ground_contacts(M, sc, pose, cs, v, a_k, t_k, fext, cforce)
            rf, rc, ra, rt = ref.ground_contacts(M, sc, q, qd, anchor, touching)
            assert close(fext, rf) and close(cforce, rc) and close(a_k, ra) and np.array_equal(t_k, rt)
            assert (cforce > 0).sum() <= n_max
            unlimited = ref.ground_contacts(M, sc._replace(max_contacts=0), q, qd, anchor, touching)[1]
            limited += int((unlimited > 0).sum() > n_max)
    assert nc < 2 or limited > 5


@pytest.mark.parametrize("name, M", FIGURES, ids=IDS)
def test_mechanical_energy_matches_reference(name, M):
    rng = np.random.default_rng(13)
    scene = gpmotion.make_scene()
    for _ in range(10):
        q, qd = random_state(M, rng)
        pose, X, v, cbias, cs = run_kinematics(M, q, qd)
        e = planar.mechanical_energy(M, scene, q, qd, pose, cs, v)
        assert close(e, ref.energy(M, scene.gravity, q, qd), 1e-11)


_NOJIT_SCRIPT = textwrap.dedent("""
    import json, sys
    import numpy as np
    import gpmotion
    from gpmotion.controllers import schedule

    def runs():
        fig = gpmotion.load_figure("lamp")
        rng = np.random.default_rng(5)
        off = fig.model.neutral + rng.uniform(-0.2, 0.2, (2, 3))
        ctrl = schedule.sines(off, 0.5, rng.uniform(6, 12, (2, 3)), rng.uniform(0, 6, (2, 3)))
        scene = gpmotion.make_scene(poles=[[0.2, 0.33, 0.05]])   # the lamp's head meets it
        out = {}
        for act in ("pd", "kinematic"):
            tr = gpmotion.rollout(fig, scene, ctrl, n_steps=250, actuation=act, record_every=5,
                                  record_senses=True)
            for k in ("q", "qd", "com", "contact_force", "pole_hit", "energy", "senses"):
                out[f"{act}_{k}"] = getattr(tr, k)
        return out

    if __name__ == "__main__":
        np.savez(sys.argv[1], **runs())
""")


def test_rollout_with_jit_disabled_matches_the_compiled_kernels(tmp_path):
    script = tmp_path / "nojit_rollout.py"
    script.write_text(_NOJIT_SCRIPT)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", GPMOTION_CACHE=str(tmp_path / "cache"),
               PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    res = subprocess.run([sys.executable, str(script), str(tmp_path / "nojit.npz")],
                         env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    plain = np.load(tmp_path / "nojit.npz")
    ns = {}
    exec(compile(_NOJIT_SCRIPT, "nojit_rollout", "exec"), ns)
    jitted = ns["runs"]()
    assert jitted["pd_contact_force"].max() > 0 and jitted["pd_pole_hit"].max() > 0
    for k, a in jitted.items():
        assert close(plain[k], a), (k, np.abs(plain[k] - a).max())
