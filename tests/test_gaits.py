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


# -- the auslander-2d study (gpmotion/studies/auslander-2d/spec.toml) ----------------------
def test_the_auslander_study_runs_the_tuned_configurations_on_the_reproduction_figures():
    """Each configuration builds; all run on the reproduction figures (the damped
    ground); the tuned settings are the documented ones; the cyclic gaits repeat
    a 1 s script and the t_per = T versions differ from them in t_per only."""
    import gpmotion
    from gpmotion.study import SHIPPED
    from gpmotion.study.driver import check
    from gpmotion.study.spec import load
    spec = load(SHIPPED / "auslander-2d" / "spec.toml")
    check(spec)                                        # every task, family and search builds
    conf = {n: c.stages[0] for n, c in spec.configurations.items()}
    figure = {"starman_travel": "starman_auslander", "beryl_travel": "beryl_auslander"}
    for name, st in conf.items():
        assert st.params["figure"] == figure[st.task], name
        assert gpmotion.get_task(st.task, **st.params).scene().c_ground == 200.0
        assert st.search == {"n_working": 10, "n_generations": 3999, "reseed_every": 200}
    assert conf["star-rotations"].params["w_rotations"] == 4.0
    assert conf["star-height"].params["w_max_height"] == 0.5
    for name, t_per in (("star-contact", 1.0), ("star-height", 1.0), ("star-rotations", None),
                        ("beryl-tumble", None), ("beryl-periodic", 0.5)):
        assert conf[name].options.get("t_per") == t_per, name
    for name in ("star-contact", "star-height"):
        head, aperiodic = conf[name], conf[f"{name}-aperiodic"]
        assert head.params == aperiodic.params and aperiodic.options == {}
        assert spec.configurations[name].expect == spec.configurations[f"{name}-aperiodic"].expect
    assert set(spec.tune_seeds).isdisjoint(spec.report_seeds)


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


# -- strict definitions: posture, which limbs carry the weight, landings -----------------
def strict(t, force, pitch, x, z, angles):
    m = gaits.strict_measures(t, force, STAR, pitch, x, z, angles)
    return gaits.classify_strict(m), m


def test_a_shuffle_on_a_hand_and_a_foot_is_loose_shuffle_but_strictly_other():
    t = frames()
    down = lambda i: ("foot_l",) if (i // 7) % 2 else ("foot_r", "hand_r")   # noqa: E731
    args = (t, forces(t, down), np.pi / 2 + 0.05 * np.sin(t * 3.7 + t ** 2), t / 2,
            0.4 + 0.01 * t, aperiodic_angles(t))
    assert gaits.classify(feat(*args)) == "shuffle"
    label, m = strict(*args)
    assert m["hands_share"] == pytest.approx(1 / 3, abs=0.05) and label == "other"
    feet_only = forces(t, lambda i: ("foot_l",) if (i // 7) % 2 else ("foot_r",))
    assert strict(t, feet_only, *args[2:])[0] == "shuffle"


def test_a_shuffle_lying_pitched_over_is_strictly_other():
    t = frames()
    down = lambda i: ("foot_l",) if (i // 7) % 2 else ("foot_r",)   # noqa: E731
    label, m = strict(t, forces(t, down), np.pi / 2 - np.radians(80) + 0 * t, t / 2,
                      0.4 + 0 * t, aperiodic_angles(t))
    assert m["upright"] == 0.0 and m["max_tilt_deg"] == pytest.approx(80)
    assert label == "other"
    # sunk to a fifth of the standing height: not upright either
    z = np.where(t < 0.2, 0.4, 0.08)
    assert strict(t, forces(t, down), np.pi / 2 + 0 * t, t / 2, z, aperiodic_angles(t))[0] == "other"


def test_a_hop_lands_on_the_feet():
    t = frames()
    flying = {*range(30, 40), *range(80, 90)}
    on_feet = lambda i: () if i in flying else ("foot_l", "foot_r")   # noqa: E731
    args = (np.pi / 2 + 0 * t, t / 2, 0.4 + 0 * t, aperiodic_angles(t))
    label, m = strict(t, forces(t, on_feet), *args)
    assert (m["landings"], m["landed_on_feet"], label) == (2, 2, "hop")
    on_hands = lambda i: () if i in flying else ("hand_l",) if i in (40, 90) else ("foot_l",)  # noqa: E731
    label, m = strict(t, forces(t, on_hands), *args)
    assert (m["landings"], m["landed_on_feet"], label) == (2, 0, "other")
    assert gaits.classify(feat(t, forces(t, on_hands), *args)) == "hop"


def test_three_quarters_of_a_turn_is_no_hop():
    t = frames()
    flying = {*range(30, 40), *range(80, 90)}
    down = lambda i: () if i in flying else ("foot_l",)   # noqa: E731
    pitch = np.pi / 2 - 2 * np.pi * 0.75 * t / t[-1]
    assert gaits.classify(feat(t, forces(t, down), pitch, t / 2, 0.4 + 0 * t, aperiodic_angles(t))) == "hop"
    assert strict(t, forces(t, down), pitch, t / 2, 0.4 + 0 * t, aperiodic_angles(t))[0] == "other"


def test_a_cartwheel_turns_on_hands_and_feet_not_over_the_head():
    t = frames()
    pitch = np.pi / 2 - 2 * np.pi * 1.2 * t / t[-1]
    args = (pitch, 2.0 * t / t[-1], 0.4 + 0 * t, aperiodic_angles(t))
    assert strict(t, forces(t, cartwheel_support), *args)[0] == "cartwheel"
    over_head = lambda i: ("head", "hand_l") if (i // 20) % 2 else ("foot_l",)   # noqa: E731
    label, m = strict(t, forces(t, over_head), *args)
    assert m["other_share"] > 0.3 and label == "tumble"
    airborne = lambda i: () if i % 10 < 6 else cartwheel_support(i)   # noqa: E731
    assert strict(t, forces(t, airborne), *args)[0] == "tumble"


def test_judge_keeps_measures_that_name_either_label():
    from gpmotion import load_figure, simulate
    traj = simulate(load_figure("starman"), 0.5)
    label, m = gaits.judge(traj)
    assert label == "other" and gaits.relabel(m, "loose") == gaits.gait_of(traj)[0]
    assert m["upright"] == 1.0 and m["feet_share"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="definition"):
        gaits.judge(traj, definition="lenient")
