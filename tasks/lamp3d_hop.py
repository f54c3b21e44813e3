"""lamp3d_hop: the 3-D lamp hops to a target point (Gritz & Hahn's lamp is 3-D).

lamp_hop on the ``lamp3d`` figure: a free base with width, so the lamp can tip
sideways, turn and drift out of its plane.  The same terms and weights as
lamp_hop; "distance" is measured in the floor plane (sideways drift counts)
and "fell" is the base tilting beyond 1 rad in any direction.  A symmetric
start would never leave the plane, so the lamp starts tilted sideways by
``roll0`` (resting on one edge of its base): the first landing is lopsided and
the controller must hop without tipping over or drifting sideways.
"""
import math

import numpy as np

from gpmotion.model import make_scene
from gpmotion.task import Task, register_task
from gpmotion.tasks.lamp_hop import ARRIVED, HOP_TERMS

# per base corner: half lamp_hop's per-point ground (make_scene's 5000 N/m,
# 60 N·s/m), so each side's two corners push as one planar base contact did
GROUND = {"k_ground": 2500.0, "c_ground": 30.0, "k_tangent": 2500.0, "c_tangent": 30.0}
BASE = ("base_back_l", "base_back_r", "base_front_l", "base_front_r")
FELL = 1.0              # rad: base tilt (angle of its up axis from vertical)
HALF_WIDTH = 0.08       # m: base centre to its side edge (lamp3d.toml)
HALF_THICK = 0.015      # m: base centre to its underside
LAMP3D_PARAMS = {"roll0": 0.05}
LAMP3D_DOCS = {"roll0": "initial sideways tilt of the base about the travel axis, resting on "
                        "its right edge (rad; 0 = the planar lamp's symmetric start, which never "
                        "leaves the plane; tipping starts at ≈0.43)"}


def tilted_start(task):
    """q_default with the base rolled by roll0 about its lower right edge (y = −0.08 m)."""
    q = task.figure.q_default.copy()
    phi = task.params["roll0"]
    c, s = math.cos(phi), math.sin(phi)
    edge_z = q[2] - HALF_THICK                   # the upright base's underside
    q[1] = -HALF_WIDTH + c * HALF_WIDTH - s * HALF_THICK
    q[2] = edge_z + s * HALF_WIDTH + c * HALF_THICK
    q[3:7] = (math.cos(phi / 2), math.sin(phi / 2), 0.0, 0.0)
    return q, np.zeros(task.figure.nv)


def base_tilt(traj) -> np.ndarray:
    """Angle between the base's up axis and the vertical [E, F] (rad)."""
    _, qx, qy, _ = np.moveaxis(traj.base()[..., 3:7], -1, 0)
    up_z = 1.0 - 2.0 * (qx * qx + qy * qy)          # z of the body z axis
    return np.arccos(np.clip(up_z, -1.0, 1.0))


def hop3d_measures(task, traj):
    """lamp_hop's terms for the 3-D lamp (lamp3d_limbo adds the pole)."""
    fig = traj.figure
    base = traj.site("base_centre")[..., :2]                 # [E, F, 2] floor plane
    goal = np.array([task.params["distance"], 0.0])
    d = np.linalg.norm(base - goal, axis=-1)
    at = d < ARRIVED
    first = np.where(at.any(axis=1), at.argmax(axis=1), d.shape[1] - 1)
    late = traj.times[first] / task.seconds
    after = np.arange(d.shape[1])[None, :] >= first[:, None]
    speed = np.linalg.norm(traj.com[..., 3:6], axis=-1)
    moving = np.where(after, speed, 0.0).sum(axis=1) / np.maximum(after.sum(axis=1), 1)
    heads = [fig.contact_names.index(c) for c in ("head_tip", "head_rim")]
    head_force = traj.contact_force[..., heads].max(axis=(1, 2))
    fell = base_tilt(traj).max(axis=1) > FELL
    act = fig.model.act_q                # configuration index (the free root has 7)
    neutral = np.abs(traj.q[:, -1, act] - fig.model.neutral).mean(axis=1)
    return {"distance": d[:, -1], "late": late, "moving": moving,
            "head_hit": (head_force > 0).astype(float) + head_force / (fig.total_mass * 9.81),
            "fell": fell.astype(float), "neutral": neutral,
            "energy": traj.energy.sum(axis=1), "sideways": np.abs(base[:, -1, 1])}


def count_hops3d(traj, e=0):
    """Hops of episode e: flights of the whole lamp, as the filmstrip marks them."""
    from gpmotion.frames import flights
    return flights(traj, e)


@register_task
class Lamp3DHop(Task):
    name = "lamp3d_hop"
    figure = "lamp3d"
    goal_label = "target"
    description = "the 3-D lamp (free base, can tip sideways) hops to a target point"
    params = {"distance": 0.4, "seconds": 3.0, **LAMP3D_PARAMS}
    bounds = {"distance": (-5.0, 5.0), "roll0": (0.0, 1.0)}
    param_docs = {"distance": "target x from the start (m; |distance| ≥ 0.05)",
                  "seconds": "episode length (s)", **LAMP3D_DOCS}
    terms = HOP_TERMS
    success_threshold = ("base within 5 cm of the target in the floor plane, head never "
                         "touched, base never tilted beyond 1 rad")
    view = {"elev": 20, "azim": -70}

    def validate(self):
        if not 0.05 <= abs(self.params["distance"]) <= 5.0:
            raise ValueError(f"lamp3d_hop: distance must be within 0.05..5 m, got {self.params['distance']}")

    def scene(self):
        return make_scene(goal=(self.params["distance"], 0.0, 0.0), **GROUND)

    def initial_state(self):
        return tilted_start(self)

    def measure(self, traj):
        return hop3d_measures(self, traj)

    def success(self, traj, m):
        return (m["distance"] < ARRIVED) & (m["fell"] == 0) & (m["head_hit"] == 0)

    def describe(self, traj, m):
        return [f"hops: {count_hops3d(traj)}", f"final distance {m['distance'][0] * 100:.1f} cm",
                f"sideways {m['sideways'][0] * 100:.1f} cm",
                f"max tilt {np.degrees(base_tilt(traj)[0].max()):.0f}°"]
