"""herman_grasp: Herman picks a small ball up from a table and lifts it 10 cm
(Gritz & Hahn's humanoid: "touching and grasping targets").

The ball (0.2 kg, 3 cm radius) rests on a table top in front of Herman's
right hip, within reach of the right arm.  The hand closes on it the first
time they touch (the ball's centre within its radius + the hand capsule's
of the hand's axis: ``gpmotion.sim.grip3d``'s grip, a weld at the ball's
centre that then holds it under gravity), so the GP has to bring the hand
to the ball and then raise it.  The GP drives the right arm, as in the
other arm tasks; it sees the fingertip relative to the ball's start.

Main goal (a cost of 1 per 10 cm): how far the hand stayed from touching
the ball (its closest approach, 0 once gripped) plus how far the ball's
final height falls short of ``lift`` + 2 cm above its start (aiming a
little past the success height).  Style points as every Herman task, and
``table``: the hand or fingertip below the table top over the table (the
arm is not stopped by the table, so a penalty stands in for it).

Success: the ball gripped and at least ``lift`` above its start at the end,
with the motion at rest (``_herman.at_rest``).
"""
from dataclasses import replace

import numpy as np

from gpmotion.model import make_scene
from gpmotion.sim import geometry3d
from gpmotion.sim.grip3d import object_params
from gpmotion.task import Term, register_task
from gpmotion.tasks._herman import (GP_DEFAULTS, MAIN_WEIGHT, REST_RULE, HermanTask, TrunkCheck,
                                    style_measures, style_terms)

MASS, RADIUS = 0.2, 0.03                 # kg, m: the ball
BALL = (0.35, -0.22, -0.05)              # its start in the pelvis frame (m): fore, left, up
TABLE_X, TABLE_Y = (0.15, 0.80), (-0.60, 0.20)   # the table top's extent, pelvis frame (m)
MARGIN = 0.02                            # m: the main term aims this far past ``lift``


@register_task
class HermanGrasp(HermanTask):
    name = "herman_grasp"
    description = "Herman picks a ball up from a table and lifts it"
    params = {"lift": 0.10, "seconds": 2.0}
    # 36 generations, not 50: the grip forms in the first 0.15 s and lifting
    # is found early; 50 took 89-108 s of main-thread CPU.  5 seeds
    # each: 5 / 5 at 42 (88-97 s), 5 / 5 at 36
    gp = replace(HermanTask.gp, defaults={**GP_DEFAULTS, "generations": 36})
    bounds = {"lift": (0.0, 0.3)}
    param_docs = {"lift": "how high to lift the ball above its start (m)",
                  "seconds": "episode length (s)"}
    goal_label = "ball"
    terms = (Term("grasp", MAIN_WEIGHT, main=True,
                  doc="closest hand-ball gap before the grip (m) + shortfall of the ball's "
                      "final height below lift + 2 cm (m)"),
             Term("table", MAIN_WEIGHT, phase=(0.1, 0.4),
                  doc="mean depth of hand and fingertip below the table top, over the table (m)"),
             *style_terms())
    success_threshold = "ball gripped and lifted at least `lift` above its start at the end; " + REST_RULE

    def validate(self):
        if not 0.0 <= self.params["lift"] <= 0.3:
            raise ValueError(f"herman_grasp: lift must be within 0..0.3 m, got {self.params['lift']}")

    def _world(self, rel):
        m = self.figure.model
        return m.fixed_pos + m.fixed_rot @ np.asarray(rel, float)

    @property
    def ball_start(self) -> np.ndarray:
        return self._world(BALL)

    @property
    def table_z(self) -> float:
        return float(self.ball_start[2] - RADIUS)

    def _hand(self):
        """(link, a, b, radius) of the right hand's capsule: the gripping surface."""
        f = self.figure
        m = f.model
        i = f.body_names.index("hand_r")
        return int(m.seg_link[i]), m.seg_a[i], m.seg_b[i], float(m.seg_r[i])

    def scene(self):
        link, a, b, r = self._hand()
        lo, hi = self._world((TABLE_X[0], TABLE_Y[0], 0.0)), self._world((TABLE_X[1], TABLE_Y[1], 0.0))
        obj = object_params(mass=MASS, radius=RADIUS, position=self.ball_start, table_z=self.table_z,
                            table_x=(min(lo[0], hi[0]), max(lo[0], hi[0])),
                            table_y=(min(lo[1], hi[1]), max(lo[1], hi[1])),
                            link=link, a=a, b=b, grip_radius=r)
        return make_scene(goal=tuple(float(v) for v in self.ball_start), obj=obj)

    def _gap(self, traj):
        """Per episode, frame: distance from the ball's surface to the hand capsule (m, >= 0)."""
        link, a, b, r = self._hand()
        ends = geometry3d.points_fast(self.figure.model, traj.q, [link, link], np.stack([a, b]))
        wa, wb = ends[..., 0, :], ends[..., 1, :]
        c, ab = traj.obj[..., :3], wb - wa
        t = np.clip(np.einsum("...k,...k->...", c - wa, ab)
                    / np.maximum(np.einsum("...k,...k->...", ab, ab), 1e-12), 0.0, 1.0)
        d = np.linalg.norm(c - (wa + t[..., None] * ab), axis=-1)
        return np.maximum(d - RADIUS - r, 0.0)

    def _below_table(self, traj):
        """Mean over frames of the deepest of hand and fingertip below the table top, over it."""
        scene_obj = self.scene().obj
        x0, x1, y0, y1 = scene_obj[6], scene_obj[7], scene_obj[8], scene_obj[9]
        depth = np.zeros(traj.q.shape[:2])
        for name in ("hand_r", "fingertip_r"):
            p = traj.site(name)
            over = (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 1] >= y0) & (p[..., 1] <= y1)
            depth = np.maximum(depth, np.where(over, np.maximum(self.table_z - p[..., 2], 0.0), 0.0))
        return depth.mean(axis=1)

    def measure(self, traj):
        gripped = traj.obj[:, -1, 6] > 0
        gap = np.where(gripped, 0.0, self._gap(traj).min(axis=1))
        lift = traj.obj[:, -1, 2] - self.ball_start[2]
        short = np.maximum(self.params["lift"] + MARGIN - lift, 0.0)
        out = {"grasp": gap + short, "table": self._below_table(traj), "lift": lift,
               "gripped": gripped.astype(float)}
        out.update(style_measures(traj))
        return out

    def reached(self, traj, m):
        return (m["gripped"] > 0) & (m["lift"] >= self.params["lift"])

    def describe(self, traj, m):
        g = traj.obj[0, :, 6] > 0
        when = f"at {traj.times[g.argmax()]:.2f} s" if g.any() else "never"
        return [f"ball gripped {when}; lifted {m['lift'][0] * 100:.1f} cm (goal {self.params['lift'] * 100:.0f} cm)",
                f"fingertip speed over the last 0.1 s ≤ {m['end_speed'][0] * 100:.1f} cm/s"]


@register_task
class HermanGraspV2(TrunkCheck, HermanGrasp):
    """v2: the right forearm may not cross the trunk (``_herman.TrunkCheck``;
    v1's seed 0 did not cross; the check is on every Herman task)."""
    version = 2


@register_task
class HermanGraspV3(TrunkCheck, HermanGrasp):
    """v3: the forearm check judged, not charged (``TrunkCheck.charge``): the
    cost and the search are v1's, success also needs the forearm out of the
    trunk.  5 seeds: v2 (charged) 4 / 5, v1's search 5 / 5, whose
    best controllers never crossed (0.0 cm)."""
    version = 3
    charge = False
