"""The compiled figure: flat arrays the kernels read, plus the names around them.

Every link carries one degree of freedom (planar kernel).  A `planar` root
is the chain  slide-x → slide-z → hinge  (the first two links massless), so
the generalized coordinates are ``q = [x, z, pitch, hinge angles...]``.  A
`fixed` root body is welded to the world: it owns no link, and its child
joints hang from the world (parent -1) at the root placement.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

# joint (link) types
REVOLUTE, SLIDE_X, SLIDE_Z = 0, 1, 2
# actuation per dof
PASSIVE, ACTUATED = 0, 1
# actuation modes for a rollout
PD, KINEMATIC = 0, 1


class Model(NamedTuple):
    """Arrays only: the one thing the numba kernels see (order parents-first)."""
    BACKEND = "planar"      # the simulator backend (gpmotion.sim.backend); class constants,
    DIMENSIONS = 2          # not fields (the kernels never see them)
    parent: np.ndarray      # int64[nl]   parent link or -1 (world)
    jtype: np.ndarray       # int64[nl]   REVOLUTE / SLIDE_X / SLIDE_Z
    xtree: np.ndarray       # float64[nl, 3]  (angle, rx, rz) parent→joint frame
    mass: np.ndarray        # float64[nl]
    com: np.ndarray         # float64[nl, 2]  centre of mass in link frame
    icom: np.ndarray        # float64[nl]     rotational inertia about the com
    lo: np.ndarray          # float64[nl]     joint limits (±inf when free)
    hi: np.ndarray
    damping: np.ndarray     # float64[nl]     passive viscous joint damping
    act_dof: np.ndarray     # int64[na]   dof of each actuator
    kp: np.ndarray          # float64[na]
    kd: np.ndarray
    tau_max: np.ndarray
    neutral: np.ndarray     # float64[na]
    cp_link: np.ndarray     # int64[nc]   contact points (-1: world-fixed body)
    cp_pos: np.ndarray      # float64[nc, 2]
    seg_link: np.ndarray    # int64[ns]   capsules for drawing and obstacles
    seg_a: np.ndarray       # float64[ns, 2]
    seg_b: np.ndarray
    seg_r: np.ndarray       # float64[ns]
    fixed_pose: np.ndarray  # float64[3]  pose of a fixed root body (θ, x, z)
    base_link: int          # link whose pose is "the base" (-1: fixed root)
    limit_k: float          # joint-limit spring (N·m/rad)
    limit_c: float          # joint-limit damper (N·m·s/rad)
    sense_lo: np.ndarray    # float64[n_senses] ranges of the normalized view
    sense_hi: np.ndarray
    sense_at: np.ndarray    # int64[n_slots] where the kernel writes each sense slot (gpmotion.sim.senses)

    @property
    def nq(self) -> int:
        return len(self.parent)

    @property
    def nv(self) -> int:
        return len(self.parent)

    def __repr__(self) -> str:
        return _model_repr(self)


def _model_repr(m) -> str:
    """Sizes, not arrays: a Model's full repr is tens of kB."""
    dims = "3-D" if m.DIMENSIONS == 3 else "planar"
    return (f"{type(m).__name__}({dims}: {len(m.parent)} links, {len(m.act_dof)} actuators, "
            f"{len(m.cp_link)} contact points, {len(m.seg_link)} segments, "
            f"{len(m.sense_lo)} senses, mass {float(m.mass.sum()):.3g} kg)")


# ---- 3-D figures (gpmotion.sim.spatial3d) ---------------------------------
# link types of the 3-D kernel
HINGE3D, SLIDE3D, FREE3D = 0, 1, 2


class Model3D(NamedTuple):
    """Arrays of a 3-D figure (order parents-first); see gpmotion/sim/spatial3d.py.

    Every link has one dof (hinge about / slide along ``axis`` of its joint
    frame) except a ``free`` root, link 0: 6 dofs, q = (x, y, z, qw, qx, qy, qz),
    q̇ = (ω_body, v_body).  Per-dof arrays (``lo``, ``hi``, ``damping``) have nv
    entries; ``qadr``/``dadr`` give each link's first q / q̇ index.
    """
    BACKEND = "3d"          # the simulator backend (gpmotion.sim.backend); class constants,
    DIMENSIONS = 3          # not fields (the kernels never see them)
    parent: np.ndarray      # int64[nl]   parent link or -1 (world)
    jtype: np.ndarray       # int64[nl]   HINGE3D / SLIDE3D / FREE3D
    axis: np.ndarray        # float64[nl, 3]  unit joint axis in the joint frame
    xrot: np.ndarray        # float64[nl, 3, 3]  joint frame → parent coordinates
    xpos: np.ndarray        # float64[nl, 3]     joint frame origin in the parent
    qadr: np.ndarray        # int64[nl]
    dadr: np.ndarray        # int64[nl]
    mass: np.ndarray        # float64[nl]
    com: np.ndarray         # float64[nl, 3]     centre of mass in link frame
    icom: np.ndarray        # float64[nl, 3, 3]  inertia about the com, link frame
    lo: np.ndarray          # float64[nv]  joint limits (±inf when free)
    hi: np.ndarray
    damping: np.ndarray     # float64[nv]
    act_dof: np.ndarray     # int64[na]   velocity index of each actuator
    act_q: np.ndarray       # int64[na]   configuration index of each actuator
    kp: np.ndarray          # float64[na]
    kd: np.ndarray
    tau_max: np.ndarray
    neutral: np.ndarray     # float64[na]
    cp_link: np.ndarray     # int64[nc]   contact points (-1: fixed root body)
    cp_pos: np.ndarray      # float64[nc, 3]
    ss_link: np.ndarray     # int64[nss]  sensed sites (``sense = true``; -1: fixed root body)
    ss_pos: np.ndarray      # float64[nss, 3]  their positions in the link frame
    seg_link: np.ndarray    # int64[ns]
    seg_a: np.ndarray       # float64[ns, 3]
    seg_b: np.ndarray
    seg_r: np.ndarray       # float64[ns]
    fixed_rot: np.ndarray   # float64[3, 3]  orientation of a fixed root body
    fixed_pos: np.ndarray   # float64[3]     its position
    base_link: int          # link whose frame is "the base" (-1: fixed root)
    limit_k: float
    limit_c: float
    sense_lo: np.ndarray
    sense_hi: np.ndarray
    sense_at: np.ndarray    # int64[n_slots] where the kernel writes each sense slot (gpmotion.sim.senses)
    nq: int
    nv: int

    def __repr__(self) -> str:
        return _model_repr(self)
# ---- end 3-D ---------------------------------------------------------------


class Scene(NamedTuple):
    """World settings shared by every episode of a rollout."""
    gravity: float          # m/s², acting along −z
    ground: int             # 1: a ground plane at ground_z, 0: none
    ground_z: float
    k_ground: float         # normal stiffness per contact point (N/m)
    c_ground: float         # normal damping per contact point (N·s/m)
    mu: float               # Coulomb friction coefficient
    k_tangent: float        # stick spring of the friction anchor (N/m)
    c_tangent: float        # stick damper (N·s/m)
    poles: np.ndarray       # float64[np, 3] horizontal poles: x, z, radius
    k_pole: float
    c_pole: float
    goal: np.ndarray        # float64[2] the goal point (x, z) senses refer to
    goal_y: float = 0.0     # its y: a 3-D figure's goal is (goal[0], goal_y, goal[1])
    obj: np.ndarray = np.zeros(0)   # a free object, its table and grip (gpmotion.sim.grip3d); empty: none
    selfc: np.ndarray = np.zeros((0, 4))   # self-contact pairs (gpmotion.sim.selfcontact3d); empty: none
    max_contacts: int = 0   # planar: only the deepest N points touch the ground (Auslander's 2); 0: all

    @property
    def goal3(self) -> np.ndarray:
        """The goal as a 3-D point (x, y, z)."""
        return np.array([self.goal[0], self.goal_y, self.goal[1]], dtype=np.float64)


def make_scene(*, gravity=9.81, ground=True, ground_z=0.0, k_ground=5000.0,
               c_ground=60.0, mu=0.8, k_tangent=5000.0, c_tangent=60.0,
               poles=(), k_pole=5000.0, c_pole=50.0, goal=(0.0, 0.0), obj=(), selfc=(),
               max_contacts=0) -> Scene:
    """A Scene with the defaults every shipped figure is stable with at dt=1 ms.

    ``goal``: (x, z) for planar figures, or (x, y, z) (a 3-D figure's senses
    refer to it; a planar one sees its (x, z)).
    ``obj``: a free object with its table and grip, 3-D figures only
    (``gpmotion.sim.grip3d.object_params``); empty: none.
    ``selfc``: capsule pairs of a 3-D figure that collide with each other
    (``gpmotion.sim.selfcontact3d.self_contact_pairs``); empty: none.
    ``max_contacts``: planar figures only; N > 0 lets only the N most deeply
    penetrating contact points touch the ground each step, the others pass
    through it (Auslander et al. §2.1 assume two); 0: every point.
    """
    goal = np.asarray(goal, dtype=np.float64).reshape(-1)
    if goal.size not in (2, 3) or not np.all(np.isfinite(goal)):
        raise ValueError(f"scene: goal must be 2 (x, z) or 3 (x, y, z) finite numbers, got {goal.tolist()}")
    goal_y = float(goal[1]) if goal.size == 3 else 0.0
    goal = goal[[0, 2]].copy() if goal.size == 3 else goal.copy()
    poles = np.asarray(poles, dtype=np.float64).reshape(-1, 3)
    for name, v in (("gravity", gravity), ("k_ground", k_ground), ("c_ground", c_ground),
                    ("mu", mu), ("k_tangent", k_tangent), ("c_tangent", c_tangent),
                    ("k_pole", k_pole), ("c_pole", c_pole)):
        if not np.isfinite(v) or v < 0:
            raise ValueError(f"scene: {name} must be a finite number >= 0, got {v!r}")
    if isinstance(max_contacts, bool) or not isinstance(max_contacts, (int, np.integer)) or max_contacts < 0:
        raise ValueError(f"scene: max_contacts must be an integer >= 0 (0: every point), got {max_contacts!r}")
    if not np.all(np.isfinite(poles)) or np.any(poles[:, 2] <= 0):
        raise ValueError("scene: poles need finite x, z and a radius > 0")
    return Scene(float(gravity), int(bool(ground)), float(ground_z), float(k_ground),
                 float(c_ground), float(mu), float(k_tangent), float(c_tangent),
                 poles, float(k_pole), float(c_pole), goal, goal_y, _object(obj), _selfc(selfc),
                 int(max_contacts))


def _object(obj) -> np.ndarray:
    from .sim.grip3d import N_OBJ
    obj = np.array(obj, dtype=np.float64).reshape(-1)
    if obj.size not in (0, N_OBJ) or not np.all(np.isfinite(obj)):
        raise ValueError(f"scene: obj must be empty or {N_OBJ} finite numbers "
                         "(gpmotion.sim.grip3d.object_params)")
    return obj


def _selfc(selfc) -> np.ndarray:
    from .sim.selfcontact3d import N_SELFC
    rows = np.array(selfc, dtype=np.float64).reshape(-1, N_SELFC)
    if not np.all(np.isfinite(rows)) or np.any(rows < 0) or np.any(rows[:, :2] != np.round(rows[:, :2])):
        raise ValueError("scene: selfc rows are (segment, segment, k, c): two segment indices, "
                         "k and c >= 0 (gpmotion.sim.selfcontact3d.self_contact_pairs)")
    return rows


@dataclass
class Figure:
    """A compiled figure: the Model plus names for people and tasks."""
    name: str
    model: Model
    root: str                       # "planar" or "fixed" (3-D also "free")
    link_names: list[str]           # per dof
    actuator_names: list[str]       # joint names of actuated hinges
    contact_names: list[str]
    site_names: list[str]
    site_link: np.ndarray
    site_pos: np.ndarray
    sense_names: list[str]
    body_names: list[str]
    q_default: np.ndarray           # initial q from the spec
    total_mass: float
    description: str = ""
    spec: dict = field(default_factory=dict, repr=False)

    @property
    def ground(self) -> dict:
        """The ground this figure is made for (its spec's ``[ground]``:
        make_scene's k_ground, c_ground, mu, k_tangent, c_tangent); {} = defaults."""
        return dict(self.spec.get("ground", {}))

    @property
    def nq(self) -> int:
        """Length of the configuration q (a 3-D free root has nq = nv + 1)."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Length of the velocity q̇ (equals nq for planar figures)."""
        return int(self.model.nv)

    @property
    def dimensions(self) -> int:
        return self.model.DIMENSIONS

    @property
    def n_act(self) -> int:
        return len(self.model.act_dof)

    def __repr__(self) -> str:        # names and sizes, not the Model's arrays
        return (f"Figure({self.name!r}, {self.dimensions}-D, {self.root} root, "
                f"{len(self.body_names)} bodies, {self.n_act} actuated joints, "
                f"{len(self.contact_names)} contacts, {len(self.site_names)} sites, "
                f"{len(self.sense_names)} senses, {self.total_mass:.3g} kg)")

    def sense_index(self, name: str) -> int:
        try:
            return self.sense_names.index(name)
        except ValueError:
            raise KeyError(f"figure {self.name!r} has no sense {name!r}; "
                           f"senses: {', '.join(self.sense_names)}") from None

    def actuator_limits(self) -> np.ndarray:
        m = self.model
        return np.stack([m.lo[m.act_dof], m.hi[m.act_dof]], axis=1)
