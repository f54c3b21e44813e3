"""The facts a run and a replay print count what a person counts: a lamp's hops are
its flights, the ones the filmstrip marks, not every 10 ms a contact lets go."""
import json

import pytest

from gpmotion.render3d import motion_events
from gpmotion.replay import load_controller, replay_genome

from .golden_runs import GOLDEN


@pytest.mark.parametrize("name", ["lamp_hop-gp", "lamp_limbo-gp"])
def test_hops_are_the_flights_the_filmstrip_marks(name, tmp_path):
    best = json.loads((GOLDEN / f"{name}.json").read_text())["best"]
    path = tmp_path / "best.json"
    path.write_text(json.dumps({**best, "plugins": [], "version": 1}))
    task, family, actuation, genome, _ = load_controller(path)
    traj, _, measures, _ = replay_genome(task, family, actuation, genome)
    [hops] = [f for f in task.describe(traj, measures) if f.startswith("hops: ")]
    takeoffs = sum(label == "take-off" for _, label in motion_events(traj))
    assert hops == f"hops: {takeoffs}"
    cf = traj.contact_force[0]
    chatter = int(((cf.max(axis=1) == 0)[1:] & (cf.max(axis=1) > 0)[:-1]).sum())
    if name == "lamp_limbo-gp":
        assert takeoffs < chatter, "short losses of contact are not hops"


def test_the_docs_and_examples_use_no_deprecated_task_attribute():
    """task.fig and task.p warn that they are deprecated: the docs show task.figure
    and task.params."""
    import re
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    files = [f for f in root.glob("docs/**/*.md") if "notes" not in f.parts]   # notes: history
    files += [*root.glob("examples/*.py"), root / "README.md"]
    used = [f"{f.relative_to(root)}: {m.group(0)}" for f in files
            for m in re.finditer(r"\btask\.(fig|p)\b(?!\w)", f.read_text(encoding="utf-8"))]
    assert not used, used
