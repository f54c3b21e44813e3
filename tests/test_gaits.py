"""Gait classifier (gpmotion.gaits) on constructed trajectories, one per class."""
import numpy as np
import pytest

from gpmotion import gaits

STAR = ["head", "hand_l", "hand_r", "foot_l", "foot_r"]
FPS = 50
T = 3.0


def frames(T=T):
    return np.arange(int(T * FPS) + 1) / FPS


def forces(t, down):
    """[F, 5] contact forces: 10 N on the points ``down(i)`` names per frame."""
    f = np.zeros((t.size, len(STAR)))
    for i in range(t.size):
        for name in down(i):
            f[i, STAR.index(name)] = 10.0
    return f


def feat(t, force, pitch, x, z, angles):
    return gaits.features(t, force, STAR, pitch, x, z, angles)


def aperiodic_angles(t, seed=0):
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.normal(0, 0.15, (t.size, 4)), axis=0)


def rolling(t, turns, down):
    """A figure rolling ``turns`` times to the right (+x) with contacts ``down``."""
    pitch = np.pi / 2 - 2 * np.pi * turns * t / t[-1]
    x = 2.0 * t / t[-1]
    return feat(t, forces(t, down), pitch, x, 0.4 + 0 * t, aperiodic_angles(t))


def cartwheel_support(i):
    """Feet, hands, feet, ... in 0.4 s blocks (two alternations per turn at 1.5 turns/3 s)."""
    return ("foot_l", "foot_r") if (i // 20) % 2 == 0 else ("hand_l", "hand_r")


def test_cartwheel():
    t = frames()
    f = rolling(t, 1.2, cartwheel_support)
    assert f.turns == pytest.approx(1.2)
    assert f.switches >= 2
    assert gaits.classify(f) == "cartwheel"


def test_rolling_over_the_head_is_a_tumble_not_a_cartwheel():
    t = frames()
    f = rolling(t, 1.2, lambda i: ("head",) if (i // 20) % 2 else ("foot_l",))
    assert f.switches == 0
    assert gaits.classify(f) == "tumble"


def test_turning_against_the_travel_direction_is_no_cartwheel():
    t = frames()
    f = rolling(t, -1.2, cartwheel_support)          # rolls left while moving right
    assert f.turns == pytest.approx(-1.2)
    assert gaits.classify(f) == "tumble"


def test_less_than_a_full_turn_is_no_rotation():
    t = frames()
    f = rolling(t, 0.9, cartwheel_support)
    assert gaits.classify(f) != "cartwheel" and gaits.classify(f) != "tumble"


def test_hop_needs_two_flight_phases():
    t = frames()
    flying = {*range(30, 40), *range(80, 90)}
    down = lambda i: () if i in flying else ("foot_l", "foot_r")   # noqa: E731
    f = feat(t, forces(t, down), np.pi / 2 + 0 * t, t / 2, 0.4 + 0 * t, aperiodic_angles(t))
    assert f.flights == 2
    assert gaits.classify(f) == "hop"
    one = {*range(30, 40)}
    f1 = feat(t, forces(t, lambda i: () if i in one else ("foot_l",)), np.pi / 2 + 0 * t,
              t / 2, 0.4 + 0 * t, aperiodic_angles(t))
    assert f1.flights == 1 and gaits.classify(f1) == "other"
    # the drop onto the ground at the start is no flight phase
    f0 = feat(t, forces(t, lambda i: () if i < 10 or i in one else ("foot_l",)),
              np.pi / 2 + 0 * t, t / 2, 0.4 + 0 * t, aperiodic_angles(t))
    assert f0.flights == 1


def test_a_one_frame_gap_is_no_flight():
    t = frames()
    down = lambda i: () if i % 25 == 0 and i > 0 else ("foot_l",)   # noqa: E731
    f = feat(t, forces(t, down), np.pi / 2 + 0 * t, t / 2, 0.4 + 0 * t, aperiodic_angles(t))
    assert f.flights == 0


def test_shuffle_keeps_a_foot_down_and_is_aperiodic():
    t = frames()
    down = lambda i: ("foot_l",) if (i // 7) % 2 else ("foot_r", "hand_r")   # noqa: E731
    f = feat(t, forces(t, down), np.pi / 2 + 0.05 * np.sin(t * 3.7 + t ** 2),
             t / 2, 0.4 + 0.01 * t, aperiodic_angles(t))
    assert f.flights == 0 and f.feet_down == 1.0 and f.period is None
    assert gaits.classify(f) == "shuffle"


def test_crawling_on_the_hands_is_not_a_shuffle():
    t = frames()
    down = lambda i: ("hand_l", "head") if i % 10 < 5 else ("hand_r", "foot_l")   # noqa: E731
    f = feat(t, forces(t, down), np.pi / 2 + 0 * t, t / 2, 0.2 + 0 * t, aperiodic_angles(t))
    assert f.feet_down == pytest.approx(0.5, abs=0.02)
    assert gaits.classify(f) == "other"


def test_periodic_shuffle_finds_its_period():
    t = frames()
    per = 0.5
    ph = 2 * np.pi * t / per
    angles = np.column_stack([np.sin(ph + k) for k in range(4)])
    down = lambda i: ("foot_l",) if (i % 25) < 12 else ("foot_r",)   # noqa: E731
    f = feat(t, forces(t, down), np.pi / 2 + 0.1 * np.sin(ph), 0.4 * t, 0.5 + 0.02 * np.cos(ph),
             angles)
    assert f.period == pytest.approx(per)
    assert gaits.classify(f) == "periodic shuffle"
    # the same joint motion while the body drifts in pitch is not periodic
    f2 = feat(t, forces(t, down), np.pi / 2 + 0.6 * t, 0.4 * t, 0.5 + 0.02 * np.cos(ph), angles)
    assert f2.period is None and gaits.classify(f2) == "shuffle"


def test_a_still_pose_sliding_along_is_no_periodic_shuffle():
    t = frames()
    f = feat(t, forces(t, lambda i: ("foot_l", "foot_r")), np.pi / 2 + 0 * t, 0.3 * t,
             0.4 + 0 * t, np.ones((t.size, 4)))
    assert f.period is None and gaits.classify(f) == "shuffle"


def test_no_travel_is_other():
    t = frames()
    f = feat(t, forces(t, lambda i: ("foot_l", "foot_r")), np.pi / 2 + 0 * t, 0.05 * t / T,
             0.4 + 0 * t, aperiodic_angles(t))
    assert gaits.classify(f) == "other"


def test_bad_shapes_are_one_clear_error():
    t = frames()
    with pytest.raises(ValueError, match="contact_force"):
        gaits.features(t, np.zeros((t.size, 3)), STAR, t, t, t, np.zeros((t.size, 4)))


def test_real_trajectory_of_a_standing_starman():
    from gpmotion import load_figure, simulate
    fig = load_figure("starman")
    traj = simulate(fig, 0.5)
    name, f = gaits.gait_of(traj)
    assert name == "other" and abs(f.distance) < 0.05
    assert f.feet_down == 1.0 and f.flights == 0
    assert abs(f.turns) < 0.05


# -- benchmarks/auslander_2d.py: every run resumable -------------------------------------
def _study():
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "auslander_2d.py"
    spec = importlib.util.spec_from_file_location("auslander_2d", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.CONFIGS["tiny"] = ("starman_travel", "bsr-time", {"seconds": 0.5}, {}, ("hop",), "tiny")
    return mod


def test_study_resumes_a_cut_run_to_the_uninterrupted_result(tmp_path, capsys, monkeypatch):
    # run_one sets NUMBA_NUM_THREADS=1 unless set (for its own process); here it must keep
    # numba's value, or every later compile in this process fails ("Cannot set
    # NUMBA_NUM_THREADS to a different value once the threads have been launched")
    import numba
    monkeypatch.setenv("NUMBA_NUM_THREADS", str(numba.config.NUMBA_NUM_THREADS))
    from gpmotion.run import run
    from gpmotion.runconfig import RunConfig
    study = _study()
    whole = study.run_one("tiny", 3, 60, str(tmp_path / "a"))
    # a study killed mid-run leaves a checkpointed run folder; the next call resumes it
    cfg = RunConfig(task="starman_travel", family="bsr-time", seed=3, params={"seconds": 0.5},
                    threads=1, search={"n_working": 10, "n_generations": 5, "reseed_every": 200})
    run(cfg, tmp_path / "b" / "runs" / "tiny-seed3-60", quiet=True, artifacts=False,
        max_generations=2)
    cut = study.run_one("tiny", 3, 60, str(tmp_path / "b"))
    assert cut["resumed"] and not whole["resumed"]
    assert cut["genome"] == whole["genome"] and cut["cost"] == whole["cost"]
    assert cut["evaluations"] == whole["evaluations"] == 60
    # finished runs are read back, not rerun; the table names every cell's budget
    study.run_one("tiny", 4, 40, str(tmp_path / "b"))
    study.main(["--configs", "tiny", "--seeds", "2", "--first-seed", "3", "--budget", "60",
                "--out", str(tmp_path / "b"), "--table-only"])
    out = capsys.readouterr().out
    assert "| tiny | 2 | 60 ×1, 40 ×1 |" in out


def test_study_never_mixes_in_runs_of_other_settings(tmp_path, capsys):
    study = _study()
    study.run_one("tiny", 3, 20, str(tmp_path))
    assert (("tiny", 3, 20) in study.load_results(tmp_path))
    study.CONFIGS["tiny"] = ("starman_travel", "bsr-time", {"seconds": 0.5, "w_rotations": 1.0}, {},
                             ("hop",), "tiny")
    assert study.load_results(tmp_path) == {}          # the stored result is stale: skipped
    assert "other settings" in capsys.readouterr().err
    (tmp_path / "tiny-seed3-20.json").unlink()         # its run folder is refused, not resumed
    with pytest.raises(SystemExit) as e:
        study.main(["--configs", "tiny", "--seeds", "1", "--first-seed", "3", "--budget", "20",
                    "--out", str(tmp_path)])
    assert e.value.code == 2


def test_a_study_file_adds_configurations_that_spawned_workers_run(tmp_path, capsys, monkeypatch):
    """--study: one's own configurations from JSON (here a figure variant), run
    by two spawned workers, which never see the parent's CONFIGS."""
    import json
    import sys
    study = _study()
    monkeypatch.setitem(sys.modules, "auslander_2d", study)     # what the workers unpickle by name
    variant = tmp_path / "short_arms.toml"
    variant.write_text('extends = "starman"\nname = "starman_short_arms"\n'
                       '[[joints]]\nname = "arm_l"\nlimits = [-1.5, 0.3]\n')
    study_file = tmp_path / "study.json"
    study_file.write_text(json.dumps({"mine": ["starman_travel", "bsr-time",
                                               {"seconds": 0.5, "figure": str(variant)}, {},
                                               ["shuffle"], "my short-armed Star-Man"]}))
    out = tmp_path / "out"
    study.main(["--study", str(study_file), "--configs", "mine", "--seeds", "2", "--budget", "20",
                   "--workers", "2", "--out", str(out)])
    assert "| my short-armed Star-Man | 2 | 20 |" in capsys.readouterr().out
    recs = [json.loads(p.read_text()) for p in sorted(out.glob("mine-seed*-20.json"))]
    assert [r["seed"] for r in recs] == [0, 1] and all(r["params"]["figure"] == str(variant) for r in recs)


@pytest.mark.parametrize("text, says", [
    ("{not json", "cannot read"),
    ('{"star-contact": ["starman_travel", "bsr-time", {}, {}, [], "x"]}', "built-in"),
    ('{"a": ["no_such_task", "bsr-time", {}, {}, [], "x"]}', "unknown task"),
    ('{"a": ["starman_travel", "gp", {}, {}, [], "x"]}', "BSR family"),
    ('{"a": ["starman_travel", "bsr-time", {}, {}, ["moonwalk"], "x"]}', "gaits"),
    ('{"a": ["starman_travel", "bsr-time", {}]}', "must be"),
    ("[]", "JSON object"),
])
def test_a_bad_study_file_is_one_line_and_exit_2(tmp_path, capsys, text, says):
    f = tmp_path / "study.json"
    f.write_text(text)
    with pytest.raises(SystemExit) as e:
        _study().main(["--study", str(f), "--configs", "a", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert e.value.code == 2 and len(err) == 1 and says in err[0] and err[0].startswith("auslander_2d: ")


def test_study_leaves_numba_threads_alone(tmp_path):
    """run_one in a process with running numba threads must not change NUMBA_NUM_THREADS:
    numba re-reads it before compiling, and every later compile in the process fails."""
    import os
    before = os.environ.get("NUMBA_NUM_THREADS")
    _study().run_one("tiny", 5, 20, str(tmp_path))
    assert os.environ.get("NUMBA_NUM_THREADS") == before


def test_every_study_configuration_builds_its_task_and_ground():
    """Each configuration's task, family options and figure variant are valid;
    a ``two:`` variant is its figure on a ground where two points touch at most."""
    import gpmotion
    from gpmotion.families import make_family
    study = _study()
    limited = set()
    for name, (task_name, fam, params, options, _, _) in study.CONFIGS.items():
        resolved = study._resolved(params)
        task = gpmotion.get_task(task_name, **resolved)
        make_family(fam, task, **options)
        fig = params.get("figure", ":")
        variant, base = fig.split(":") if ":" in fig else ("", fig)
        shipped = gpmotion.load_figure(base or study.FIGURE_OF[task_name]).ground
        want = gpmotion.make_scene(**{**shipped, **study.GROUND_VARIANTS.get(variant, {})})
        scene = task.scene()
        assert scene.max_contacts == want.max_contacts and scene.c_ground == want.c_ground, name
        assert scene.mu == want.mu, name
        limited |= {name} if scene.max_contacts == 2 else set()
    assert {"star-contact-two", "beryl-periodic-two", "star-sense-contact-two"} <= limited
    # every core configuration has its twin on the damped ground
    for name in study.CORE:
        for variant, c in study.DAMPINGS.items():
            task_name, _, params, _, expected, _ = study.CONFIGS[f"{name}-{variant}"]
            assert expected == study.CONFIGS[name][4]
            assert gpmotion.get_task(task_name, **study._resolved(params)).scene().c_ground == c
    # the headline set is the core set on the reproduction's figures, the default
    assert study.HEADLINE == [f"{n}-auslander" for n in study.CORE]
    for name in study.CORE:
        task_name, fam, params, options, expected, _ = study.CONFIGS[f"{name}-auslander"]
        core = study.CONFIGS[name]
        assert (fam, expected) == (core[1], core[4])
        assert params["figure"] == study.AUSLANDER_FIGURE[task_name]
        assert gpmotion.get_task(task_name, **params).scene().c_ground == study.DAMPED_C
        rest = {k: v for k, v in params.items() if k != "figure"}
        extra_params, extra_options, label = study.AUSLANDER_TUNING.get(name, ({}, {}, core[5]))
        assert rest == {**core[2], **extra_params}
        assert options == {**core[3], **extra_options}
        assert study.CONFIGS[f"{name}-auslander"][5].startswith(label)
    assert study.CONFIGS["star-height-auslander"][2]["w_max_height"] == 0.5
    assert study.CONFIGS["star-rotations-auslander"][2]["w_rotations"] == 4.0
    # the cyclic gaits repeat a 1 s script; the cartwheel and the tumble do not repeat
    for name, t_per in (("star-contact", 1.0), ("star-height", 1.0), ("star-rotations", None),
                        ("beryl-tumble", None), ("beryl-periodic", 0.5)):
        assert study.CONFIGS[f"{name}-auslander"][3].get("t_per") == t_per
    # the t_per = T versions stay, differing from the headline in t_per only
    for name in ("star-contact", "star-height"):
        head, aperiodic = study.CONFIGS[f"{name}-auslander"], study.CONFIGS[f"{name}-auslander-aperiodic"]
        assert head[2] == aperiodic[2] and aperiodic[3] == {} and head[4] == aperiodic[4]


def test_the_reproduction_figures_differ_from_theirs_only_as_documented():
    """starman_auslander: five equal 0.5 m rods and c_ground 200; beryl_auslander: c_ground 200."""
    import gpmotion
    for name, base in (("starman_auslander", "starman"), ("beryl_auslander", "beryl")):
        fig, ref = gpmotion.load_figure(name), gpmotion.load_figure(base)
        assert fig.ground == {**ref.ground, "c_ground": 200.0}
        assert fig.actuator_names == ref.actuator_names and fig.contact_names == ref.contact_names
        assert fig.total_mass == ref.total_mass
    star = gpmotion.load_figure("starman_auslander")
    head = gpmotion.load_figure("starman").contact_names.index("head")
    assert star.model.cp_pos[head].tolist() == [0.5, 0.0]
    assert gpmotion.load_figure("starman").model.cp_pos[head].tolist() == [0.3, 0.0]
