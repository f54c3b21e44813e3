"""Dense hybrid dynamics shared by the planar and 3-D references (plain numpy)."""
import numpy as np


def hybrid_dynamics(H, C, tau, presc, presc_qdd, arm):
    """qdd and joint forces from the joint-space mass matrix H and bias forces C.

    Prescribed dofs (``presc``) move with ``presc_qdd``; a free dof's joint
    force is ``tau − arm·qdd`` (the implicit-PD armature), so the system
    matrix is H + diag(arm).  Returns (qdd, forces): a prescribed dof's force
    is the one that makes it move as told, a free dof's its joint force.
    """
    n = len(tau)
    presc = np.zeros(n, bool) if presc is None else np.asarray(presc, bool)
    arm = np.zeros(n) if arm is None else np.asarray(arm, float)
    H = H + np.diag(np.where(presc, 0.0, arm))
    free = ~presc
    qdd = np.zeros(n)
    if presc.any():
        qdd[presc] = np.asarray(presc_qdd)[presc]
    rhs = tau[free] - C[free] - H[np.ix_(free, presc)] @ qdd[presc]
    qdd[free] = np.linalg.solve(H[np.ix_(free, free)], rhs)
    tau_out = np.array(tau, dtype=float)
    tau_out[presc] = (H @ qdd + C)[presc]          # arm is 0 on prescribed dofs
    tau_out[free] -= arm[free] * qdd[free]
    return qdd, tau_out
