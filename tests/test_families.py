"""Controller families are one registered protocol: the public contract holds
for every registered family, and the harness builds a run's search without
naming a family (a family registered here, in a test, runs and compares)."""
import ast
import json
from pathlib import Path

import numpy as np
import pytest

import gpmotion
from gpmotion.check import check_family
from gpmotion.cli import main
from gpmotion.controllers import schedule
from gpmotion.families import Family, family_names, make_family, register_family, unregister_family
from gpmotion.search.serial import SerialSearch, serial_generations

ROOT = Path(gpmotion.__file__).resolve().parent
TINY = ["--param", "seconds=0.3", "--quiet", "--no-artifacts"]


@pytest.mark.parametrize("name", family_names())
def test_every_registered_family_keeps_the_contract(name):
    check_family(name)


class PoseFamily(Family):
    """A test family: one constant target pose per controlled joint, hill-climbed."""
    name = "test-pose"
    description = "a constant pose (a test family)"
    search_class = SerialSearch
    cli = {"--generations": "n_generations", "--working": "n_working"}

    def __init__(self, task, step=0.2, **options):
        super().__init__(task, step=float(step), **options)
        self.actuators = task.controlled_actuators()
        self.limits = task.figure.actuator_limits()[self.actuators]

    def random(self, rng):
        lo, hi = self.limits.T
        return lo + rng.random(len(self.actuators)) * (hi - lo)

    def mutate(self, genome, rng, extra=None):
        lo, hi = self.limits.T
        return np.clip(genome + rng.normal(0, self.options["step"], genome.shape), lo, hi)

    def encode(self, genomes):
        neutral = self.task.figure.model.neutral
        rows = []
        for g in genomes:
            pose = neutral.copy()
            pose[self.actuators] = g
            rows.append(schedule.constant(pose))
        return schedule.stack(rows)

    def to_json(self, genome):
        return {"kind": "test-pose", "pose": [float(x) for x in genome]}

    def from_json(self, data):
        if not isinstance(data, dict) or data.get("kind") != "test-pose" \
                or not isinstance(data.get("pose"), list) or len(data["pose"]) != len(self.actuators):
            raise ValueError("not a test-pose controller")
        return np.array(data["pose"], dtype=np.float64)

    def budget_settings(self, budget, population=None):
        return {"n_working": 4, "n_generations": serial_generations(self.task, budget, 4)}


@pytest.fixture
def pose_family():
    register_family(PoseFamily)
    try:
        yield PoseFamily
    finally:
        unregister_family(PoseFamily.name)


def test_a_family_registered_outside_the_package_runs_compares_and_replays(pose_family, tmp_path,
                                                                           capsys):
    check_family(pose_family)                          # the public check holds a user's family too
    out = tmp_path / "run"
    assert main(["run", "lamp_hop", "--controller", "test-pose", "--generations", "3",
                 "--working", "4", "--out", str(out), *TINY]) == 0
    best = json.loads((out / "best.json").read_text())
    assert best["family"] == "test-pose" and best["genome"]["kind"] == "test-pose"
    assert main(["replay", str(out)]) == 0
    assert main(["resume", str(out), "--extend-generations", "2", "--quiet"]) == 0
    assert main(["compare", "lamp_hop", "--controllers", "test-pose", "--seeds", "1", "--budget",
                 "30", "--param", "seconds=0.3", "--out", str(tmp_path / "cmp"), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["run", "lamp_hop", "--controller", "test-pose", "--population", "5",
                 "--out", str(tmp_path / "no"), *TINY]) == 2
    assert "--population does not apply to --controller test-pose" in capsys.readouterr().err
    main(["list", "controllers"])
    assert "test-pose" in capsys.readouterr().out


def test_unregistered_family_is_gone(pose_family):
    unregister_family(pose_family.name)
    assert "test-pose" not in family_names()
    with pytest.raises(ValueError, match="unknown controller family 'test-pose'"):
        make_family("test-pose", gpmotion.get_task("lamp_hop"))
    register_family(pose_family)                       # the fixture unregisters it again


def test_a_second_family_under_a_taken_name_names_both_files(tmp_path):
    src = tmp_path / "other_gp.py"
    src.write_text("from gpmotion.families import Family, register_family\n"
                   "@register_family\nclass Other(Family):\n    name = 'gp'\n")
    import importlib.util
    import sys
    spec = importlib.util.spec_from_file_location("other_gp", src)
    sys.modules["other_gp"] = module = importlib.util.module_from_spec(spec)
    try:
        with pytest.raises(ValueError, match=r"registered twice.*families/gp\.py.*other_gp\.py"):
            spec.loader.exec_module(module)
    finally:
        del sys.modules["other_gp"]
    assert make_family("gp", gpmotion.get_task("lamp_hop")).__class__.__name__ == "GPFamily"


def _family_name_literals(path: Path, names: set) -> list:
    tree = ast.parse(path.read_text())
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.FunctionDef, ast.ClassDef)) and n.body
            and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    return [(path.relative_to(ROOT).as_posix(), n.lineno) for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and n.value in names and id(n) not in docs]


def test_no_code_outside_a_family_names_a_family():
    """The dispatch is the registry: no string literal equal to a family's name
    outside gpmotion/families (bench's "gp" is its GP-interpreter workload)."""
    names = set(family_names())
    found = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("families/") or rel == "bench.py":
            continue
        found += _family_name_literals(path, names)
    assert not found, found
