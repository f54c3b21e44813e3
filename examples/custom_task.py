"""A new task in one small file: the lamp stretches its head as high as it can.

Drop a file like the class below into a folder, name it in the folder's
manifest ``gpmotion-plugin.toml`` (``modules = ["custom_task"]``) and pass
`--plugins FOLDER` to any gpmotion command; `gpmotion.check_task` runs the
same contract checks the built-in tasks pass.  Its id is ``lamp_reach-v1``
(``version = 2`` publishes a changed score under a new id).

This folder is such a plugin folder (its manifest names this file only):
``gpmotion run lamp_reach --plugins examples``.  A run this script makes
registers the task in its own process, so reading it back needs the folder
too: ``gpmotion replay runs/example-lamp-reach --plugins examples``.
"""
import numpy as np

import gpmotion
from gpmotion import Task, Term, register_task


@register_task
class LampReach(Task):
    name = "lamp_reach"
    figure = "lamp"
    description = "raise the head as high as possible and hold it there"
    params = {"seconds": 2.0}
    terms = (Term("low", 1.0, main=True, doc="1 m minus the head height at the end"),
             Term("wobble", 0.2, phase=(0.3, 0.7), doc="head speed over the last half"))

    def measure(self, traj):
        head = traj.site("head_tip")
        half = head.shape[1] // 2
        speed = np.linalg.norm(np.diff(head[:, half:], axis=1), axis=-1).sum(axis=1) / self.seconds
        return {"low": 1.0 - head[:, -1, 1], "wobble": speed}


if __name__ == "__main__":
    gpmotion.check_task("lamp_reach")
    gpmotion.run(gpmotion.RunConfig(task="lamp_reach", search={"population": 100, "generations": 10}),
                 "runs/example-lamp-reach", force=True)
