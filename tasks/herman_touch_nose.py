"""herman_touch_nose: Herman touches his nose with the right index fingertip
(Gritz & Hahn's humanoid: "touching grasping targets, gesturing, touching nose").

The GP drives the right arm (shoulder y/z/x, elbow, wrist y/x); the rest of
the body holds its neutral pose with PD servos.  Main goal: fingertip–nose
distance at the end, plus half the mean distance over the last 0.5 s (so the
finger should arrive and stay).  Style points, phased in: keep the hand out
of the torso, disturb the held joints little, spend little work, end at rest.
"""
import numpy as np

from gpmotion.task import Task, Term, register_task
from gpmotion.tasks._herman import (ARM, FIGURE, GP_DEFAULTS, VIEW, MAIN_WEIGHT, TERMINALS, goal_scene,
                                    site_at_rest, style_measures, style_terms, tail)

TOUCH = 0.03            # m: "touching"
HOLD = 0.5              # s: the window of the averaged distance


def fingertip_distance(traj, site):
    """Distance [E, F] from the right fingertip to another site (both move)."""
    return np.linalg.norm(traj.site("fingertip_r") - traj.site(site), axis=-1)


@register_task
class HermanTouchNose(Task):
    name = "herman_touch_nose"
    figure = FIGURE
    description = "Herman touches his nose with the right fingertip"
    params = {"seconds": 1.5}
    controlled = ARM
    terminals = TERMINALS
    gp_defaults = GP_DEFAULTS
    view = VIEW
    goal_label = "nose at rest"    # pictures: the scene goal, captioned
    terms = (Term("nose", MAIN_WEIGHT, main=True,
                  doc=f"fingertip–nose distance at the end + 0.5 × its mean over the last {HOLD} s (m)"),
             *style_terms())
    success_threshold = f"fingertip within {TOUCH * 100:.0f} cm of the nose at the end"

    def scene(self):
        # the senses' goal: the nose at the neutral pose (the head is PD-held,
        # so it moves only a little)
        return goal_scene(site_at_rest(self.figure, "nose"))

    def measure(self, traj):
        d = fingertip_distance(traj, "nose")
        out = {"nose": d[:, -1] + 0.5 * d[:, tail(traj, HOLD)].mean(axis=1),
               "nose_end": d[:, -1]}
        out.update(style_measures(traj))
        return out

    def success(self, traj, m):
        return m["nose_end"] < TOUCH

    def picture_events(self, traj, e=0):
        """Filmstrip frames to keep: the first touch."""
        near = fingertip_distance(traj, "nose")[e] < TOUCH
        return [(int(near.argmax()), "first touch")] if near.any() else []

    def describe(self, traj, m):
        d = fingertip_distance(traj, "nose")[0]
        near = d < TOUCH
        first = f"{traj.times[near.argmax()]:.2f} s" if near.any() else "never"
        return [f"fingertip–nose {d[-1] * 100:.1f} cm at the end; first touch {first}",
                f"held joints off neutral by {np.degrees(m['posture'][0]):.1f}° RMS; "
                f"fingertip speed at the end {m['rest'][0] * 100:.1f} cm/s"]
