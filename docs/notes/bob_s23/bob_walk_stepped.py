"""bob_walk_stepped: Bob's walk scored by the ground his steps cover
(session 23's experiment, a plugin: ``--plugins docs/notes/bob_s23``; not a
shipped task).

bob_walk-v3 rewards the com's and the feet's forward motion (weights 1 and
0.5) and 0.2 per alternating step; its best controllers travel 0.5-1.6 m on
1-3 counted steps: most of the distance is sliding and leaning, which earns
as much as stepping.  Here the com's travel is worth a quarter as much, the
feet's nothing, and each counted step (v3's: alternating, landing ≥ 5 cm
ahead of the other foot, facing within 45°, before a fall) earns its
length, the landing foot's lead over the other foot (capped at 0.6 m),
times ``w_stride``.  Falls, facing and sideways motion cost as in v3.
Solved as v3: ≥ 5 alternating forward steps before falling.
"""
import numpy as np

from gpmotion.bsr import secondary3d as s3
from gpmotion.task import Term, register_task
from gpmotion.tasks._creature3d import FALL, SIDEWAYS, foot_tracks
from gpmotion.tasks.bob_walk import BobWalkV3

CAP = 0.6


def stride(force, fwd, fell, yaw, max_yaw=np.radians(45.0), ahead=0.05):
    """Σ lead (m, ≤ CAP) of the alternating forward steps [E] (count_steps' rule)."""
    down = force > 0
    touch = down[:, 1:, :] & ~down[:, :-1, :]
    lead = fwd[:, 1:, :] - fwd[:, 1:, ::-1]
    ok = ~np.asarray(fell)[:, 1:] & (np.abs(yaw[:, 1:] - yaw[:, :1]) <= max_yaw)
    step = touch & (lead >= ahead) & ok[..., None]
    total = np.zeros(step.shape[0])
    last = np.full(step.shape[0], -1)
    for f in range(step.shape[1]):
        for k in (0, 1):
            take = step[:, f, k] & (last != k)
            total += np.where(take, np.minimum(lead[:, f, k], CAP), 0.0)
            last = np.where(take, k, last)
    return total


@register_task
class BobWalkStepped(BobWalkV3):
    name = "bob_walk_stepped"
    version = 1
    description = "Bob walks forward, scored by the length of his alternating steps"
    params = {**BobWalkV3.params, "w_com": 0.25, "w_stride": 2.0}
    param_docs = {**BobWalkV3.param_docs, "w_com": "reward per m of com travel",
                  "w_stride": "reward per m of alternating forward steps (each ≤ 0.6 m)"}
    terms = (Term("distance", -1.0, param="w_com", doc="com displacement along the start heading (m)"),
             Term("stride", -1.0, param="w_stride", main=True, doc="Σ length of the alternating forward steps (m)"),
             SIDEWAYS, FALL,
             Term("facing", 1.0, param="w_facing", doc="mean |heading − start heading| (rad)"))

    def measure(self, traj):
        m = super().measure(traj)
        fig = traj.figure
        yaw = s3.heading(traj.base()[..., 3:7])
        other = [k for k, n in enumerate(fig.contact_names) if n not in self.feet]
        fell = s3.fallen(s3.quat_up(traj.base()[..., 3:7])[..., 2], traj.com[..., 2],
                         traj.contact_force[..., other], self.max_tilt, self.min_height)
        xy = traj.sites()[..., [fig.site_names.index(n) for n in self.foot_sites], :2]
        fwd, force = foot_tracks(traj, xy, self.foot_groups, yaw)
        m["stride"] = stride(force, fwd, fell, yaw)
        return m
