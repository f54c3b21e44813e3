"""Batched rollout: many episodes in parallel (threads) → a Trajectory.

The kernel is the one episode loop (gpmotion.sim.episode) generated per
controller kernel module (so the controller's ``control`` is inlined into
the step loop: no Python call per step) and cached on disk
(gpmotion.sim.kernels); the figure's backend (gpmotion.sim.backend) supplies
the physics and the geometry of recorded frames.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..compile_events import compile_lock
from ..controllers import ControllerBatch
from ..model import KINEMATIC, PD, REVOLUTE, Figure, Scene, make_scene
from .backend import backend_of
from .kernel_io import Outputs, Program, Settings, Start
from .grip3d import O_LINK
from .kernels import kernel_for
from .threads import run_chunks

DIVERGE_LIMIT = 1e4        # |q| or |q̇| beyond this ends the episode as diverged
ACTUATION = {"pd": PD, "kinematic": KINEMATIC}


@dataclass
class Trajectory:
    """Recorded channels of a batch, frames every ``record_every`` steps.

    Shapes: ``[E, F, ...]`` for E episodes and F frames.  Event channels
    (contact_force, pole_hit, impact, energy) hold the max (sum for energy)
    over the steps since the previous frame.

    3-D figures (``figure.dimensions == 3``): ``q`` holds the configuration
    (nq: a free root's position and quaternion first), ``qd`` the velocity
    (nv), ``com`` is [E, F, 6] (x, y, z, vx, vy, vz); ``poses()`` gives 4×4
    link transforms, ``base()`` (x, y, z, qw, qx, qy, qz), ``sites()`` and
    ``segments()`` 3-vectors.
    """
    figure: Figure
    scene: Scene
    dt: float
    record_every: int
    times: np.ndarray          # [F]
    q: np.ndarray              # [E, F, nq]
    qd: np.ndarray             # [E, F, nv]  (nv = nq for planar figures)
    com: np.ndarray            # [E, F, 4]  x, z, vx, vz  (3-D: [E, F, 6] x, y, z, vx, vy, vz)
    contact_force: np.ndarray  # [E, F, nc] max ground normal force per contact point
    pole_hit: np.ndarray       # [E, F]     max penetration into any pole (m)
    impact: np.ndarray         # [E, F]     max total ground normal force (N)
    energy: np.ndarray         # [E, F]     actuator work |τ·q̇|·dt since the previous frame (J)
    targets: np.ndarray        # [E, F, n_act]
    senses: np.ndarray | None  # [E, F, n_senses] when recorded
    diverged: np.ndarray       # [E] bool
    diverged_step: np.ndarray  # [E] step of divergence or −1
    contact_end: np.ndarray | None = None   # [E, nc, 2|3] friction anchors at the end (contact0 of a continuation)
    steps_run: np.ndarray | None = None     # [E] steps simulated: fewer when a divergence or a stop ended one
    obj: np.ndarray | None = None   # [E, F, 7] the scene's object: x, y, z, vx, vy, vz, gripped (0/1); None: no object

    @property
    def n_episodes(self) -> int:
        return self.q.shape[0]

    def __repr__(self) -> str:        # not the arrays (tens of kB)
        div = int(self.diverged.sum())
        n = self.n_episodes
        return (f"Trajectory({self.figure.name!r}, {n} episode{'s' * (n != 1)} × "
                f"{len(self.times)} frames every {self.dt * self.record_every * 1e3:g} ms, "
                f"{self.times[-1] if len(self.times) else 0:g} s, q {self.q.shape[2]}"
                f"{', senses' if self.senses is not None else ''}"
                f"{f', {div} diverged' if div else ''})")

    def _repr_html_(self) -> str:     # Jupyter: the report's player (the first episode)
        from ..report.inline import player_html
        return player_html(self)

    def episode(self, e: int) -> "Trajectory":
        """A one-episode view (keeps the leading axis)."""
        sl = slice(e, e + 1)
        return replace(self, q=self.q[sl], qd=self.qd[sl], com=self.com[sl],
                       contact_force=self.contact_force[sl], pole_hit=self.pole_hit[sl],
                       impact=self.impact[sl], energy=self.energy[sl], targets=self.targets[sl],
                       senses=None if self.senses is None else self.senses[sl],
                       diverged=self.diverged[sl], diverged_step=self.diverged_step[sl],
                       contact_end=None if self.contact_end is None else self.contact_end[sl],
                       obj=None if self.obj is None else self.obj[sl])

    @property
    def backend(self):
        """The simulator backend of the figure (gpmotion.sim.backend)."""
        return backend_of(self.figure.model)

    @property
    def is3d(self) -> bool:
        return self.figure.dimensions == 3

    def _memo(self, key: str, compute):
        """``compute()`` once per Trajectory (scores ask for poses and sites
        several times); keyed on ``q`` so a ``replace``d copy recomputes.
        Results are read-only."""
        key = "_memo" + key                      # not to shadow the methods
        cached = self.__dict__.get(key)
        if cached is None or cached[0] is not self.q:
            value = compute()
            for v in value if isinstance(value, tuple) else (value,):
                v.setflags(write=False)
            cached = self.__dict__[key] = (self.q, value)
        return cached[1]

    def poses(self) -> np.ndarray:
        """Planar: [E, F, nl, 3] (θ, x, z); 3-D: [E, F, nl, 4, 4] world transforms."""
        return self._memo("_poses", lambda: self.backend.link_poses(self.figure.model, self.q))

    def base(self) -> np.ndarray:
        """Base (root body) pose [E, F, 3] = (pitch, x, z); 3-D: [E, F, 7] (x, y, z, qw, qx, qy, qz)."""
        return self.backend.base_pose(self.figure.model, self.q, self.poses)

    def _points(self, links, local) -> np.ndarray:
        return self.backend.points(self.figure.model, self.q, self.poses, links, local)

    def _sites_and_segments(self) -> tuple[np.ndarray, np.ndarray]:
        """Sites and capsule end points from one kinematics pass over the frames
        (a 3-D score asks for both, and the pass is most of their cost)."""
        f, m = self.figure, self.figure.model
        ns, nseg = len(f.site_link), len(m.seg_link)

        def compute():
            # site_pos is [n_sites, dims] even with no sites (figures.specparse);
            # each capsule's two ends side by side, so both results are views
            # of the one array (a herman generation's is ~100 MB: no copies)
            ends = np.stack([m.seg_a, m.seg_b], axis=1).reshape(2 * nseg, -1)
            p = self._points(np.concatenate([f.site_link, np.repeat(m.seg_link, 2)]),
                             np.concatenate([f.site_pos, ends]))
            return p[..., :ns, :], p[..., ns:, :].reshape(p.shape[:-2] + (nseg, 2, p.shape[-1]))
        return self._memo("_sites_segments", compute)

    def sites(self) -> np.ndarray:
        """World positions of the figure's sites [E, F, n_sites, 2 or 3]."""
        return self._sites_and_segments()[0]

    def site(self, name: str) -> np.ndarray:
        """World positions of one site [E, F, 2 or 3]: the same numbers as
        ``sites()[..., k, :]`` (each point is computed on its own), without the
        other points when those are not computed yet (a score that reads one
        site of a generation's episodes pays for one point, not all)."""
        k = self.figure.site_names.index(name)
        whole = self.__dict__.get("_memo_sites_segments")
        if whole is not None and whole[0] is self.q:
            return whole[1][0][..., k, :]
        f = self.figure
        return self._memo(f"_site_{name}", lambda: self._points(f.site_link[k:k + 1],
                                                                f.site_pos[k:k + 1])[..., 0, :])

    def segments(self) -> np.ndarray:
        """Capsule end points [E, F, n_seg, 2 (a/b), 2 or 3]."""
        return self._sites_and_segments()[1]

    def sense(self, name: str) -> np.ndarray:
        if self.senses is None:
            raise ValueError("senses were not recorded (rollout(..., record_senses=True))")
        return self.senses[..., self.figure.sense_index(name)]


def _batch_state(x, n, nq, default, what):
    x = default if x is None else np.asarray(x, dtype=np.float64)
    x = np.atleast_2d(x)
    if x.shape[-1] != nq:
        raise ValueError(f"{what} must have {nq} entries (one per "
                         f"{'coordinate' if what == 'q0' else 'dof'}), got {x.shape[-1]}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{what} must be finite")
    # a writable C-ordered copy: one kernel signature (a broadcast row copied in
    # numpy's "K" order came out Fortran-ordered, and compiled the kernel again)
    return np.array(np.broadcast_to(x, (n, nq)), order="C")


def _contact_state(x, n, nc, k):
    """The friction-anchor state [n, nc, k] (anchor x (, y), touching 0/1) a rollout starts from."""
    if x is None:
        return np.zeros((n, nc, k))
    x = np.asarray(x, dtype=np.float64)
    if x.shape[-2:] != (nc, k) or not np.all(np.isfinite(x)):
        raise ValueError(f"contact0 must be finite, shaped [..., {nc}, {k}] (a Trajectory's contact_end), "
                         f"got {x.shape}")
    return np.array(np.broadcast_to(x, (n, nc, k)), order="C")        # a copy: the kernel writes it


def rollout(figure: Figure, scene: Scene, controller: ControllerBatch, *, n_steps: int,
            q0=None, qd0=None, contact0=None, dt: float = 1e-3, record_every: int = 10,
            actuation: str = "pd", default_tau: float = 0.05, record_senses: bool = False,
            stop_pitch: float | None = None, threads: int | None = None) -> Trajectory:
    """Simulate every episode of ``controller`` for ``n_steps`` steps of ``dt``.

    The full physical state at the end is (``q[:, -1]``, ``qd[:, -1]``,
    ``contact_end``); passing them as ``q0``, ``qd0``, ``contact0`` continues
    the motion exactly (``contact_end`` holds each contact point's friction
    anchor and touching flag; by default no point starts touching).

    ``n_steps`` may give each episode its own length (a composite's phases):
    episode e then ends at frame ⌈n_steps[e] / record_every⌉ (its
    ``contact_end`` is taken there) and its later frames hold that pose with
    zero velocity and no events, as after a divergence.

    ``stop_pitch`` (planar figures with a floating base): an episode ends at
    the first recorded frame whose base pitch is beyond ±``stop_pitch`` rad,
    and holds that frame to the end in the same way; ``steps_run`` counts the
    steps each episode simulated.
    """
    if actuation not in ACTUATION:
        raise ValueError(f"actuation must be one of {sorted(ACTUATION)}, got {actuation!r}")
    if not (np.isfinite(dt) and 0 < dt <= 0.01):
        raise ValueError(f"dt must be in (0, 0.01] s, got {dt!r}")
    E, nq, nv, m = controller.n_episodes, figure.nq, figure.nv, figure.model
    steps = np.floor(np.asarray(n_steps, dtype=np.float64))      # as int(n_steps) did
    if steps.ndim > 1 or steps.size not in (1, E) or not np.all((steps >= 1) & (steps < 2**40)) or record_every < 1:
        raise ValueError("n_steps (a number, or one per episode) and record_every must be >= 1")
    steps = -(-steps.astype(np.int64) // record_every) * record_every     # whole frames
    n_steps = int(steps.max())
    steps = np.array(np.broadcast_to(steps, (E,)))
    backend = backend_of(m)
    has_obj = len(scene.obj) > 0
    if has_obj and (figure.dimensions != 3 or not 0 <= scene.obj[O_LINK] < len(m.parent)):
        raise ValueError(f"scene: a free object needs a 3-D figure and a gripping link of it; "
                         f"{figure.name!r} has {len(m.parent)} links")
    if len(scene.selfc) and (figure.dimensions != 3 or scene.selfc[:, :2].max() >= len(m.seg_link)):
        raise ValueError(f"scene: self-contact pairs need a 3-D figure and segments of it; "
                         f"{figure.name!r} has {len(m.seg_link)} segments")
    if scene.max_contacts and figure.dimensions != 2:
        raise ValueError(f"scene: max_contacts applies to planar figures only; {figure.name!r} is 3-D")
    q0 = _batch_state(q0, E, nq, figure.q_default, "q0")
    qd0 = _batch_state(qd0, E, nv, np.zeros(nv), "qd0")
    F = n_steps // record_every + 1
    nc, na, ns = len(m.cp_link), len(m.act_dof), len(m.sense_lo)
    start = Start(steps, q0, qd0, _contact_state(contact0, E, nc, backend.CONTACT_WIDTH))
    settings = Settings(float(dt), int(record_every), ACTUATION[actuation], float(default_tau),
                        DIVERGE_LIMIT, bool(record_senses), *_stop(figure, stop_pitch))
    program = Program(np.array(controller.ci, dtype=np.int64, order="C"),
                      np.array(controller.cf, dtype=np.float64, order="C"),
                      np.zeros((E, max(1, controller.cstate_size))))
    out = Outputs.zeros(E, F, nq, nv, backend.COM_WIDTH, nc, na, ns, record_senses, has_obj)
    kernel = kernel_for(controller.module, backend.NAME)
    run_batch(kernel, (m, scene, backend.goal(scene), settings, start, program, out), E, threads)
    channels = out._asdict()
    status, senses, obj = channels.pop("status"), channels.pop("senses"), channels.pop("obj")
    return Trajectory(figure=figure, scene=scene, dt=dt, record_every=record_every,
                      times=np.arange(F) * dt * record_every,
                      senses=senses if record_senses else None,
                      diverged=status[:, 0].astype(bool), diverged_step=status[:, 1],
                      contact_end=start.contact, obj=obj if has_obj else None,
                      steps_run=status[:, 2].copy(), **channels)


def _stop(figure: Figure, stop_pitch: float | None) -> tuple[int, float, float]:
    """The kernel's stop condition (dof, offset, bound) for ``stop_pitch``: the base's
    pitch is its hinge's q plus the fixed angles above it, where only slides are."""
    if stop_pitch is None:
        return -1, 0.0, 0.0
    if not (np.isfinite(stop_pitch) and stop_pitch > 0):
        raise ValueError(f"stop_pitch must be a positive angle (rad), got {stop_pitch!r}")
    m = figure.model
    b = int(m.base_link) if figure.dimensions == 2 else -1
    chain = []
    while b >= 0:
        chain.append(b)
        b = int(m.parent[b])
    if not chain or m.jtype[chain[0]] != REVOLUTE or any(m.jtype[l] == REVOLUTE for l in chain[1:]):
        raise ValueError(f"stop_pitch needs a planar figure whose base is a hinge on slides; "
                         f"{figure.name!r} has none")
    return chain[0], float(sum(m.xtree[l, 0] for l in chain)), float(stop_pitch)


def run_batch(kernel, args: tuple, n: int, threads: int | None = None) -> None:
    """Episodes 0..n-1 of a rollout kernel's batch on ``threads`` threads
    (:func:`gpmotion.sim.threads.run_chunks`): the kernel releases the GIL and
    an episode writes only its own rows, so its result does not depend on the
    thread that ran it.  The kernel is compiled or loaded first, here, under
    the compile lock."""
    if not getattr(kernel.rollout_batch, "signatures", True):
        with compile_lock(kernel.__file__):
            kernel.rollout_batch(*args, 0, 0)
    run_chunks(kernel.rollout_batch, args, n, threads)


def simulate(figure: Figure, seconds: float = 2.0, *, targets=None, scene: Scene | None = None,
             q0=None, qd0=None, contact0=None, dt: float = 1e-3, record_every: int = 10,
             actuation: str = "pd", default_tau: float = 0.05) -> Trajectory:
    """One episode for scripts and tests.

    ``targets``: None (hold neutral), an array [n_act] (constant), a pair
    ``(times, targets[K, n_act])`` of keyframes, or a ControllerBatch.
    """
    from ..controllers import schedule
    if isinstance(figure, str):
        from ..figures import load_figure
        figure = load_figure(figure)
    if targets is None:
        ctrl = schedule.constant(figure.model.neutral)
    elif isinstance(targets, ControllerBatch):
        ctrl = targets
    elif isinstance(targets, tuple) and len(targets) == 2:
        ctrl = schedule.keyframes(*targets)
    else:
        ctrl = schedule.constant(targets)
    if not isinstance(targets, ControllerBatch) and targets is not None:
        n = np.asarray(targets[1] if isinstance(targets, tuple) else targets).reshape(-1, figure.n_act if figure.n_act else 1)
        if figure.n_act == 0 or n.shape[-1] != figure.n_act:
            raise ValueError(f"targets: figure {figure.name!r} has {figure.n_act} actuators "
                             f"({', '.join(figure.actuator_names)})")
    scene = scene or make_scene(**figure.ground)
    return rollout(figure, scene, ctrl, n_steps=max(1, int(round(seconds / dt))), q0=q0, qd0=qd0,
                   dt=dt, record_every=record_every, actuation=actuation, default_tau=default_tau)
