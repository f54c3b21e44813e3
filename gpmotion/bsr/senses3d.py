"""The senses of 3-D sense-based BSR controllers (Auslander et al. §4.2) and their filter.

"The physical senses used in our 3D controllers are the height of Bob's
center of mass and its linear velocity, Bob's angular velocity, an up vector
(the latter three senses are expressed as 3D vectors in a figure-centric
coordinate system), contact forces and collision impulses for each possible
contact point, and internal angles for each flexible joint", all low-pass
filtered "to remove noise and high-frequency variation".  Ours, in order
(V = 10 + n_contacts + n_driven_joints):

  com_z                        height of the centre of mass (m)
  v_fwd, v_left, v_up          linear velocity: the root body's horizontal
                               velocity (m/s) and the com's vertical velocity
  w_fwd, w_left, w_up          the root body's angular velocity (rad/s)
  up_fwd, up_left, up_up       the root body's up axis
  force_<contact>              normal contact force at every contact point (N)
  angle_<joint>                every joint the controller drives (rad)

Figure-centric frame: the *heading frame* of the root body — x along its
forward axis projected on the ground, z up, y to the left — so the senses do
not change when the figure walks in another direction, and the up vector
reads the figure's forward and sideways tilt.  Choices the paper leaves
open, stated here:
* the 3-D kernel senses the com's vertical velocity but not its horizontal
  one, so the horizontal velocity is the root body's (the trunk or pelvis,
  which carries most of the mass);
* "collision impulses" are not separate senses: the filtered normal force
  is the impulse per unit time over the filter's window;
* ranges (for normalization to [0, 1]) are the figure's ranges of the raw
  senses each one is built from (velocity ±3 m/s, angular velocity
  ±10 rad/s, up ±1, com height 0..2 m, forces and angles as the figure).

The filter: a first-order low-pass (exponential smoothing) of each sense at
the controller's sampling interval Δ = ``record_every`` × dt (the task's
frame interval: 20 ms on the creature tasks):

    y_k = y_{k−1} + α (x_k − y_{k−1}),   α = 1 − exp(−Δ / τ_f),   y_0 = x_0,

the exact discretization of τ_f ẏ = x − y with the input held over each
interval.  Its step response is 1 − (1 − α)^k (63 % after τ_f); default
τ_f = 0.05 s (corner frequency 1/(2π τ_f) ≈ 3.2 Hz), which removes the
contact springs' chatter (tens of Hz) and keeps the gait (1-2 Hz).  The
controller filters in-kernel (``sense3d_kernel``) at exactly the recorded
frames, so :func:`filtered_trajectory` — the numpy twin — gives the
relevance heuristic the same points the controller saw.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gpmotion.controllers import ControllerBatch

KERNEL = str(Path(__file__).resolve().parent / "sense3d_kernel.py")
FILTER_TAU = 0.05                       # s: the low-pass filter's time constant
SOURCES = ("vx", "vy", "com_vz", "wx", "wy", "wz", "up_x", "up_y", "up_z", "com_z", "yaw")
BODY_NAMES = ("com_z", "v_fwd", "v_left", "v_up", "w_fwd", "w_left", "w_up",
              "up_fwd", "up_left", "up_up")
# each body sense is normalized with the range of this raw sense
_RANGE_OF = ("com_z", "vx", "vy", "com_vz", "wx", "wy", "wz", "up_x", "up_y", "up_z")


def filter_alpha(interval: float, tau: float = FILTER_TAU) -> float:
    """α of the first-order low-pass filter sampled every ``interval`` s."""
    if not (interval > 0 and tau > 0):
        raise ValueError(f"filter: interval and tau must be > 0, got {interval}, {tau}")
    return float(1.0 - np.exp(-interval / tau))


def low_pass(x, alpha: float) -> np.ndarray:
    """y over frames (axis −2) of x [..., F, V]: y_0 = x_0, y_k = y_{k−1} + α (x_k − y_{k−1})."""
    x = np.asarray(x, dtype=np.float64)
    y = np.empty_like(x)
    y[..., 0, :] = x[..., 0, :]
    for k in range(1, x.shape[-2]):
        y[..., k, :] = y[..., k - 1, :] + alpha * (x[..., k, :] - y[..., k - 1, :])
    return y


@dataclass(frozen=True)
class SensePlan:
    """Which raw senses of a figure make the 3-D BSR senses, and their ranges."""
    names: tuple[str, ...]          # V sense names (BODY_NAMES, force_*, angle_*)
    sources: np.ndarray             # int[11]: raw indices of SOURCES
    extra: np.ndarray               # int[n_c + n_a]: raw indices of force_* and angle_*
    n_contacts: int
    lo: np.ndarray                  # float[V]
    hi: np.ndarray
    every: int                      # steps between samples
    alpha: float

    @property
    def n_senses(self) -> int:
        return len(self.names)

    def derived(self, raw) -> np.ndarray:
        """Unfiltered senses [..., F, V] from raw recorded senses [..., F, n_raw]."""
        raw = np.asarray(raw, dtype=np.float64)
        s = raw[..., self.sources]
        c, sn = np.cos(s[..., 10]), np.sin(s[..., 10])
        body = [s[..., 9]]
        for k in range(3):
            a, b = s[..., 3 * k], s[..., 3 * k + 1]
            body += [c * a + sn * b, -sn * a + c * b, s[..., 3 * k + 2]]
        return np.concatenate([np.stack(body, axis=-1), raw[..., self.extra]], axis=-1)

    def filtered(self, raw) -> np.ndarray:
        """Filtered senses in raw units [..., F, V] (what the controller holds)."""
        return low_pass(self.derived(raw), self.alpha)

    def normalized(self, raw) -> np.ndarray:
        """Filtered, normalized senses in [0, 1] [..., F, V]: the stimulus trajectory."""
        span = self.hi - self.lo
        y = (self.filtered(raw) - self.lo) / np.where(span > 0, span, 1.0)
        return np.clip(np.where(span > 0, y, 0.5), 0.0, 1.0)


def sense_plan(fig, actuators, record_every: int, dt: float, tau: float = FILTER_TAU) -> SensePlan:
    """The plan for a 3-D figure whose controller drives ``actuators`` (indices)."""
    names = list(fig.sense_names)
    missing = [n for n in SOURCES if n not in names]
    if missing:
        raise ValueError(f"3-D sense-based BSR needs the senses {missing} ({fig.name} is not a 3-D figure?)")
    sources = np.array([names.index(n) for n in SOURCES], dtype=np.int64)
    forces = [f"force_{c}" for c in fig.contact_names]
    angles = [f"angle_{fig.actuator_names[a]}" for a in actuators]
    extra = np.array([names.index(n) for n in forces + angles], dtype=np.int64)
    m = fig.model
    rng_idx = [names.index(n) for n in _RANGE_OF] + list(extra)
    return SensePlan(names=BODY_NAMES + tuple(forces + angles), sources=sources, extra=extra,
                     n_contacts=len(forces), lo=np.asarray(m.sense_lo, np.float64)[rng_idx].copy(),
                     hi=np.asarray(m.sense_hi, np.float64)[rng_idx].copy(), every=int(record_every),
                     alpha=filter_alpha(record_every * dt, tau))


def encode_batch(genomes, plan: SensePlan, actuators) -> ControllerBatch:
    """Program arrays of SenseGenomes for ``sense3d_kernel`` (layout there)."""
    genomes = list(genomes)
    if not genomes:
        raise ValueError("encode_batch: no genomes")
    amap = np.asarray(actuators, dtype=np.int64).ravel()
    V = plan.n_senses
    for g in genomes:
        if g.kind != "sense" or g.n_senses != V or g.n_act != amap.size:
            raise ValueError(f"encode_batch: a 3-D sense-based genome needs {V} senses and "
                             f"{amap.size} joints, got {g.kind} with {getattr(g, 'n_senses', 0)} and {g.n_act}")
    n_a = plan.extra.size - plan.n_contacts
    head = np.concatenate([[0, V, amap.size, plan.every, plan.n_contacts, n_a],
                           plan.sources, plan.extra, amap]).astype(np.int64)
    rows_i, rows_f = [], []
    for g in genomes:
        head[0] = g.n_rules
        rows_i.append(head.copy())
        rules = np.hstack([g.weights()[:, None], g.tau[:, None], g.mu, g.lam, g.theta0]).ravel()
        rows_f.append(np.concatenate([[plan.alpha], plan.lo, plan.hi, rules]))
    ci = np.zeros((len(genomes), max(r.size for r in rows_i)), dtype=np.int64)
    cf = np.zeros((len(genomes), max(r.size for r in rows_f)), dtype=np.float64)
    for e, (ri, rf) in enumerate(zip(rows_i, rows_f)):
        ci[e, :ri.size] = ri
        cf[e, :rf.size] = rf
    return ControllerBatch(module=KERNEL, ci=ci, cf=cf, cstate_size=2 + 2 * V)


def select_rules(genome, stimulus) -> np.ndarray:
    """Numpy twin of the kernel's rule choice: the active rule at every frame
    of a normalized stimulus trajectory [F, V] (rule 0 at frame 0)."""
    W = genome.weights()
    active = np.zeros(stimulus.shape[0], dtype=np.int64)
    for f in range(1, stimulus.shape[0]):
        score = W * (1.0 - np.max((genome.lam * (stimulus[f] - genome.mu)) ** 2, axis=1))
        j = int(np.argmax(score))
        active[f] = j if score[j] > 0 else active[f - 1]
    return active
