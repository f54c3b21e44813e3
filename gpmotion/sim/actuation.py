"""Joint laws shared by the planar and the 3-D kernels, per scalar dof.

A joint limit is a unilateral spring-damper (it pushes back, never pulls);
an actuator is a torque-limited PD servo (``pd``) or Auslander's kinematic
τ-law τ²θ̈ + 2τθ̇ + (θ − θ₀) = 0 (``kinematic``: a prescribed acceleration).

PD servos are implicit in the velocity ("stable PD", Tan et al. 2011; MuJoCo's
implicit damping).  The explicit law u = kp(θ* − θ) − kd·θ̇ on a joint of
effective inertia I, stepped by semi-implicit Euler, is unstable once
kd·dt/I > 2 (the velocity update multiplies by 1 − kd·dt/I each step) — a
light link between stiff servos (a humanoid's pelvis) jitters at dt = 1 ms.
Evaluating the damping at the end-of-step velocity θ̇⁺ = θ̇ + dt·θ̈ and the
spring at θ + dt²·θ̈ (the step's θ⁺ = θ + dt·θ̇⁺ less its explicit dt·θ̇ part):

    τ = kp(θ* − θ − dt²·θ̈) − kd(θ̇ + dt·θ̈) = u − a·θ̈,    a = dt·(kd + dt·kp),

i.e. a joint *armature* a: the ABA adds it to the joint's D = SᵀIᴬS, with
u as the joint force (and reports u − a·θ̈, the torque actually applied).
With it a 1-dof servo is stable for every I > 0 and every gain (analysis in
``tests/test_physics.py``).  A saturated servo (|u| ≥ τ_max) gives a
constant torque, which does not depend on θ̇⁺: no armature; nor for a
kinematic (prescribed) joint.
"""
import numpy as np
from numba import njit

_INLINE = dict(cache=True, error_model="numpy", boundscheck=False, inline="always")


@njit(**_INLINE)
def limit_torque(x, w, lo, hi, k, c):
    """Torque of the limit spring-damper at angle x and rate w."""
    if x < lo:
        return max(0.0, k * (lo - x) - c * w)
    if x > hi:
        return min(0.0, k * (hi - x) - c * w)
    return 0.0


@njit(**_INLINE)
def servo(x, w, target, neutral, lo, hi, kp, kd, tau_max, tau_c, actuation, dt):
    """(torque, prescribed?, prescribed acceleration, armature) of one actuator.

    The armature ``dt·(kd + dt·kp)`` of an unsaturated PD servo makes it
    implicit (module docstring); it is 0 for a saturated servo and for a
    kinematic joint.  Targets are clamped to the limits; a non-finite target
    (a controller's NaN) holds neutral instead of poisoning the physics.
    """
    if not np.isfinite(target):
        target = neutral
    target = min(hi, max(lo, target))
    if actuation == 0:
        u = kp * (target - x) - kd * w
        arm = dt * (kd + dt * kp) if abs(u) < tau_max else 0.0
        return min(tau_max, max(-tau_max, u)), 0, 0.0, arm
    tc = max(tau_c, 2.0 * dt)
    return 0.0, 1, (target - x - 2.0 * tc * w) / (tc * tc), 0.0


@njit(**_INLINE)
def apply_servos(M, q, qd, targets, taus, actuation, dt, act_q, tau, presc, presc_qdd, arm):
    """Add every actuator's servo torque (or prescribed acceleration) to its dof.

    Actuator a drives dof ``M.act_dof[a]``, whose angle is ``q[act_q[a]]``.
    """
    for a in range(M.act_dof.shape[0]):
        d = M.act_dof[a]
        u, p, acc, ar = servo(q[act_q[a]], qd[d], targets[a], M.neutral[a], M.lo[d], M.hi[d],
                              M.kp[a], M.kd[a], M.tau_max[a], taus[a], actuation, dt)
        tau[d] += u
        arm[d] += ar
        if p:
            presc[d] = 1
            presc_qdd[d] = acc
