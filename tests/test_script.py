"""The composite-motion script language: parser errors and scores computed by hand."""
import numpy as np
import pytest

from tests.figures_for_tests import box
from gpmotion import Trajectory, compile_spec, make_scene
from gpmotion.compose import script as S

TABLE4 = """\
# Auslander et al. 1995, Table 4 (durations in seconds)
phase cartwheel = Δcm_x × (Δtime ≟ 0.4)
phase jump      = max_t{min_i{y_i(t)}} × (Δtime ≟ 0.3)
phase shuffle   = Δcm_x × (Δtime ≟ 0.3)
total = (1.0 + cartwheel) × (1.0 + jump) × (1.0 + shuffle)
"""
TABLE4_ASCII = """
phase cartwheel = dcm_x * (dtime ~= 0.4)
phase jump = max_t(min_i(y_i)) * (dtime ~= 0.3); phase shuffle = dcm_x * (dtime ~= 0.3)
total = (1 + cartwheel) * (1 + jump) * (1 + shuffle)
"""
FRAME = 0.1          # s between frames (dt 0.01 × record_every 10)


def box_traj(x, z, theta=None, force=None, diverged=None):
    """A box Trajectory whose centre of mass and root follow x, z [E, F] (no simulation)."""
    fig = compile_spec(box())
    x, z = np.atleast_2d(x).astype(float), np.atleast_2d(z).astype(float)
    E, F = x.shape
    theta = np.zeros((E, F)) if theta is None else np.atleast_2d(theta)
    q = np.stack([x, z, theta], axis=-1)                # planar root: (x, z, θ)
    com = np.stack([x, z, np.zeros_like(x), np.zeros_like(x)], axis=-1)
    force = np.zeros((E, F, 2)) if force is None else np.asarray(force, float)
    zeros = np.zeros((E, F))
    return Trajectory(figure=fig, scene=make_scene(goal=(2.0, 0.0)), dt=0.01, record_every=10,
                      times=np.arange(F) * FRAME, q=q, qd=np.zeros_like(q), com=com,
                      contact_force=force, pole_hit=zeros, impact=zeros, energy=zeros,
                      targets=np.zeros((E, F, 0)), senses=None,
                      diverged=np.zeros(E, bool) if diverged is None else np.asarray(diverged),
                      diverged_step=np.full(E, -1))


def test_table4_by_hand():
    F = 11
    f = np.arange(F)
    x = np.stack([0.5 * f * FRAME, 1.0 * f * FRAME])          # com x: 0.5 m/s and 1 m/s
    z = np.zeros((2, F))
    z[:, 5] = 0.25                                            # a hop at frame 5 (both episodes)
    z[1, 8] = 0.6                                             # episode 1 also hops at frame 8 (in its shuffle)
    traj = box_traj(x, z)
    bounds = np.array([[0, 4, 7, 10], [0, 3, 7, 10]])
    out = S.evaluate(S.parse(TABLE4), traj, bounds)
    # episode 0: phases 0.4 s, 0.3 s, 0.3 s, all on time
    cart0, jump0, shuf0 = 0.5 * 0.4, 0.25, 0.5 * 0.3
    # episode 1: cartwheel 0.3 s (≟ 0.4 → 1 − 0.1/0.4), jump 0.4 s (≟ 0.3 → 1 − 0.1/0.4)
    cart1, jump1, shuf1 = 1.0 * 0.3 * 0.75, 0.25 * 0.75, 1.0 * 0.3
    np.testing.assert_allclose(out["cartwheel"], [cart0, cart1])
    np.testing.assert_allclose(out["jump"], [jump0, jump1])
    np.testing.assert_allclose(out["shuffle"], [shuf0, shuf1])
    np.testing.assert_allclose(out["total"], [(1 + cart0) * (1 + jump0) * (1 + shuf0),
                                              (1 + cart1) * (1 + jump1) * (1 + shuf1)])
    ascii_out = S.evaluate(S.parse(TABLE4_ASCII), traj, bounds)
    np.testing.assert_array_equal(ascii_out["total"], out["total"])


def test_windows_include_both_switch_frames():
    z = np.zeros((1, 6))
    z[0, 2] = 0.3                       # the switch frame itself
    traj = box_traj(np.zeros((1, 6)), z)
    s = S.parse("phase a = max_t(min_i(y_i))\nphase b = max_t(cm_z)\nphase c = first(t) + last(t)\n"
                "total = a + 10 * b + 100 * c")
    out = S.evaluate(s, traj, [[0, 2, 2, 5]])
    assert out["a"][0] == pytest.approx(0.3) and out["b"][0] == pytest.approx(0.3)
    assert out["c"][0] == pytest.approx(0.0 + 3 * FRAME)      # t counts from the window's start


def test_macros_are_evaluated_in_the_window_that_uses_them():
    x = np.arange(7.0)[None] ** 2                       # cm_x = 0, 1, 4, 9, ...
    traj = box_traj(x, np.zeros((1, 7)))
    s = S.parse("gain = delta(cm_x)\nphase a = gain\nphase b = gain\ntotal = gain - a - b")
    out = S.evaluate(s, traj, [[0, 2, 6]])
    assert out["a"][0] == 4 and out["b"][0] == 36 - 4
    assert out["total"][0] == 36 - 4 - 32


def test_rotations_contact_distance_and_counts():
    F = 9
    theta = np.linspace(0.0, 2 * np.pi * 1.5, F)[None]     # 1.5 turns over the motion
    x = np.zeros((1, F))
    x[0, 4:] = np.arange(5) * 0.1                         # slides 0.4 m in frames 4..8
    force = np.zeros((1, F, 2))
    force[0, 4:, 0] = 10.0                                # only the left corner touches, frames 4..8
    traj = box_traj(x, np.zeros((1, F)), theta=theta * 0, force=force)
    traj_rot = box_traj(x, np.zeros((1, F)), theta=theta, force=force)
    s = S.parse("phase a = rotations\nphase b = contact_distance + 10 * sum_t(airborne) + 100 * max_t(contacts)\n"
                "total = a + b")
    out = S.evaluate(s, traj_rot, [[0, 4, 8]])
    assert out["a"][0] == pytest.approx(1.5 * 4 / 8)
    out = S.evaluate(s, traj, [[0, 4, 8]])
    # left corner x = box x − 0.2 (θ = 0): slid 0.4 m; frames 4..8 never airborne; one point touches
    assert out["b"][0] == pytest.approx(0.4 + 0 + 100)
    out = S.evaluate(s, traj, [[0, 5, 8]])                # phase b from frame 5: 0.3 m slid
    assert out["b"][0] == pytest.approx(0.3 + 0 + 100)
    out = S.evaluate(s, traj, [[0, 2, 8]])                # frames 2, 3 airborne
    assert out["b"][0] == pytest.approx(0.4 + 20 + 100)


@pytest.mark.parametrize("expr, value", [
    ("2 ^ 3 - -1", 9.0), ("-2 ^ 2", -4.0), ("7 / 2 * 2", 7.0), ("1 - 2 - 3", -4.0),
    ("(3 ~= 4) + (0 ~= 0)", 0.75 + 1.0), ("(3 ≟ -3)", 0.0), ("near(1, 1.5, 2)", 0.75),
    ("(1 < 2) + (2 <= 2) + (3 > 4) + (4 >= 5)", 2.0), ("abs(-3) + sqrt(16) + min(2, 5) + max(2, 5)", 14.0),
    ("clip(7, 0, 5) + exp(0)", 6.0), ("goal_x + goal_z", 2.0), ("1e1 + .5", 10.5),
])
def test_arithmetic(expr, value):
    traj = box_traj(np.zeros((1, 3)), np.zeros((1, 3)))
    out = S.evaluate(S.parse(f"phase a = {expr}\ntotal = a"), traj, [[0, 2]])
    assert out["total"][0] == pytest.approx(value)


def test_bad_totals_are_worst():
    traj = box_traj(np.zeros((2, 3)), np.zeros((2, 3)), diverged=[False, True])
    out = S.evaluate(S.parse("phase a = 1\ntotal = a"), traj, [[0, 2], [0, 2]])
    assert out["total"].tolist() == [1.0, -np.inf]
    out = S.evaluate(S.parse("phase a = sqrt(-1)\ntotal = a"), traj, [[0, 2], [0, 2]])
    assert out["total"].tolist() == [-np.inf, -np.inf]


@pytest.mark.parametrize("text, where, words", [
    ("phase a = dcm_x\ntotal = a +", "2:12", "unexpected end of line"),
    ("phase a = dcm_x\ntotal = a $ 2", "2:11", "unexpected character '$'"),
    ("phase a = foo\ntotal = a", "1:11", "unknown name 'foo'"),
    ("phase a = cm_x\ntotal = a", "1:11", "must be a number"),
    ("phase a = max_t(y_i)\ntotal = a", "1:17", "needs signal"),
    ("phase a = min_i(cm_x)\ntotal = a", "1:17", "needs points"),
    ("phase a = max_t(cm_x, 2)\ntotal = a", "1:11", "takes 1 argument"),
    ("phase a = dcm_x\nphase a = 1\ntotal = a", "2:7", "already defined"),
    ("phase dcm_x = 1\ntotal = 1", "1:7", "already a measure"),
    ("phase a = total\ntotal = a", "1:11", "unknown name 'total'"),
    ("phase a = 1\ntotal = b\nb = a", "2:9", "unknown name 'b'"),
    ("phase a = 1 ~= 2 ~= 3\ntotal = a", "1:18", "unexpected '~='"),
    ("phase a = y_i(2)\ntotal = a", "1:11", "write y_i or y_i(t)"),
    ("phase a = last(site_x(cm_x))\ntotal = a", "1:23", "quoted name"),
    ('phase a = __import__("os")\ntotal = a', "1:11", "unknown function"),
    ("phase a = 1", "1:1", "needs a line `total"),
    ("phase total = 1", "1:7", "'total' is the score, not a phase"),
    ("total = 1", "1:1", "declares no phase"),
    ("phase a = " + "-" * 300 + "1" + "\ntotal = a", "1:", "nested too deeply"),
])
def test_errors_point_at_line_and_column(text, where, words):
    with pytest.raises(S.ScriptError) as e:
        S.parse(text)
    assert str(e.value).startswith(where) and words in str(e.value), str(e.value)
    assert isinstance(e.value, ValueError)


def test_load_names_the_file(tmp_path):
    p = tmp_path / "s.motion"
    p.write_text("phase a = 1\ntotal = a +\n")
    with pytest.raises(S.ScriptError, match=r"s\.motion:2:12: unexpected end"):
        S.load(p)
    p.write_bytes(b"\xff\xfe")
    with pytest.raises(S.ScriptError, match="cannot read script"):
        S.load(p)


def test_bind_checks_site_names():
    fig = compile_spec(box())
    s = S.parse('phase a = last(site_x("hub"))\ntotal = a')
    with pytest.raises(S.ScriptError, match="1:16: box has no site 'hub'"):
        S.bind(s, fig)


def test_bounds_are_checked():
    traj = box_traj(np.zeros((1, 3)), np.zeros((1, 3)))
    s = S.parse("phase a = 1\nphase b = 1\ntotal = a")
    with pytest.raises(ValueError, match="bounds must be"):
        S.evaluate(s, traj, [[0, 2]])
    with pytest.raises(ValueError, match="non-decreasing"):
        S.evaluate(s, traj, [[0, 2, 1]])


def test_measures_on_a_simulated_lamp_match_numpy():
    """Each measure is what its doc says, on a real trajectory (the lamp settling, goal 0.4 m ahead)."""
    from gpmotion import load_figure, simulate
    fig = load_figure("lamp")
    traj = simulate(fig, 0.6, scene=make_scene(goal=(0.4, 0.0)), record_every=10)
    s = S.parse('phase a = last(goal_distance_of("base_centre"))\nphase b = sum_t(energy) + max_t(impact)\n'
                'total = mean_t(speed) + 10 * last(site_z("head_tip")) + max_t(time) + last(goal_distance)')
    S.bind(s, fig)
    F = traj.q.shape[1]
    out = S.evaluate(s, traj, [[0, 20, F - 1]])
    base = traj.site("base_centre")[0, 20]                  # phase a: frames 0..20
    assert out["a"][0] == pytest.approx(np.hypot(base[0] - 0.4, base[1]))
    assert out["b"][0] == pytest.approx(traj.energy[0, 20:].sum() + traj.impact[0, 20:].max())
    speed = np.linalg.norm(traj.com[0, :, 2:4], axis=-1).mean()
    com_goal = np.hypot(traj.com[0, -1, 0] - 0.4, traj.com[0, -1, 1])
    assert out["total"][0] == pytest.approx(speed + 10 * traj.site("head_tip")[0, -1, 1] + traj.times[-1] + com_goal)
