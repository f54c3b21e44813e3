"""The episode loop of every rollout: one loop for every backend and controller.

Each step: the backend observes the state (kinematics, contact forces, com,
senses), the controller sets the joint targets, a frame is recorded every
``every`` steps (event channels hold the max, energy the sum, since the
previous frame), and the backend advances the state by dt.

A rollout kernel for a backend and a controller kernel module is a copy of
this file with two lines replaced, the imports marked ``# backend`` and
``# controller`` below (:mod:`gpmotion.sim.kernels` writes the copy to the
cache folder, so numba caches it on disk and inlines the backend's steps and
the controller's ``control`` into the loop: no call per step).  Imported as it
is, with JIT disabled, the steps dispatch in Python on the model's backend and
the ``schedule`` controller runs.  The controller contract is in
:mod:`gpmotion.controllers`; the arguments are the named structures of
:mod:`gpmotion.sim.kernel_io`.
"""
import numpy as np
from numba import njit

from gpmotion.sim.borrow import borrowed, hold
from gpmotion.sim.backend import JIT, advance, observe, save_contact, store_object, workspace  # backend
from gpmotion.controllers.schedule_kernel import control as ctrl_control, init as ctrl_init  # controller


def run_episode(M, S, goal, st, e, start, prog, out):
    """Simulate episode ``e`` of the batch."""
    n_steps = start.n_steps[e]
    M, S = borrowed(M), borrowed(S)   # the model and scene outlive the call: uncounted
    contact = start.contact[e]
    # views of the caller's arrays, uncounted (the caller holds them past the call)
    ci, cf, cstate = borrowed((prog.ci[e], prog.cf[e], prog.cstate[e]))
    out_q, out_qd, out_com, out_cforce = borrowed((out.q[e], out.qd[e], out.com[e],
                                                   out.contact_force[e]))
    out_pole, out_impact, out_energy = borrowed((out.pole_hit[e], out.impact[e], out.energy[e]))
    out_targets, out_senses, status, out_obj = borrowed((out.targets[e], out.senses[e],
                                                         out.status[e], out.obj[e]))
    has_obj = S.obj.shape[0] > 0
    dt, every, actuation, default_tau, limit = st.dt, st.every, st.actuation, st.default_tau, st.limit
    record_senses = st.record_senses
    stop_dof, stop_off, stop_abs = st.stop_dof, st.stop_off, st.stop_abs
    nc = M.cp_link.shape[0]
    na = M.act_dof.shape[0]
    ns = M.sense_lo.shape[0]
    neutral = M.neutral
    owned = workspace(M, S, start.qd0.shape[1], contact)
    work = borrowed(owned)         # uncounted views (gpmotion.sim.borrow); owned lives to the end
    # the state and the loop's scratch, held by ``scratch`` to the end and used uncounted
    scratch = (start.q0[e].copy(), start.qd0[e].copy(), np.zeros(nc), np.zeros(out_com.shape[1]),
               np.zeros(ns + 1), np.zeros(ns), np.zeros(na), np.zeros(na), np.zeros(nc))
    q, qd, cforce, com, senses_all, senses_norm, targets, taus, max_cf = borrowed(scratch)
    senses = senses_all[:ns]       # senses_all: + a scratch entry for the body slots a layout leaves out
    max_pole = 0.0
    max_impact = 0.0
    energy = 0.0
    frame = 0
    countdown = 0                  # steps until the next recorded frame
    ctrl_init(ci, cf, cstate)
    status[0] = 0
    status[1] = -1
    status[2] = n_steps
    ended = False                  # a recorded frame met the stop condition
    for step in range(n_steps + 1):
        t = step * dt
        pen = observe(M, S, goal, q, qd, work, cforce, com, t, senses_all, senses_norm)
        total = 0.0
        for k in range(nc):
            total += cforce[k]
            if cforce[k] > max_cf[k]:
                max_cf[k] = cforce[k]
        max_impact = max(max_impact, total)
        max_pole = max(max_pole, pen)
        for a in range(na):
            targets[a] = neutral[a]
            taus[a] = default_tau
        ctrl_control(ci, cf, senses, senses_norm, t, cstate, targets, taus)
        if countdown == 0:
            countdown = every
            out_q[frame, :] = q
            out_qd[frame, :] = qd
            out_com[frame, :] = com
            out_cforce[frame, :] = max_cf
            out_pole[frame] = max_pole
            out_impact[frame] = max_impact
            out_energy[frame] = energy
            out_targets[frame, :] = targets
            if record_senses:
                out_senses[frame, :] = senses
            if has_obj:
                store_object(work, out_obj[frame])
            max_cf[:] = 0.0
            max_pole = 0.0
            max_impact = 0.0
            energy = 0.0
            frame += 1
            ended = stop_dof >= 0 and abs(q[stop_dof] + stop_off) > stop_abs
        countdown -= 1
        if step == n_steps or ended:
            status[2] = step
            break
        ok, energy = advance(M, S, q, qd, targets, taus, actuation, dt, limit, work, energy)
        if not ok:
            status[0] = 1
            status[1] = step
            status[2] = step + 1
            break
    save_contact(owned, contact)
    hold(scratch)
    # an episode that ended early (diverged, stopped, or shorter) holds its last frame
    for f in range(frame, out_q.shape[0]):
        out_q[f, :] = out_q[frame - 1, :]
        out_qd[f, :] = 0.0
        out_com[f, :] = out_com[frame - 1, :]
        out_cforce[f, :] = 0.0
        out_pole[f] = 0.0
        out_impact[f] = 0.0
        out_energy[f] = 0.0
        out_targets[f, :] = out_targets[frame - 1, :]
        if record_senses:
            out_senses[f, :] = out_senses[frame - 1, :]
        if has_obj:
            out_obj[f, :] = out_obj[frame - 1, :]


_run_episode = njit(**JIT)(run_episode)


@njit(cache=True, nogil=True)
def rollout_batch(M, S, goal, st, start, prog, out, lo, hi):
    """Episodes ``lo`` to ``hi`` - 1 of the batch, without the GIL: the threads of
    :func:`gpmotion.sim.rollout.run_batch` share a batch out, and an episode writes
    only its own rows.  (Threads from Python, not a numba ``prange``: the parallel
    wrapper adds a sixth to a kernel's cold compile.)"""
    for i in range(lo, hi):
        _run_episode(M, S, goal, st, i, start, prog, out)
