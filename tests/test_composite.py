"""Composite controllers: the state carries across switches exactly; the file is safe."""
import json

import numpy as np
import pytest

from gpmotion import get_task, load_figure, make_scene, rollout
from gpmotion.compose import composite as C
from gpmotion.controllers import schedule
from gpmotion.families import make_family
from gpmotion.records import FormatError, atomic_write_json, envelope

# stateless sense feedback (no `t`): the same controller split anywhere is the same motion
GP_TREES = [["mul", 2.0, "sin", "pitch"], ["add", "angle_arm_l", 0.3], ["sub", 0.5, "com_vz"], ["mul", "vx", -1.0]]


def write_controller(path, family="gp", task="starman_travel", seconds=1.0, seed=0, **params):
    t = get_task(task, seconds=seconds, **params)
    f = make_family(family, t)
    if family == "gp":
        genome = f.from_json({"kind": "gp", "pset": f.info.hash, "trees": GP_TREES})
    else:
        genome = f.random(np.random.default_rng(seed))
    rec = {"task": t.name, "params": dict(t.params), "family": family, "options": dict(f.options),
           "actuation": f.default_actuation, "genome": f.to_json(genome)}
    atomic_write_json(path, envelope("best", rec))
    return path


@pytest.fixture(scope="module")
def ctrl_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("ctrl")
    write_controller(d / "gp.json")
    write_controller(d / "time.json", family="bsr-time", seed=3)
    write_controller(d / "sense.json", family="bsr-sense", seed=5)
    write_controller(d / "lamp.json", family="bsr-time", task="lamp_hop")
    return d


def test_rollout_continues_exactly_from_its_end_state():
    """(q, qd, contact_end) is the whole state: two halves make the single run, bit for bit."""
    fig = load_figure("starman")
    rng = np.random.default_rng(0)
    ctrl = schedule.stack([schedule.constant(fig.model.neutral + 0.5 * rng.standard_normal(fig.n_act))
                           for _ in range(3)])
    sc = make_scene()
    full = rollout(fig, sc, ctrl, n_steps=1500, record_every=10)
    a = rollout(fig, sc, ctrl, n_steps=700, record_every=10)
    assert np.any(a.contact_end[..., 1] == 1)                 # some points are touching at the split
    b = rollout(fig, sc, ctrl, n_steps=800, record_every=10, q0=a.q[:, -1], qd0=a.qd[:, -1],
                contact0=a.contact_end)
    np.testing.assert_array_equal(np.concatenate([a.q, b.q[:, 1:]], axis=1), full.q)
    np.testing.assert_array_equal(b.contact_end, full.contact_end)
    reset = rollout(fig, sc, ctrl, n_steps=800, record_every=10, q0=a.q[:, -1], qd0=a.qd[:, -1])
    assert np.abs(reset.q[:, -1] - full.q[:, -1]).max() > 1e-6  # the anchors matter


def test_each_episode_may_run_its_own_length():
    fig = load_figure("starman")
    rng = np.random.default_rng(1)
    ctrls = [schedule.constant(fig.model.neutral + 0.5 * rng.standard_normal(fig.n_act)) for _ in range(3)]
    steps = np.array([400, 1000, 700])
    tr = rollout(fig, make_scene(), schedule.stack(ctrls), n_steps=steps, record_every=10)
    assert tr.q.shape[1] == 101 and not tr.diverged.any()
    for e, n in enumerate(steps):
        one = rollout(fig, make_scene(), ctrls[e], n_steps=int(n), record_every=10)
        np.testing.assert_array_equal(tr.q[e, :n // 10 + 1], one.q[0])
        np.testing.assert_array_equal(tr.contact_end[e], one.contact_end[0])
        assert np.all(tr.q[e, n // 10:] == one.q[0, -1]) and not tr.qd[e, n // 10 + 1:].any()
    with pytest.raises(ValueError, match="n_steps"):
        rollout(fig, make_scene(), schedule.stack(ctrls), n_steps=[10, 20])
    with pytest.raises(ValueError, match="n_steps"):
        rollout(fig, make_scene(), schedule.stack(ctrls), n_steps=[10, 0, 20])


def test_contact0_is_checked_and_not_modified():
    fig = load_figure("starman")
    ctrl = schedule.constant(fig.model.neutral)
    c0 = np.zeros((len(fig.contact_names), 2))
    with pytest.raises(ValueError, match="contact0"):
        rollout(fig, make_scene(), ctrl, n_steps=10, contact0=np.zeros((2, 2)))
    tr = rollout(fig, make_scene(), ctrl, n_steps=300, contact0=c0)
    assert np.all(c0 == 0) and tr.contact_end[0, :, 1].max() == 1


def test_one_controller_split_anywhere_is_the_single_run(ctrl_dir):
    comp = C.from_controllers([ctrl_dir / "gp.json", ctrl_dir / "gp.json"], switches=[0.6], seconds=2.0)
    switches = [[0.6], [1.0], [0.0], [2.0], [1.37]]               # 1.37 s rounds to frame 68 (20 ms frames)
    traj, bounds = C.run(comp, switches)
    assert bounds[:, 1].tolist() == [30, 50, 0, 100, 68]
    single = rollout(comp.figure, comp.scene, comp.parts[0].batch(1), n_steps=2000, dt=comp.dt,
                     record_every=comp.record_every, actuation="pd", default_tau=comp.parts[0].family.default_tau)
    for ch in ("q", "qd", "com", "contact_force", "impact", "energy", "targets"):
        np.testing.assert_array_equal(getattr(traj, ch), np.broadcast_to(getattr(single, ch), getattr(traj, ch).shape), ch)
    assert traj.contact_force.max() > 0 and not traj.diverged.any()


@pytest.mark.parametrize("second", ["time.json", "sense.json"])
def test_each_phase_starts_fresh_from_the_switch_state(ctrl_dir, second):
    """A time-based controller's clock starts at its switch, a sense-based one's rule memory is fresh:
    phase 2 is a new rollout from phase 1's end state."""
    comp = C.from_controllers([ctrl_dir / "gp.json", ctrl_dir / second], switches=[0.4], seconds=1.0)
    traj, bounds = C.run(comp)
    s = bounds[0, 1]
    assert s == 20
    gp_part, time_part = comp.parts
    first = rollout(comp.figure, comp.scene, gp_part.batch(1), n_steps=400, dt=comp.dt, record_every=20,
                    actuation=gp_part.actuation, default_tau=gp_part.family.default_tau)
    second = rollout(comp.figure, comp.scene, time_part.batch(1), n_steps=600, dt=comp.dt, record_every=20,
                     q0=first.q[:, -1], qd0=first.qd[:, -1], contact0=first.contact_end,
                     actuation=time_part.actuation, default_tau=time_part.family.default_tau)
    np.testing.assert_array_equal(traj.q[:, :s + 1], first.q)
    np.testing.assert_array_equal(traj.q[:, s:], second.q)
    np.testing.assert_array_equal(traj.targets[:, s + 1:], second.targets[:, 1:])
    assert time_part.actuation == "kinematic" and gp_part.actuation == "pd"


def test_file_round_trip(ctrl_dir, tmp_path, monkeypatch):
    monkeypatch.chdir(ctrl_dir)                 # controllers named relative to the working directory
    comp = C.from_controllers(["gp.json", "time.json"], switches=[0.4], seconds=1.0, names=["spin", "kick"])
    (tmp_path / "sub").mkdir()
    C.save(tmp_path / "sub" / "c.json", comp)   # ... saved elsewhere: paths relative to the file
    monkeypatch.chdir(tmp_path)
    back = C.load(tmp_path / "sub" / "c.json")
    C.save(tmp_path / "c.json", back)
    back = C.load(tmp_path / "c.json")
    assert [p.name for p in back.parts] == ["spin", "kick"] and back.switches.tolist() == [0.4]
    assert back.seconds == 1.0
    obj = json.loads((tmp_path / "c.json").read_text())
    assert obj["format"] == "gpmotion-composite" and obj["version"] == 1
    # relative controller paths are relative to the composite file
    rel = dict(obj, phases=[{"name": "a", "controller": "gp.json"}], switches=[])
    (ctrl_dir / "rel.json").write_text(json.dumps(rel))
    assert C.load(ctrl_dir / "rel.json").parts[0].task.name == "starman_travel"


def test_default_timing_is_each_controllers_own_duration(ctrl_dir):
    comp = C.from_controllers([ctrl_dir / "gp.json", ctrl_dir / "gp.json", ctrl_dir / "gp.json"])
    assert comp.seconds == 3.0 and comp.switches.tolist() == [1.0, 2.0]


@pytest.mark.parametrize("change, words", [
    ({"format": "gpmotion-best"}, "expected format 'gpmotion-composite'"),
    ({"version": 2}, "unsupported gpmotion-composite version"),
    ({"extra": 1}, "unknown key(s) extra"),
    ({"phases": []}, "'phases' must be a list"),
    ({"phases": [{"controller": 3}]}, "phases[0] must be"),
    ({"phases": [{"controller": "gp.json", "code": "x"}]}, "phases[0] must be"),
    ({"phases": [{"name": "a b", "controller": "gp.json"}]}, "phases[0].name must be a name"),
    ({"phases": [{"controller": "missing.json"}]}, "cannot read"),
    ({"switches": [0.5, 0.6]}, "2 phases need 1 switch time(s)"),
    ({"switches": [1.5]}, "non-decreasing within [0, 1.0]"),
    ({"switches": ["0.5"]}, "'switches' must be a list of numbers"),
    ({"seconds": True}, "'seconds' must be a number"),
    ({"seconds": 0.001}, "seconds must be in [0.02, 600]"),
    ({"scene": {"gravity": -1}}, "scene: gravity must be"),
    ({"scene": {"import": 1}}, "scene: unknown setting(s) import"),
    ({"phases": [{"controller": "gp.json"}, {"controller": "lamp.json"}]}, "one composite, one figure"),
])
def test_bad_files_fail_in_one_line(ctrl_dir, tmp_path, change, words):
    obj = {"format": "gpmotion-composite", "version": 1, "seconds": 1.0, "switches": [0.5],
           "phases": [{"controller": str(ctrl_dir / "gp.json")}, {"controller": str(ctrl_dir / "time.json")}]}
    obj.update(change)
    for ph in obj["phases"]:
        if isinstance(ph, dict) and isinstance(ph.get("controller"), str) and not ph["controller"].startswith("/"):
            ph["controller"] = str(ctrl_dir / ph["controller"])
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(obj))
    with pytest.raises((C.CompositeError, FormatError)) as e:
        C.load(p)
    msg = str(e.value)
    assert "\n" not in msg and words in msg and str(p) in msg, msg
    assert isinstance(e.value, ValueError)


def test_bad_switch_arrays(ctrl_dir):
    comp = C.from_controllers([ctrl_dir / "gp.json", ctrl_dir / "gp.json"])
    with pytest.raises(C.CompositeError, match="need 1 finite switch"):
        comp.bounds([[0.5, 0.7]])
    with pytest.raises(C.CompositeError, match="need 1 finite switch"):
        comp.bounds([[np.nan]])
    # out-of-range and unsorted switch times are clipped and sorted, not refused (a search mutates them)
    assert comp.bounds([[-1.0], [9.0]]).tolist() == [[0, 0, 100], [0, 100, 100]]


def test_shared_histories_are_simulated_once_and_exactly(ctrl_dir, monkeypatch):
    """Episodes with the same start and switches share phases; per-episode starts are respected."""
    comp = C.from_controllers([ctrl_dir / "gp.json", ctrl_dir / "time.json"], switches=[0.4], seconds=1.0)
    q0 = np.tile(comp.figure.q_default, (4, 1))
    q0[1, 2] += 0.2                                        # episode 1 starts tilted
    switches = [[0.4], [0.4], [0.4], [0.6]]
    calls = []
    real = C.rollout
    monkeypatch.setattr(C, "rollout", lambda *a, **kw: calls.append(kw["q0"].shape[0]) or real(*a, **kw))
    traj, _ = C.run(comp, switches, q0=q0)
    # starts {nominal, tilted} × switch frames {20, 30} → 3 distinct histories: one batch of 3 per phase
    assert calls == [3, 3]
    monkeypatch.setattr(C, "rollout", real)
    for e in range(4):
        one, _ = C.run(comp, [switches[e]], q0=q0[e])
        np.testing.assert_array_equal(traj.q[e], one.q[0])
        np.testing.assert_array_equal(traj.energy[e], one.energy[0])
    assert not np.array_equal(traj.q[0], traj.q[1]) and np.array_equal(traj.q[0], traj.q[2])


@pytest.mark.slow
def test_3d_rollout_continues_exactly_from_its_end_state():
    """The same for a 3-D figure (free root, 2-D friction anchors)."""
    fig = load_figure("herman_standing")
    ctrl = schedule.constant(fig.model.neutral)
    sc = make_scene()
    full = rollout(fig, sc, ctrl, n_steps=600, record_every=10)
    a = rollout(fig, sc, ctrl, n_steps=300, record_every=10)
    assert a.contact_end.shape[-1] == 3 and np.any(a.contact_end[..., 2] == 1)
    b = rollout(fig, sc, ctrl, n_steps=300, record_every=10, q0=a.q[:, -1], qd0=a.qd[:, -1],
                contact0=a.contact_end)
    np.testing.assert_array_equal(np.concatenate([a.q, b.q[:, 1:]], axis=1), full.q)


# ---------------------------------------------------------------- per-phase scenes; replay/render/export

POLE = [[0.3, 0.25, 0.02]]


def _phased(ctrl_dir, tmp_path, pole_phase=1):
    phases = [{"name": "a", "controller": str(ctrl_dir / "time.json"), "scene": {"goal": [0.5, 0.0]}},
              {"name": "b", "controller": str(ctrl_dir / "gp.json")}]
    phases[pole_phase]["scene"] = {"poles": POLE, "goal": [1.5, 0.0]}
    path = tmp_path / f"phased{pole_phase}.json"
    atomic_write_json(path, envelope("composite", {"seconds": 2.0, "phases": phases, "switches": [1.0]}))
    return path


def test_each_phase_runs_in_its_own_scene(ctrl_dir, tmp_path):
    from gpmotion.compose import script as S
    comp = C.load(_phased(ctrl_dir, tmp_path))
    assert len(comp.scenes[0].poles) == 0 and len(comp.scenes[1].poles) == 1
    assert comp.scenes[0].goal[0] == 0.5 and comp.scenes[1].goal[0] == 1.5
    # the pole is in the world only in its phase: phase 1 is the same motion as with no pole at all
    no_pole = C.assemble(comp.parts, comp.switches, comp.seconds, None, [{"goal": [0.5, 0.0]}, {}])
    a, bounds = C.run(comp)
    b, _ = C.run(no_pole)
    s1 = bounds[0, 1]
    np.testing.assert_array_equal(a.q[:, :s1 + 1], b.q[:, :s1 + 1])
    # goals are the phase's: the script's goal_x reads each phase's scene
    s = S.parse("phase a = goal_x\nphase b = goal_x\ntotal = a + b\n")
    v = S.evaluate(s, a, bounds, comp.scenes)
    assert v["a"][0] == 0.5 and v["b"][0] == 1.5 and v["total"][0] == 2.0
    # the file keeps each phase's scene
    C.save(tmp_path / "again.json", comp)
    again = C.load(tmp_path / "again.json")
    assert [len(sc.poles) for sc in again.scenes] == [0, 1]
    assert C.to_obj(again)["phases"][1]["scene"]["poles"] == POLE


def test_a_phase_without_a_scene_gets_its_own_tasks(ctrl_dir):
    comp = C.from_controllers([ctrl_dir / "time.json", ctrl_dir / "lamp.json"][:1] * 2)
    task_scene = comp.parts[0].task.scene_at(1.0)
    assert all(np.array_equal(sc.goal, task_scene.goal) for sc in comp.scenes)


def test_replay_render_and_export_take_a_composite(ctrl_dir, tmp_path, capsys):
    from gpmotion.cli import main
    path = _phased(ctrl_dir, tmp_path)
    assert main(["replay", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [p["phase"] for p in out["phases"]] == ["a", "b"] and out["switches"] == [1.0]
    assert out["phases"][0]["end_s"] == out["phases"][1]["start_s"] == 1.0
    assert main(["export", str(path), "--bvh", str(tmp_path / "m.bvh")]) == 0
    frames = int(next(line for line in (tmp_path / "m.bvh").read_text().splitlines()
                      if line.startswith("Frames:")).split()[1])
    assert frames == C.load(path).n_frames
    assert main(["render", str(path), "-o", str(tmp_path / "m.png"), "--gif", str(tmp_path / "m.gif")]) == 0
    from PIL import Image
    with Image.open(tmp_path / "m.png") as im:
        assert im.height > 1.5 * im.width / 3           # one strip per phase, stacked
    with Image.open(tmp_path / "m.gif") as im:
        assert im.n_frames > 2
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "gpmotion-composite", "version": 1, "phases": []}))
    capsys.readouterr()
    assert main(["replay", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "phases" in err[0]


def test_the_example_cartwheel_is_of_the_current_figure_and_turns_whole():
    """The old example carried the legs' pre-widening range [-1.2, 0.4] in its genome (a
    time-based genome keeps the ranges it was drawn in) and could only tip 0.80 of a turn."""
    from pathlib import Path

    from gpmotion.replay import load_controller, replay_genome
    path = Path(__file__).resolve().parents[1] / "examples" / "composite" / "cartwheel.json"
    task, fam, act, genome, _ = load_controller(path)
    m = task.figure.model
    assert fam.to_json(genome)["limits"] == [[float(m.lo[i]), float(m.hi[i])] for i in m.act_dof]
    _, _, measures, _ = replay_genome(task, fam, act, genome)
    assert measures["rotations"][0] >= 1.0
