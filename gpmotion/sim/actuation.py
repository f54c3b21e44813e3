"""Joint laws shared by the planar and the 3-D kernels, per scalar dof.

A joint limit is a unilateral spring-damper (it pushes back, never pulls);
an actuator is a torque-limited PD servo (``pd``) or Auslander's kinematic
τ-law τ²θ̈ + 2τθ̇ + (θ − θ₀) = 0 (``kinematic``: a prescribed acceleration).
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
    """(torque, prescribed?, prescribed acceleration) of one actuator.

    Targets are clamped to the limits; a non-finite target (a controller's
    NaN) holds neutral instead of poisoning the physics.
    """
    if not np.isfinite(target):
        target = neutral
    target = min(hi, max(lo, target))
    if actuation == 0:
        u = kp * (target - x) - kd * w
        return min(tau_max, max(-tau_max, u)), 0, 0.0
    tc = max(tau_c, 2.0 * dt)
    return 0.0, 1, (target - x - 2.0 * tc * w) / (tc * tc)
