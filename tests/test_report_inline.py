"""Jupyter's inline view (``_repr_html_``): a Trajectory, a run's result and a
study's result show the report's player with their frames."""
import base64
import html
import json
import re

import numpy as np

from gpmotion.replay import replay_genome
from gpmotion.run import RunConfig, run
from gpmotion.task import get_task


def _page_data(frag: str) -> dict:
    """The page inside the iframe's srcdoc, and the data it plays."""
    m = re.fullmatch(r'<iframe style="[^"]*" srcdoc="([^"]*)"></iframe>', frag)
    assert m, frag[:200]
    doc = html.unescape(m.group(1))
    assert "class Player" in doc and "THREE.WebGLRenderer" in doc      # the report's player
    data = re.search(r'<script type="application/json" id="gpm-data">(.*?)</script>', doc, re.S)
    return json.loads(data.group(1))


def _positions(motion) -> np.ndarray:
    q = motion["segs"]
    v = np.frombuffer(base64.b64decode(q["q"]), dtype="<i2").astype(float)
    return q["lo"] + (v + 32767) * q["step"]


def test_a_trajectory_shows_its_frames(tmp_path):
    from gpmotion.families import make_family
    task = get_task("lamp_hop")
    genome, _, _ = run(RunConfig(task="lamp_hop", family="gp", seed=0,
                                 search={"population": 6, "generations": 1}),
                       tmp_path / "r", quiet=True, artifacts=False, checkpoint_every=0)
    traj = replay_genome(task, make_family("gp", task), "pd", genome)[0]
    data = _page_data(traj._repr_html_())
    motion = data["panels"][0]["motion"]
    seg = traj.segments()[0]
    assert motion["n"] == len(traj.times) == seg.shape[0]
    xz = _positions(motion).reshape(seg.shape[0], seg.shape[1], 2, 3)[..., [0, 2]]
    assert np.abs(xz - seg).max() <= motion["segs"]["step"]           # the frames, 16-bit


def test_a_run_and_a_study_show_their_report(tmp_path):
    from gpmotion.study.driver import run_study
    from gpmotion.study.spec import parse
    result = run(RunConfig(task="lamp_hop", family="gp", seed=1,
                           search={"population": 6, "generations": 2}),
                 tmp_path / "r", quiet=True, artifacts=False, checkpoint_every=0)
    genome, cost, rd = result                                    # still the (genome, cost, dir)
    data = _page_data(result._repr_html_())
    assert data["kind"] == "run" and data["panels"][0]["cost"] == cost
    assert data["panels"][0]["film"]["entries"]                  # the film of the generations
    from gpmotion.compare import comparison_spec
    spec = parse(comparison_spec(get_task("lamp_hop", seconds=0.5), ["gp"], 2, 20, "pd",
                                 {"seconds": 0.5}, 6, None))
    rows = run_study(spec, tmp_path / "s", spec.report_seeds, quiet=True)
    assert [r["seed"] for r in rows] == [0, 1]
    data = _page_data(rows._repr_html_())
    assert data["kind"] == "study" and len(data["panels"]) == 1          # one per configuration
    best = min(rows, key=lambda r: r["cost"])
    panel = data["panels"][0]
    assert panel["cost"] == best["cost"] and f"(seed {best['seed']})" in panel["name"]
    assert panel["motion"]["n"] > 1 and panel["film"]["entries"]       # the kept run folder
    assert data["table"]["rows"][0][1] == 2                              # both seeds counted
