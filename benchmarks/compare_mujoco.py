"""gpmotion's kernels against MuJoCo: the lamp (planar, two workloads) and the humanoid (3-D).

    python benchmarks/compare_mujoco.py [--quick] [--json] [--episodes N] [--seconds S]

1. **Sine targets** (``sine``): our kernel vs MuJoCo's C ``rollout`` with the
   controls precomputed — pure simulator throughput; bar: ours ≥ 3× on one
   thread.
2. **GP controllers** (``gp``): the lamp driven by three random ~35-node GP
   trees (:func:`gpmotion.bench.bench_gp_trees`, the ``gpmotion bench
   --controller gp`` trees), contacts active, ``lamp_hop`` episodes (3 s).
   Ours evaluates the trees in-kernel; MuJoCo runs the loop users write
   today: every step, Python reads the senses from ``MjData``, calls the three
   ``deap.gp.compile``d trees, writes ``data.ctrl`` and calls
   ``mujoco.mj_step`` (:func:`mujoco_gp_loop`).  Bar: ours ≥ 10× that loop on
   one thread; goal ≥ 25×.
3. **Humanoid** (``humanoid``): the 3-D humanoid ``herman`` (29 links, fixed
   pelvis, 6 foot contacts) with sine targets on every actuator, ours vs MuJoCo's C
   ``rollout`` — model generated from the compiled 3-D arrays
   (:func:`mjcf_from_figure3d`).  Bar: ours ≥ 0.5× MuJoCo on one thread;
   goal: faster.
4. Correctness cross-checks: a passive double pendulum (planar), and a
   passive 3-D double pendulum whose second hinge axis is tilted out of
   the first's plane (:func:`pendulum3d_crosscheck`), no contact, from the
   same initial state in both engines.

Prints a summary, or one JSON object with every number (``--json``).

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
  our PD law (ours is implicit in the velocity — an armature dt·(kd + dt·kp)
  on unsaturated servos, ``gpmotion/sim/actuation.py`` — where MuJoCo's
  ``Euler`` treats actuator gains explicitly; the same work per step);
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

The MuJoCo + ``gp.compile`` loop builds the same 19-entry sense vector as our
kernel (``gpmotion.sim.senses``) from ``MjData``:

* exact: ``px, pz`` (root slide qpos − the lamp_hop goal), ``vx, vz, pitch,
  pitch_rate`` (root qpos/qvel: the slides are world-aligned, the hinge sits
  at the base origin, so these equal our base senses), ``t`` (``data.time``),
  ``angle_*`` / ``rate_*`` (hinge qpos/qvel);
* approximated: ``com_z`` and ``com_vz`` are ``subtree_com[0]`` and
  ``subtree_linvel[0]`` (after an explicit ``mj_subtreeVel``), which
  ``mj_step`` left at the state *before* its integration — one step (1 ms)
  stale; ``force_<contact>`` is the normal force (``mj_contactForce``) of
  the contact at that point's sphere from MuJoCo's soft-constraint solve of
  the previous step, not our penalty spring's force at the current state.
  Trajectories therefore differ between the engines (they would anyway:
  different contact models); the work per step does not.

The trees are compiled with a *plain* DEAP primitive set holding the same
primitive functions as gpmotion's registry (protected division, guarded
sin/cos) — what a DEAP user writes.  gpmotion's own set wraps every
primitive in the interpreter's clamp, one more Python call per node; that
variant is timed too (``mujoco_gp_compile_clamped_steps_per_s``), and it is
what checks that the trees compute in Python what they compute in-kernel
(``trees_agree_max_abs_diff``, on senses recorded by our rollout).  A
non-finite tree output (possible without the clamp) sets the joint's neutral
angle, as our kernel does.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import numpy as np

import gpmotion
from gpmotion.bench import bench_gp_trees, sine_workload
from gpmotion.controllers import schedule
from gpmotion.model import REVOLUTE, SLIDE_X, SLIDE_Z

CONTACT_RADIUS = 0.001


def _f(*xs):
    return " ".join(f"{float(x):.17g}" for x in xs)


class _MJCF:
    """What the planar and 3-D MJCF writers share: one body per link (a
    massless link whose only child sits at its origin lends its joint to that
    child's body), an ``<inertial>`` per massive link, a small sphere per
    contact point, ``<position>`` servos and the ground plane.  A subclass
    says how its model's links are placed, jointed and weighed."""
    compiler = ""               # extra attributes of <compiler>

    def __init__(self, fig, contact_radius):
        self.fig, self.m, self.names, self.contact_radius = fig, fig.model, fig.link_names, contact_radius

    def xml(self, scene, integrator, dt) -> str:
        m = self.m
        nl = len(m.parent)
        children = {i: [] for i in range(-1, nl)}
        for i in range(nl):
            children[int(m.parent[i])].append(i)
        merged_into = {i: children[i][0] for i in range(nl)
                       if m.mass[i] == 0.0 and len(children[i]) == 1 and self.lends_joint(i, children[i][0])}
        bodies = []
        for c in children[-1]:
            bodies += self._body(c, 2, children, merged_into, scene)
        acts = []
        for a in range(len(m.act_dof)):
            joint, d = self.servo(a)
            acts.append(f'    <position joint="{joint}" kp="{_f(m.kp[a])}" kv="{_f(m.kd[a])}" '
                        f'ctrllimited="true" ctrlrange="{_f(m.lo[d], m.hi[d])}" '
                        f'forcelimited="true" forcerange="{_f(-m.tau_max[a], m.tau_max[a])}"/>')
        ground = ""
        if scene.ground:
            ground = (f'    <geom name="ground" type="plane" size="0 0 1" pos="0 0 {_f(scene.ground_z)}" '
                      f'contype="0" conaffinity="1"/>')
        return "\n".join([
            f'<mujoco model="{self.fig.name}">',
            f'  <compiler angle="radian" inertiafromgeom="false"{self.compiler}/>',
            f'  <option timestep="{_f(dt)}" gravity="0 0 {_f(-scene.gravity)}" integrator="{integrator}"/>',
            "  <worldbody>", ground, *bodies, "  </worldbody>",
            "  <actuator>", *acts, "  </actuator>",
            "</mujoco>"])

    def _body(self, first, depth, children, merged_into, scene) -> list[str]:
        m = self.m
        chain = [first]
        while chain[-1] in merged_into:
            chain.append(merged_into[chain[-1]])
        i = chain[-1]                         # the link that owns the mass
        pad = "  " * depth
        out = [f'{pad}<body name="link_{self.names[i]}" {self.placement(first)}>']
        out += [pad + "  " + self.joint(j) for j in chain]
        if m.mass[i] > 0:
            out.append(f'{pad}  <inertial {self.inertial(i)}/>')
        for k in range(len(m.cp_link)):
            if m.cp_link[k] == i:
                out.append(f'{pad}  <geom name="cp_{self.fig.contact_names[k]}" type="sphere" '
                           f'size="{self.contact_radius}" pos="{self.contact_pos(k)}" contype="1" '
                           f'conaffinity="0" condim="3" friction="{_f(scene.mu)} 0.005 0.0001"/>')
        for c in children[i]:
            out += self._body(c, depth + 1, children, merged_into, scene)
        out.append(f"{pad}</body>")
        return out

    def _limits(self, d) -> str:
        m = self.m
        if np.isfinite(m.lo[d]) and np.isfinite(m.hi[d]):
            return f' limited="true" range="{_f(m.lo[d], m.hi[d])}"'
        return ""


class _PlanarMJCF(_MJCF):
    """Planar links: hinges about −y, slides along x and z, placed by ``xtree``."""
    axis = {REVOLUTE: "0 -1 0", SLIDE_X: "1 0 0", SLIDE_Z: "0 0 1"}

    def lends_joint(self, i, child) -> bool:
        return not np.any(self.m.xtree[child])

    def placement(self, i) -> str:
        a0, rx, rz = self.m.xtree[i]
        return f'pos="{_f(rx, 0.0, rz)}" axisangle="0 -1 0 {float(a0):.17g}"'

    def joint(self, i) -> str:
        m = self.m
        kind = "hinge" if m.jtype[i] == REVOLUTE else "slide"
        return (f'<joint name="{self.names[i]}" type="{kind}" axis="{self.axis[int(m.jtype[i])]}"'
                f' damping="{_f(m.damping[i])}"{self._limits(i)}/>')

    def inertial(self, i) -> str:
        m = self.m
        inertia = max(float(m.icom[i]), 1e-9)
        return (f'pos="{_f(m.com[i, 0], 0.0, m.com[i, 1])}" mass="{_f(m.mass[i])}" '
                f'diaginertia="{_f(inertia, inertia, inertia)}"')

    def contact_pos(self, k) -> str:
        return _f(self.m.cp_pos[k, 0], 0.0, self.m.cp_pos[k, 1])

    def servo(self, a) -> tuple[str, int]:
        i = int(self.m.act_dof[a])
        return self.names[i], i


def mjcf_from_figure(fig, scene, *, contact_radius=CONTACT_RADIUS, integrator="Euler",
                     dt=1e-3) -> str:
    """An MJCF string for a compiled planar gpmotion figure (see the module doc)."""
    return _PlanarMJCF(fig, contact_radius).xml(scene, integrator, dt)


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


def race(fig, scene, xml, sines, n_steps, dt, repeats, threads):
    """Ours vs MuJoCo's C ``rollout`` (model ``xml``) on the same per-episode sine
    targets, changing every step, from the figure's default pose at rest; best of
    ``repeats`` timings on one thread and on ``threads``.  Returns our trajectory,
    the MuJoCo model, its states [episodes, steps, state] and the rates."""
    import mujoco as mj
    from mujoco import rollout as mjr

    off, amp, om, ph = sines
    episodes = len(off)
    # --- ours
    ctrl = schedule.sines(off, amp, om, ph)
    run = lambda th: gpmotion.rollout(fig, scene, ctrl, n_steps=n_steps, dt=dt, threads=th)
    tr = run(1)
    ours1 = _best(lambda: run(1), repeats)
    oursn = _best(lambda: run(threads), repeats)
    # --- MuJoCo: the same targets precomputed as its control array
    model = mj.MjModel.from_xml_string(xml)
    t = np.arange(n_steps) * dt
    control = np.ascontiguousarray(off[:, None, :] + amp[:, None, :] *
                                   np.sin(om[:, None, :] * t[None, :, None] + ph[:, None, :]))
    init = _initial_states(mj, model, np.tile(fig.q_default, (episodes, 1)),
                           np.zeros((episodes, fig.nv)))
    state = np.zeros((episodes, n_steps, init.shape[1]))
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
    steps = episodes * n_steps
    rates = {"ours_steps_per_s": steps / ours1,
             "ours_steps_per_s_all_threads": steps / oursn,
             "mujoco_steps_per_s": steps / mujoco1,
             "mujoco_steps_per_s_all_threads": steps / mujocon,
             "ratio_one_thread": mujoco1 / ours1,
             "ratio_all_threads": mujocon / oursn,
             "threads": threads}
    return tr, model, state, rates


def compare_lamp(episodes, seconds, repeats, threads, seed=0):
    import mujoco as mj

    fig = gpmotion.load_figure("lamp")
    scene = gpmotion.make_scene()
    dt = 1e-3
    n_steps = int(round(seconds / dt))
    tr, model, state, rates = race(fig, scene, mjcf_from_figure(fig, scene, dt=dt),
                                   sine_workload(fig, episodes, seed), n_steps, dt, repeats, threads)
    # how much contact MuJoCo saw (episode 0, every 10th step) and how far it went
    d = mj.MjData(model)
    ncon = []
    for k in range(0, n_steps, 10):
        mj.mj_setState(model, d, state[0, k], mj.mjtState.mjSTATE_FULLPHYSICS)
        mj.mj_forward(model, d)
        ncon.append(d.ncon)
    ncon = np.array(ncon)
    touching = tr.contact_force.sum(axis=-1) > 0
    return {
        "workload": {"figure": "lamp", "episodes": episodes, "steps_per_episode": n_steps,
                     "dt": dt, "controls": "per-episode random sines, changing every step",
                     "mujoco_integrator": "Euler", "mujoco_nq": model.nq, "mujoco_nu": model.nu},
        **rates,
        "bar_one_thread": 3.0,
        "meets_bar": bool(rates["ratio_one_thread"] >= 3.0),
        "ours_contact_frames": float(touching.mean()),
        "mujoco_contact_frames": float((ncon > 0).mean()),
        "mujoco_mean_contacts": float(ncon.mean()),
        "ours_diverged": int(tr.diverged.sum()),
        "mujoco_final_x_mean": float(state[:, -1, 1].mean()),
        "ours_final_x_mean": float(tr.q[:, -1, 0].mean()),
    }


# ------------------------------------------------------------------ GP controllers

def plain_pset(info):
    """A DEAP primitive set as a user writes it: the registry's functions, unwrapped."""
    from deap import gp
    pset = gp.PrimitiveSet("USER", len(info.terminal_names))
    for prim in info.primitives:
        pset.addPrimitive(prim.func, prim.arity, name=prim.name)
    pset.renameArguments(**{f"ARG{i}": n for i, n in enumerate(info.terminal_names)})
    return pset


def mujoco_gp_loop(mj, model, fig, goal, funcs, n_steps, q0, qd0, *, unpack=True):
    """The Python loop users write today: senses → compiled trees → ``data.ctrl`` → ``mj_step``.

    ``funcs`` are compiled trees, one per actuator; each is called with the 19
    senses as positional arguments (``deap.gp.compile``'s lambda) when
    ``unpack``, else with the sense list (``compile_reference``).  Returns
    the final ``MjData`` and the number of steps with some contact.
    """
    data = mj.MjData(model)
    mj.mj_resetData(model, data)
    data.qpos[:] = q0
    data.qvel[:] = qd0
    mj.mj_forward(model, data)
    nc = len(fig.contact_names)
    geom_cp = {model.geom(f"cp_{c}").id: k for k, c in enumerate(fig.contact_names)}
    na = fig.n_act
    neutral = [float(x) for x in fig.model.neutral]
    gx, gz = float(goal[0]), float(goal[1])
    f6 = np.zeros(6)
    ctrl = data.ctrl
    subtree_com, subtree_linvel = data.subtree_com, data.subtree_linvel
    isfinite, contact_force, subtree_vel, step = (math.isfinite, mj.mj_contactForce,
                                                  mj.mj_subtreeVel, mj.mj_step)
    touching = 0
    for _ in range(n_steps):
        qp = data.qpos.tolist()
        qv = data.qvel.tolist()
        force = [0.0] * nc
        ncon = data.ncon
        if ncon:
            touching += 1
            con = data.contact
            for i, (g1, g2) in enumerate(con.geom.tolist()):
                k = geom_cp.get(g2, geom_cp.get(g1))
                if k is not None:
                    contact_force(model, data, i, f6)
                    force[k] += f6[0]
        subtree_vel(model, data)
        senses = [qp[0] - gx, qp[1] - gz, qv[0], qv[1], qp[2], qv[2],
                  float(subtree_com[0, 2]), float(subtree_linvel[0, 2]), data.time,
                  *qp[3:3 + na], *qv[3:3 + na], *force]
        for a in range(na):
            u = funcs[a](*senses) if unpack else funcs[a](senses)
            ctrl[a] = u if isfinite(u) else neutral[a]
        step(model, data)
    return data, touching


def compare_lamp_gp(episodes, repeats, threads, py_episodes, seed=0, seconds=None):
    """Ours (GP trees in-kernel) vs MuJoCo + ``gp.compile`` in a Python loop."""
    import mujoco as mj
    from deap import gp

    from gpmotion.gp.bytecode import tokens_to_tree
    from gpmotion.gp.pset import compile_reference

    task, fam, tokens = bench_gp_trees(seed)
    fig, scene = task.figure, task.scene()
    dt = task.dt
    n_steps = int(round((seconds or task.seconds) / dt))
    q0, qd0 = task.initial_state()
    # --- ours: the trees in the kernel
    batch = fam.encode([tokens] * episodes)
    run = lambda th: gpmotion.rollout(fig, scene, batch, n_steps=n_steps, q0=q0, qd0=qd0, dt=dt,
                                      threads=th)
    tr = run(1)
    ours1 = _best(lambda: run(1), repeats)
    oursn = _best(lambda: run(threads), repeats)
    # --- the trees compute the same in Python: senses recorded in-kernel → compile_reference
    trees = [tokens_to_tree(t, fam.info) for t in tokens]
    ref = [compile_reference(t, fam.info) for t in trees]
    rec = gpmotion.rollout(fig, scene, fam.encode([tokens]), n_steps=min(n_steps, 1000), q0=q0,
                           qd0=qd0, dt=dt, record_every=1, record_senses=True, threads=1)
    agree = max(abs(ref[a](s) - rec.targets[0, f, a]) for f, s in enumerate(rec.senses[0])
                for a in range(fig.n_act))
    # --- MuJoCo + deap.gp.compile, one thread (a Python loop)
    model = mj.MjModel.from_xml_string(mjcf_from_figure(fig, scene, dt=dt))
    user = plain_pset(fam.info)
    funcs = [gp.compile(t, user) for t in trees]
    loop = lambda fs, unpack=True: [mujoco_gp_loop(mj, model, fig, scene.goal, fs, n_steps, q0, qd0,
                                                   unpack=unpack) for _ in range(py_episodes)]
    loop(funcs)                                    # warm (first-call costs)
    outs = []
    mj_gp = _best(lambda: outs.append(loop(funcs)), repeats)
    mj_gp_clamped = _best(lambda: loop(ref, unpack=False), max(1, repeats // 2))
    # the loop's sense vector equals ours at a common state (moving, no contact yet)
    seen = []
    probe = [lambda *s, a=a: seen.append(s) or float(fig.model.neutral[a]) for a in range(fig.n_act)]
    qd_probe = np.linspace(-1.0, 1.0, fig.nv)
    mujoco_gp_loop(mj, model, fig, scene.goal, probe, 1, q0, qd_probe)
    rec0 = gpmotion.rollout(fig, scene, fam.encode([[[float(x)] for x in fig.model.neutral]]),
                            n_steps=1, q0=q0, qd0=qd_probe, dt=dt, record_every=1,
                            record_senses=True, threads=1)
    senses_diff = float(np.abs(np.array(seen[0]) - rec0.senses[0, 0]).max())
    data, touching = outs[-1][0]
    ours_step_s = ours1 / (episodes * n_steps)
    mj_step_s = mj_gp / (py_episodes * n_steps)
    ratio = mj_step_s / ours_step_s
    air = tr.contact_force.sum(axis=-1) == 0
    return {
        "workload": {"figure": "lamp", "task": task.name, "steps_per_episode": n_steps, "dt": dt,
                     "trees": tokens, "tree_nodes": [len(t) for t in tokens], "tree_seed": seed,
                     "ours_episodes": episodes, "mujoco_episodes": py_episodes,
                     "controls": "3 random GP trees (lamp_hop pset), evaluated every step"},
        "ours_gp_steps_per_s": 1.0 / ours_step_s,
        "ours_gp_steps_per_s_all_threads": episodes * n_steps / oursn,
        "mujoco_gp_compile_steps_per_s": 1.0 / mj_step_s,
        "mujoco_gp_compile_clamped_steps_per_s": py_episodes * n_steps / mj_gp_clamped,
        "ratio_one_thread": ratio,
        "bar_one_thread": 10.0,
        "goal_one_thread": 25.0,
        "meets_bar": bool(ratio >= 10.0),
        "meets_goal": bool(ratio >= 25.0),
        "threads": threads,
        "trees_agree_max_abs_diff": float(agree),
        "senses_initial_max_abs_diff": senses_diff,
        "ours_diverged": int(tr.diverged.sum()),
        "ours_contact_frames": float((~air).mean()),
        "ours_airborne_frames": float(air.mean()),
        "ours_final_x": float(tr.q[0, -1, 0]),
        "mujoco_contact_steps": touching / n_steps,
        "mujoco_final_x": float(data.qpos[0]),
        "mujoco_finite": bool(np.all(np.isfinite(data.qpos))),
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


def crosscheck(fig, mjcf, integrators, seconds, q0, dt) -> dict:
    """Max |Δθ| between the engines for a passive figure without ground, from
    joint angles ``q0`` at rest, under each MuJoCo integrator (``mjcf``: the
    figure's MJCF writer), and ours against ourselves at half the step."""
    import mujoco as mj

    scene = gpmotion.make_scene(ground=False)
    n = int(round(seconds / dt))
    tr = gpmotion.simulate(fig, seconds, scene=scene, q0=np.array(q0), dt=dt, record_every=1)
    ours = tr.q[0]                               # [n+1, nq], row k after k steps
    out = {"seconds": seconds, "q0": list(q0), "dt": dt}
    for integ in integrators:
        model = mj.MjModel.from_xml_string(mjcf(fig, scene, integrator=integ, dt=dt))
        d = mj.MjData(model)
        d.qpos[:] = q0
        theirs = [d.qpos.copy()]
        for _ in range(n):
            mj.mj_step(model, d)
            theirs.append(d.qpos.copy())
        out[f"max_angle_diff_{integ}"] = float(np.abs(np.array(theirs) - ours).max())
    # the same comparison for ourselves at half the step: how big an O(dt) gap is
    half = gpmotion.simulate(fig, seconds, scene=scene, q0=np.array(q0), dt=dt / 2, record_every=2)
    out["ours_dt_vs_dt_half"] = float(np.abs(half.q[0] - ours).max())
    out["swing_amplitude"] = float(np.abs(ours).max())
    return out


def pendulum_crosscheck(seconds=2.0, q0=(0.6, -0.4), dt=1e-3):
    """Max |Δθ| between the engines for a passive double pendulum (no contact)."""
    return crosscheck(gpmotion.load_figure(DOUBLE_PENDULUM), mjcf_from_figure,
                      ("Euler", "RK4", "implicitfast"), seconds, q0, dt)


# ------------------------------------------------------------------ 3-D: the humanoid

class _SpatialMJCF(_MJCF):
    """3-D links (``Model3D`` arrays): placed at ``xpos``, turned by ``xrot``."""
    compiler = ' autolimits="false"'

    def lends_joint(self, i, child) -> bool:
        from gpmotion.model import FREE3D
        m = self.m
        return (not np.any(m.xpos[child]) and np.allclose(m.xrot[child], np.eye(3), atol=0, rtol=0)
                and m.jtype[i] != FREE3D)

    def placement(self, i) -> str:
        from gpmotion.figures.spec3d import rot_to_quat
        return f'pos="{_f(*self.m.xpos[i])}" quat="{_f(*rot_to_quat(self.m.xrot[i]))}"'

    def joint(self, i) -> str:
        from gpmotion.model import FREE3D, HINGE3D
        m = self.m
        if m.jtype[i] == FREE3D:
            return f'<freejoint name="{self.names[i]}"/>'
        d = int(m.dadr[i])
        kind = "hinge" if m.jtype[i] == HINGE3D else "slide"
        return (f'<joint name="{self.names[i]}" type="{kind}" axis="{_f(*m.axis[i])}"'
                f' damping="{_f(m.damping[d])}"{self._limits(d)}/>')

    def inertial(self, i) -> str:
        m = self.m
        inertia = m.icom[i]
        return (f'pos="{_f(*m.com[i])}" mass="{_f(m.mass[i])}" fullinertia="'
                f'{_f(*inertia[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]])}"')

    def contact_pos(self, k) -> str:
        return _f(*self.m.cp_pos[k])

    def servo(self, a) -> tuple[str, int]:
        from gpmotion.model import FREE3D
        m = self.m
        d = int(m.act_dof[a])
        link = int(np.nonzero((m.dadr == d) & (m.jtype != FREE3D))[0][0])
        return self.names[link], d


def mjcf_from_figure3d(fig, scene, *, contact_radius=CONTACT_RADIUS, integrator="Euler",
                       dt=1e-3) -> str:
    """An MJCF string for a compiled 3-D gpmotion figure (``Model3D`` arrays).

    Per link: a body at ``xpos`` turned by ``xrot`` (its joint frame), one
    hinge / slide joint about ``axis`` at the body origin, ``<inertial>`` with
    the link's mass, centre of mass and full 3×3 ``icom``.  A massless link
    whose only child sits at its origin with no rest rotation (the inner
    links of an Euler-joint chain) lends its joint to the child's body:
    MuJoCo applies a body's joints in order, each about the already-turned
    frame, which is our chain.  A fixed root is the world (links hanging
    from it carry the root placement in ``xrot``/``xpos``).  PD servos are
    ``<position>`` actuators (kp, kv = our kd, ctrlrange = joint limits,
    forcerange = ± torque limit), contact points 1 mm spheres against a
    plane (μ = the scene's), integrator Euler, no visual geoms.
    """
    return _SpatialMJCF(fig, contact_radius).xml(scene, integrator, dt)


def compare_humanoid(episodes, seconds, repeats, threads, seed=0, amplitude=0.25, figure=None):
    """Ours vs MuJoCo's C ``rollout`` on the 3-D humanoid (herman; or ``figure``,
    a registered 3-D figure such as the creatures), sine targets on every
    actuator changing every step (amplitude ``amplitude`` × the sine
    workload's), one thread and all threads."""
    fig = gpmotion.load_figure(figure or "herman")
    scene = gpmotion.make_scene()
    dt = 1e-3
    n_steps = int(round(seconds / dt))
    off, amp, om, ph = sine_workload(fig, episodes, seed)
    tr, model, state, rates = race(fig, scene, mjcf_from_figure3d(fig, scene, dt=dt),
                                   (off, amplitude * amp, om, ph), n_steps, dt, repeats, threads)
    assert model.nq == fig.nq and model.nu == fig.n_act, (model.nq, model.nu)
    # the engines' joint angles over the episode (PD-driven, so they stay close)
    q_mj = state[:, ::tr.record_every, 1:1 + fig.nq]
    F = min(q_mj.shape[1], tr.q.shape[1])
    ratio = rates["ratio_one_thread"]
    return {
        "workload": {"figure": fig.name, "episodes": episodes, "steps_per_episode": n_steps,
                     "dt": dt, "links": int(len(fig.model.parent)), "dofs": int(fig.nv),
                     "actuators": int(fig.n_act), "contacts": int(len(fig.model.cp_link)),
                     "controls": f"per-episode random sines on every actuator ({amplitude:g} × "
                                 "the bench amplitudes), changing every step",
                     "mujoco_integrator": "Euler", "mujoco_nq": model.nq, "mujoco_nu": model.nu,
                     "mujoco_nbody": model.nbody},
        **rates,
        "bar_one_thread": 0.5,
        "meets_bar": bool(ratio >= 0.5),
        "meets_goal": bool(ratio >= 1.0),
        "ours_diverged": int(tr.diverged.sum()),
        "ours_contact_frames": float((tr.contact_force.sum(axis=-1) > 0).mean()),
        "max_joint_angle_diff_vs_mujoco": float(np.abs(q_mj[:, :F] - tr.q[:, :F]).max()),
    }


PENDULUM3D = {
    "dimensions": 3, "name": "double_pendulum_3d",
    "root": {"type": "fixed", "body": "mount", "position": [0, 0, 2.0]},
    "bodies": [{"name": "mount", "mass": 1.0, "radius": 0.01, "segment": [[0, 0, 0], [0.1, 0, 0]]},
               {"name": "l0", "mass": 1.0, "radius": 0.03, "segment": [[0, 0, 0], [0, 0.1, -1.0]],
                "inertia": [0.09, 0.085, 0.01]},
               {"name": "l1", "mass": 0.6, "radius": 0.02, "segment": [[0, 0, 0], [0.2, 0, -0.7]],
                "inertia": [[0.03, 0.002, -0.004], [0.002, 0.028, 0.001], [-0.004, 0.001, 0.012]]}],
    "joints": [{"name": "j0", "parent": "mount", "child": "l0", "offset": [0, 0, 0], "type": "hinge",
                "axis": [0, 1, 0], "limits": [-10, 10], "actuated": False},
               {"name": "j1", "parent": "l0", "child": "l1", "offset": [0, 0.1, -1.0],
                "rotation": [0.3, 0.0, 0.2], "type": "hinge", "axis": [1, 0.5, 0.3],
                "limits": [-10, 10], "actuated": False}],
}


def pendulum3d_crosscheck(seconds=2.0, q0=(0.6, -0.4), dt=1e-3):
    """Max |Δθ| between the engines for a passive 3-D double pendulum whose second
    hinge axis is not parallel to the first (tilted, in a rotated joint frame)."""
    fig = gpmotion.load_figure(PENDULUM3D)
    out = crosscheck(fig, mjcf_from_figure3d, ("Euler", "RK4"), seconds, q0, dt)
    return {**out, "axes_world_at_rest": [list(map(float, a)) for a in fig.model.axis]}


def format_summary(r: dict) -> str:
    lines = []
    if "ours_steps_per_s" in r:
        w = r["workload"]
        lines += [f"sine targets — lamp, {w['episodes']} episodes × {w['steps_per_episode']} steps "
                  f"(MuJoCo: C rollout, controls precomputed)",
                  f"  ours    {r['ours_steps_per_s'] / 1e6:8.3f} M steps/s one thread, "
                  f"{r['ours_steps_per_s_all_threads'] / 1e6:.3f} M on {r['threads']}",
                  f"  MuJoCo  {r['mujoco_steps_per_s'] / 1e6:8.3f} M steps/s one thread, "
                  f"{r['mujoco_steps_per_s_all_threads'] / 1e6:.3f} M on {r['threads']}",
                  f"  ratio   {r['ratio_one_thread']:8.2f}× one thread (bar {r['bar_one_thread']:g}×: "
                  f"{'met' if r['meets_bar'] else 'NOT met'}), {r['ratio_all_threads']:.2f}× all threads"]
    if "gp" in r:
        g, w = r["gp"], r["gp"]["workload"]
        lines += [f"GP trees ({'/'.join(map(str, w['tree_nodes']))} nodes) — lamp, "
                  f"{w['steps_per_episode']} steps per episode, contacts on",
                  f"  ours, trees in-kernel          {g['ours_gp_steps_per_s'] / 1e6:8.3f} M steps/s "
                  f"one thread ({g['ours_gp_steps_per_s_all_threads'] / 1e6:.3f} M on {g['threads']})",
                  f"  MuJoCo + DEAP gp.compile loop  "
                  f"{g['mujoco_gp_compile_steps_per_s'] / 1e3:8.1f} k steps/s "
                  f"one thread (clamped pset: {g['mujoco_gp_compile_clamped_steps_per_s'] / 1e3:.1f} k)",
                  f"  ratio  {g['ratio_one_thread']:.1f}× (bar {g['bar_one_thread']:g}×: "
                  f"{'met' if g['meets_bar'] else 'NOT met'}; goal {g['goal_one_thread']:g}×: "
                  f"{'met' if g['meets_goal'] else 'not met'})",
                  f"  trees agree in-kernel vs Python: max |Δ| {g['trees_agree_max_abs_diff']:.2g}; "
                  f"senses at a common state: max |Δ| {g['senses_initial_max_abs_diff']:.2g}; "
                  f"contact: ours {100 * g['ours_contact_frames']:.0f}% of frames, MuJoCo "
                  f"{100 * g['mujoco_contact_steps']:.0f}% of steps"]
    if "humanoid" in r:
        h, w = r["humanoid"], r["humanoid"]["workload"]
        lines += [f"humanoid — {w['figure']} ({w['links']} links, {w['dofs']} dof, {w['contacts']} "
                  f"contacts), {w['episodes']} episodes × {w['steps_per_episode']} steps, sine targets "
                  f"(MuJoCo: C rollout, controls precomputed)",
                  f"  ours    {h['ours_steps_per_s'] / 1e6:8.3f} M steps/s one thread, "
                  f"{h['ours_steps_per_s_all_threads'] / 1e6:.3f} M on {h['threads']}",
                  f"  MuJoCo  {h['mujoco_steps_per_s'] / 1e6:8.3f} M steps/s one thread, "
                  f"{h['mujoco_steps_per_s_all_threads'] / 1e6:.3f} M on {h['threads']}",
                  f"  ratio   {h['ratio_one_thread']:8.2f}× one thread (bar {h['bar_one_thread']:g}×: "
                  f"{'met' if h['meets_bar'] else 'NOT met'}; goal 1×: "
                  f"{'met' if h['meets_goal'] else 'not met'}), {h['ratio_all_threads']:.2f}× all threads"]
    for name, h in r.get("creatures", {}).items():     # the creatures' bar: ≥ 1.5× one thread
        w = h["workload"]
        lines.append(f"creature {name} ({w['links']} links, {w['dofs']} dof, {w['contacts']} contacts): "
                     f"ours {h['ours_steps_per_s'] / 1e6:.3f}, MuJoCo {h['mujoco_steps_per_s'] / 1e6:.3f} "
                     f"M steps/s one thread, ratio {h['ratio_one_thread']:.2f}× "
                     f"(bar 1.5×: {'met' if h['ratio_one_thread'] >= 1.5 else 'NOT met'})")
    if "pendulum3d_crosscheck" in r:
        c = r["pendulum3d_crosscheck"]
        lines.append(f"3-D pendulum cross-check (tilted second axis): max |Δθ| vs MuJoCo Euler "
                     f"{c['max_angle_diff_Euler']:.2g} rad, RK4 {c['max_angle_diff_RK4']:.2g} "
                     f"(ours dt vs dt/2: {c['ours_dt_vs_dt_half']:.2g})")
    if "pendulum_crosscheck" in r:
        c = r["pendulum_crosscheck"]
        lines.append(f"pendulum cross-check: max |Δθ| vs MuJoCo Euler {c['max_angle_diff_Euler']:.2g} rad, "
                     f"RK4 {c['max_angle_diff_RK4']:.2g} (ours dt vs dt/2: {c['ours_dt_vs_dt_half']:.2g})")
    v = r["versions"]
    lines.append(f"mujoco {v['mujoco']}, numba {v['numba']}, numpy {v['numpy']}, {v['cpu_count']} cpus")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--json", action="store_true", help="print one JSON object with every number")
    p.add_argument("--only", choices=["sine", "gp", "humanoid", "creatures"],
                   help="run one workload (default: all)")
    p.add_argument("--humanoid-seconds", type=float, default=None,
                   help="simulated seconds per episode, humanoid workload (default 2, quick 0.5)")
    p.add_argument("--episodes", type=int, default=None, help="episodes per batch (ours)")
    p.add_argument("--seconds", type=float, default=None,
                   help="simulated seconds per episode, sine workload (GP: lamp_hop's 3 s)")
    p.add_argument("--gp-seconds", type=float, default=None,
                   help="simulated seconds per episode, GP workload (default: lamp_hop's)")
    p.add_argument("--mujoco-episodes", type=int, default=None,
                   help="episodes of the MuJoCo + gp.compile Python loop per timing")
    p.add_argument("--repeats", type=int, default=None)
    p.add_argument("--threads", type=int, default=None)
    a = p.parse_args(argv)
    import mujoco
    import numba
    episodes = a.episodes or (8 if a.quick else 64)
    seconds = a.seconds or (0.5 if a.quick else 2.0)
    repeats = a.repeats or (2 if a.quick else 3)
    threads = a.threads or numba.config.NUMBA_NUM_THREADS
    py_episodes = a.mujoco_episodes or (1 if a.quick else 3)
    result = {}
    if a.only in (None, "sine"):
        result.update(compare_lamp(episodes, seconds, repeats, threads))
    if a.only in (None, "gp"):
        result["gp"] = compare_lamp_gp(episodes, max(repeats, 5), threads, py_episodes,
                                       seconds=a.gp_seconds)
    if a.only in (None, "humanoid"):
        result["humanoid"] = compare_humanoid(episodes, a.humanoid_seconds or seconds, repeats, threads)
    if a.only in (None, "creatures"):        # Cujo, Rex, Bob (free roots, on the ground)
        result["creatures"] = {n: compare_humanoid(episodes, a.humanoid_seconds or seconds, repeats,
                                                   threads, figure=n) for n in ("cujo", "rex", "bob")}
    result["pendulum_crosscheck"] = pendulum_crosscheck()
    result["pendulum3d_crosscheck"] = pendulum3d_crosscheck()
    result["versions"] = {"mujoco": mujoco.__version__, "numba": numba.__version__,
                          "numpy": np.__version__, "cpu_count": os.cpu_count()}
    print(json.dumps(result, indent=2) if a.json else format_summary(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
