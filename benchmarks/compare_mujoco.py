"""gpmotion's planar kernel against MuJoCo's C rollout on the same workload.

    python benchmarks/compare_mujoco.py [--quick] [--episodes N] [--seconds S]

Prints one JSON object: steps/s of both engines (one thread and all threads),
the ratio ours / MuJoCo, and a correctness cross-check (a passive double
pendulum, no contact, from the same initial state in both engines).

The MuJoCo model is generated from the compiled gpmotion ``Model`` arrays
(:func:`mjcf_from_figure`), so masses, centres of mass, rotational inertias,
link offsets and joint axes are the same numbers the kernel uses:

* the planar root (gpmotion links slide-x → slide-z → hinge, the first two
  massless) is one MuJoCo body with three joints: slide x, slide z and a
  hinge about −y (counter-clockwise in the x–z plane, as in gpmotion);
* every other link is a body with one hinge (axis −y) at its origin, placed
  and turned by the link's ``xtree`` (angle, rx, rz);
* inertia is explicit (``<inertial>``: mass, com, diaginertia = icom on all
  three axes — only the y axis matters, every angular velocity is along y);
* actuators are MuJoCo ``<position>`` servos with ``kp``, ``kv`` (= our kd),
  ``ctrlrange`` = the joint limits (our targets are clamped to them too) and
  ``forcerange`` = ± our torque limit: force = clamp(kp·(ctrl − q) − kv·q̇),
  exactly our PD law;
* ground contact: a plane, and a small sphere (radius 1 mm) at each of our
  contact points, friction μ = the scene's μ, condim 3.  Contact softness is
  MuJoCo's own soft-constraint model (default solref/solimp) rather than our
  penalty spring; joint limits are MuJoCo's soft limits rather than our
  limit springs.  These change the trajectories a little, not the work per
  step: both engines see the same bodies, joints and contact points;
* integrator: MuJoCo's default ``Euler`` (semi-implicit, like ours), dt 1 ms;
  no visual geoms, so MuJoCo collides only the 4 spheres against the plane.

Controls change every step: the sine targets our kernel computes in-loop
are precomputed as MuJoCo's ``control`` array [episodes, steps, n_act].
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

import gpmotion
from gpmotion.bench import sine_workload
from gpmotion.controllers import schedule
from gpmotion.model import REVOLUTE, SLIDE_X, SLIDE_Z

CONTACT_RADIUS = 0.001


def _f(*xs):
    return " ".join(f"{float(x):.17g}" for x in xs)


def mjcf_from_figure(fig, scene, *, contact_radius=CONTACT_RADIUS, integrator="Euler",
                     dt=1e-3) -> str:
    """An MJCF string for a compiled planar gpmotion figure (see the module doc)."""
    m = fig.model
    nl = len(m.parent)
    children = {i: [] for i in range(-1, nl)}
    for i in range(nl):
        children[int(m.parent[i])].append(i)
    # a massless link whose only child sits at its origin lends its joint to that child's body
    merged_into = {}
    for i in range(nl):
        kids = children[i]
        if (m.mass[i] == 0.0 and len(kids) == 1 and not np.any(m.xtree[kids[0]])):
            merged_into[i] = kids[0]
    axis = {REVOLUTE: "0 -1 0", SLIDE_X: "1 0 0", SLIDE_Z: "0 0 1"}
    names = fig.link_names

    def joint_xml(i):
        kind = "hinge" if m.jtype[i] == REVOLUTE else "slide"
        lim = ""
        if np.isfinite(m.lo[i]) and np.isfinite(m.hi[i]):
            lim = f' limited="true" range="{_f(m.lo[i], m.hi[i])}"'
        return (f'<joint name="{names[i]}" type="{kind}" axis="{axis[int(m.jtype[i])]}"'
                f' damping="{_f(m.damping[i])}"{lim}/>')

    def body_xml(first, depth):
        chain = [first]
        while chain[-1] in merged_into:
            chain.append(merged_into[chain[-1]])
        i = chain[-1]                         # the link that owns the mass
        a0, rx, rz = m.xtree[first]
        pad = "  " * depth
        out = [f'{pad}<body name="link_{names[i]}" pos="{_f(rx, 0.0, rz)}" '
               f'axisangle="0 -1 0 {float(a0):.17g}">']
        out += [pad + "  " + joint_xml(j) for j in chain]
        if m.mass[i] > 0:
            I = max(float(m.icom[i]), 1e-9)
            out.append(f'{pad}  <inertial pos="{_f(m.com[i, 0], 0.0, m.com[i, 1])}" '
                       f'mass="{_f(m.mass[i])}" diaginertia="{_f(I, I, I)}"/>')
        for k in range(len(m.cp_link)):
            if m.cp_link[k] == i:
                out.append(f'{pad}  <geom type="sphere" size="{contact_radius}" '
                           f'pos="{_f(m.cp_pos[k, 0], 0.0, m.cp_pos[k, 1])}" contype="1" '
                           f'conaffinity="0" condim="3" friction="{_f(scene.mu)} 0.005 0.0001"/>')
        for c in children[i]:
            out += body_xml(c, depth + 1)
        out.append(f"{pad}</body>")
        return out

    bodies = []
    for c in children[-1]:
        bodies += body_xml(c, 2)
    acts = []
    for a, i in enumerate(m.act_dof):
        acts.append(f'    <position joint="{names[i]}" kp="{_f(m.kp[a])}" kv="{_f(m.kd[a])}" '
                    f'ctrllimited="true" ctrlrange="{_f(m.lo[i], m.hi[i])}" '
                    f'forcelimited="true" forcerange="{_f(-m.tau_max[a], m.tau_max[a])}"/>')
    ground = ""
    if scene.ground:
        ground = (f'    <geom name="ground" type="plane" size="0 0 1" pos="0 0 {_f(scene.ground_z)}" '
                  f'contype="0" conaffinity="1"/>')
    return "\n".join([
        f'<mujoco model="{fig.name}">',
        '  <compiler angle="radian" inertiafromgeom="false"/>',
        f'  <option timestep="{_f(dt)}" gravity="0 0 {_f(-scene.gravity)}" integrator="{integrator}"/>',
        "  <worldbody>", ground, *bodies, "  </worldbody>",
        "  <actuator>", *acts, "  </actuator>",
        "</mujoco>"])


def _initial_states(mj, model, qpos, qvel):
    data = mj.MjData(model)
    spec = mj.mjtState.mjSTATE_FULLPHYSICS
    out = np.zeros((len(qpos), mj.mj_stateSize(model, spec)))
    for e in range(len(qpos)):
        mj.mj_resetData(model, data)
        data.qpos[:] = qpos[e]
        data.qvel[:] = qvel[e]
        mj.mj_forward(model, data)
        mj.mj_getState(model, data, out[e], spec)
    return out


def _best(fn, repeats):
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def compare_lamp(episodes, seconds, repeats, threads, seed=0):
    import mujoco as mj
    from mujoco import rollout as mjr

    fig = gpmotion.load_figure("lamp")
    scene = gpmotion.make_scene()
    dt = 1e-3
    n_steps = int(round(seconds / dt))
    off, amp, om, ph = sine_workload(fig, episodes, seed)
    # --- ours
    ctrl = schedule.sines(off, amp, om, ph)
    run = lambda th: gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, dt=dt, threads=th)
    tr = run(1)
    ours1 = _best(lambda: run(1), repeats)
    oursn = _best(lambda: run(threads), repeats)
    # --- MuJoCo
    xml = mjcf_from_figure(fig, scene, dt=dt)
    model = mj.MjModel.from_xml_string(xml)
    t = np.arange(n_steps) * dt
    control = off[:, None, :] + amp[:, None, :] * np.sin(om[:, None, :] * t[None, :, None]
                                                         + ph[:, None, :])
    control = np.ascontiguousarray(control)
    init = _initial_states(mj, model, np.tile(fig.q_default, (episodes, 1)),
                           np.zeros((episodes, fig.nq)))
    nstate = init.shape[1]
    state = np.zeros((episodes, n_steps, nstate))
    sens = np.zeros((episodes, n_steps, 0))
    data1 = mj.MjData(model)
    datan = [mj.MjData(model) for _ in range(threads)]
    with mjr.Rollout(nthread=0) as r1, mjr.Rollout(nthread=threads) as rn:
        def mj1():
            r1.rollout(model, data1, init, control, state=state, sensordata=sens)

        def mjn():
            rn.rollout(model, datan, init, control, state=state, sensordata=sens)
        mj1()
        mujoco1 = _best(mj1, repeats)
        mjn()
        mujocon = _best(mjn, repeats)
    # how much contact MuJoCo saw (episode 0, every 10th step) and how far it went
    d = mj.MjData(model)
    ncon = []
    for k in range(0, n_steps, 10):
        mj.mj_setState(model, d, state[0, k], mj.mjtState.mjSTATE_FULLPHYSICS)
        mj.mj_forward(model, d)
        ncon.append(d.ncon)
    ncon = np.array(ncon)
    steps = episodes * n_steps
    touching = tr.contact_force.sum(axis=-1) > 0
    return {
        "workload": {"figure": "lamp", "episodes": episodes, "steps_per_episode": n_steps,
                     "dt": dt, "controls": "per-episode random sines, changing every step",
                     "mujoco_integrator": "Euler", "mujoco_nq": model.nq, "mujoco_nu": model.nu},
        "ours_steps_per_s": steps / ours1,
        "ours_steps_per_s_all_threads": steps / oursn,
        "mujoco_steps_per_s": steps / mujoco1,
        "mujoco_steps_per_s_all_threads": steps / mujocon,
        "ratio_one_thread": mujoco1 / ours1,
        "ratio_all_threads": mujocon / oursn,
        "threads": threads,
        "bar_one_thread": 3.0,
        "meets_bar": bool(mujoco1 / ours1 >= 3.0),
        "ours_contact_frames": float(touching.mean()),
        "mujoco_contact_frames": float((ncon > 0).mean()),
        "mujoco_mean_contacts": float(ncon.mean()),
        "ours_diverged": int(tr.diverged.sum()),
        "mujoco_final_x_mean": float(state[:, -1, 1].mean()),
        "ours_final_x_mean": float(tr.q[:, -1, 0].mean()),
    }


DOUBLE_PENDULUM = {
    "name": "double_pendulum",
    "root": {"type": "fixed", "body": "mount", "position": [0, 2.0]},
    "bodies": [{"name": "mount", "mass": 1.0, "segment": [[0, 0], [0.1, 0]], "radius": 0.01},
               {"name": "l0", "mass": 1.0, "segment": [[0, 0], [1.0, 0]], "radius": 0.01},
               {"name": "l1", "mass": 0.6, "segment": [[0, 0], [0.7, 0]], "radius": 0.01}],
    "joints": [{"name": "j0", "parent": "mount", "child": "l0", "offset": [0, 0], "angle": -1.5708,
                "limits": [-10.0, 10.0], "actuated": False, "initial": 0.0},
               {"name": "j1", "parent": "l0", "child": "l1", "offset": [1.0, 0], "angle": 0.0,
                "limits": [-10.0, 10.0], "actuated": False, "initial": 0.0}],
}


def pendulum_crosscheck(seconds=2.0, q0=(0.6, -0.4), dt=1e-3):
    """Max |Δθ| between the engines for a passive double pendulum (no contact)."""
    import mujoco as mj

    fig = gpmotion.load_figure(DOUBLE_PENDULUM)
    scene = gpmotion.make_scene(ground=False)
    n = int(round(seconds / dt))
    tr = gpmotion.simulate(fig, seconds, scene=scene, q0=np.array(q0), dt=dt, record_every=1)
    ours = tr.q[0]                               # [n+1, 2], row k after k steps
    out = {"seconds": seconds, "q0": list(q0), "dt": dt}
    for integ in ("Euler", "RK4", "implicitfast"):
        model = mj.MjModel.from_xml_string(mjcf_from_figure(fig, scene, integrator=integ, dt=dt))
        d = mj.MjData(model)
        d.qpos[:] = q0
        theirs = [d.qpos.copy()]
        for _ in range(n):
            mj.mj_step(model, d)
            theirs.append(d.qpos.copy())
        theirs = np.array(theirs)
        out[f"max_angle_diff_{integ}"] = float(np.abs(theirs - ours).max())
    # the same comparison for ourselves at half the step: how big an O(dt) gap is
    half = gpmotion.simulate(fig, seconds, scene=scene, q0=np.array(q0), dt=dt / 2, record_every=2)
    out["ours_dt_vs_dt_half"] = float(np.abs(half.q[0] - ours).max())
    out["swing_amplitude"] = float(np.abs(ours).max())
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--episodes", type=int, default=None)
    p.add_argument("--seconds", type=float, default=None)
    p.add_argument("--repeats", type=int, default=None)
    p.add_argument("--threads", type=int, default=None)
    a = p.parse_args(argv)
    import mujoco
    import numba
    episodes = a.episodes or (8 if a.quick else 64)
    seconds = a.seconds or (0.5 if a.quick else 2.0)
    repeats = a.repeats or (2 if a.quick else 3)
    threads = a.threads or numba.config.NUMBA_NUM_THREADS
    result = compare_lamp(episodes, seconds, repeats, threads)
    result["pendulum_crosscheck"] = pendulum_crosscheck()
    result["versions"] = {"mujoco": mujoco.__version__, "numba": numba.__version__,
                          "numpy": np.__version__, "cpu_count": os.cpu_count()}
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
