"""render.py on a synthetic 3-segment swinging chain: files are valid images
of the expected kind and size, NaN frames are tolerated, bad input is a
clear ValueError, and a failed render leaves no file behind."""
import os

import numpy as np
import pytest
from PIL import Image, ImageSequence

from gpmotion import render
from tests.image_checks import no_temp_files, open_image

RADII = np.array([0.06, 0.05, 0.04])


def swinging_chain(n_frames=60, duration=2.0):
    """float[F, 3, 2, 2]: a three-link chain swinging while it drifts right."""
    t = np.linspace(0.0, duration, n_frames)
    swing = 0.8 * np.sin(2 * np.pi * t / 1.5)
    p = np.stack([0.5 * t, 0.3 + 0.1 * np.abs(np.sin(3 * t))], -1)
    segs = []
    for k in range(3):
        a = np.pi / 2 + swing * (k + 1) * 0.5
        q = p + 0.4 * np.stack([np.cos(a), np.sin(a)], -1)
        segs.append(np.stack([p, q], 1))
        p = q
    return np.stack(segs, 1), t


def test_capsule_is_as_thick_as_its_radius():
    seg = np.array([[[0.0, 0.0], [1.0, 0.0]], [[2.0, 2.0], [2.0, 2.0]]])
    poly = render.capsules(seg, np.array([0.1, 0.3]))
    assert poly.shape == (2, 2 * render._ARC, 2)
    np.testing.assert_allclose(poly[0, :, 1].max(), 0.1, atol=1e-12)
    np.testing.assert_allclose(poly[0, :, 0].min(), -0.1, atol=1e-12)
    np.testing.assert_allclose(poly[0, :, 0].max(), 1.1, atol=1e-12)
    np.testing.assert_allclose(np.hypot(*(poly[1] - 2.0).T), 0.3)  # a disc


@pytest.mark.parametrize("strip", [True, False])
def test_filmstrip_writes_png(tmp_path, strip):
    seg, t = swinging_chain()
    out = tmp_path / "filmstrip.png"
    render.filmstrip(out, seg, RADII, t, poles=[[0.6, 1.2, 0.05]], goal=(1.0, 0.0),
                     title="swing", labels=["start"] + [None] * (len(t) - 1),
                     strip=strip)
    im, _ = open_image(out)
    assert im.format == "PNG"
    assert im.size[0] >= 7 * 120 and im.size[1] > 100
    assert no_temp_files(tmp_path)


def test_filmstrip_draws_later_frames_darker(tmp_path):
    seg, t = swinging_chain()
    seg[:, :, :, 0] += np.linspace(0, 20, len(t))[:, None, None]  # far apart
    out = tmp_path / "f.png"
    render.filmstrip(out, seg, RADII, t, n_frames=3, strip=False, ground_z=None)
    with Image.open(out) as im:
        rgb = np.asarray(im.convert("RGB"), dtype=float)
    body = rgb[..., 2] - rgb[..., 0] > 40          # the blue figure pixels
    light = rgb.sum(-1)
    cols = rgb.shape[1]
    mean_light = [light[:, i * cols // 3:(i + 1) * cols // 3][body[:, i * cols // 3:(i + 1) * cols // 3]].mean()
                  for i in range(3)]
    assert mean_light[0] > mean_light[1] > mean_light[2]


def test_filmstrip_skips_nan_frames(tmp_path):
    seg, t = swinging_chain()
    seg[10:30] = np.nan
    seg[-1, 1, 0, 0] = np.inf
    render.filmstrip(tmp_path / "f.png", seg, RADII, t, n_frames=8)
    assert open_image(tmp_path / "f.png")[0].format == "PNG"


@pytest.mark.parametrize("bad", [
    np.zeros((0, 3, 2, 2)),          # no frames
    np.zeros((5, 0, 2, 2)),          # no segments
    np.zeros((5, 3, 2)),             # wrong rank
    np.full((5, 3, 2, 2), np.nan),   # nothing finite
])
def test_filmstrip_and_animate_reject_bad_input(tmp_path, bad):
    t = np.arange(len(bad), dtype=float)
    radii = np.full(bad.shape[1] if bad.ndim > 1 else 0, 0.05)
    for fn, name in [(render.filmstrip, "f.png"), (render.animate, "m.gif")]:
        with pytest.raises(ValueError):
            fn(tmp_path / name, bad, radii, t)
    assert list(tmp_path.iterdir()) == []


def test_mismatched_radii_or_times_rejected(tmp_path):
    seg, t = swinging_chain()
    with pytest.raises(ValueError, match="radii"):
        render.filmstrip(tmp_path / "f.png", seg, RADII[:2], t)
    with pytest.raises(ValueError, match="times"):
        render.filmstrip(tmp_path / "f.png", seg, RADII, t[:-1])


def gif_durations(path):
    """Per-frame display durations (ms) of a GIF, as a browser reads them."""
    with Image.open(path) as im:
        return [f.info["duration"] for f in ImageSequence.Iterator(im)]


def test_animate_writes_gif_within_frame_budget(tmp_path):
    seg, t = swinging_chain(n_frames=50)
    seg[5:9] = np.nan
    out = tmp_path / "motion.gif"
    n = render.animate(out, seg, RADII, t, poles=[[0.6, 1.2, 0.05]], goal=(1.0, 0.0),
                       fps=20, max_frames=12, title="swing", dpi=40)
    with Image.open(out) as im:
        assert im.format == "GIF"
        assert 2 <= im.n_frames <= 12 and n <= 12
        assert im.size[0] > 40 * 6 - 2 and im.size[1] > 50
    d = gif_durations(out)
    assert all(v % 10 == 0 and v >= 50 for v in d)          # ≤ 20 frames/s, whole centiseconds
    assert abs(sum(d) - 2000) <= max(d)                      # still the motion's 2 s
    assert no_temp_files(tmp_path)


@pytest.mark.parametrize("seconds, step, fps", [(3.0, 0.01, 10), (2.0, 0.013, 10)])
def test_gif_plays_in_real_time(tmp_path, seconds, step, fps):
    """The old GIFs showed every ≤200th frame at 40 ms whatever the recording
    rate: a 3 s lamp hop recorded at 100 frames/s played at 0.38× real time."""
    seg, t = swinging_chain(n_frames=int(round(seconds / step)) + 1, duration=seconds)
    render.animate(tmp_path / "m.gif", seg, RADII, t, fps=fps, dpi=20)
    d = gif_durations(tmp_path / "m.gif")
    stride = max(d)
    assert all(v % 10 == 0 and v >= 20 for v in d)
    # frames span the episode; the last one shows for one stride
    assert 1000 * seconds <= sum(d) <= 1000 * seconds + stride + 10


def test_slow_motion_gif_says_its_speed(tmp_path):
    seg, t = swinging_chain(n_frames=61, duration=0.6)
    render.animate(tmp_path / "real.gif", seg, RADII, t, fps=10, dpi=40)
    render.animate(tmp_path / "slow.gif", seg, RADII, t, speed=0.5, fps=10, dpi=40)
    assert 1200 <= sum(gif_durations(tmp_path / "slow.gif")) <= 1200 + 100
    assert 600 <= sum(gif_durations(tmp_path / "real.gif")) <= 600 + 100
    with Image.open(tmp_path / "real.gif") as a, Image.open(tmp_path / "slow.gif") as b:
        ra, rb = (np.asarray(im.convert("RGB"), int) for im in (a, b))
    differ = np.argwhere(np.abs(ra - rb).sum(-1) > 100)       # not palette jitter
    h, w = ra.shape[:2]
    # the first frames differ only where the clock and the speed are written
    assert len(differ) and differ[:, 0].max() < 0.25 * h and differ[:, 1].max() < 0.5 * w
    assert render.speed_text(0.5) == "0.5× real time" and render.speed_text(1) == "real time"
    with pytest.raises(ValueError, match="speed"):
        render.animate(tmp_path / "x.gif", seg, RADII, t, speed=0)


def test_animate_short_motion_keeps_all_frames(tmp_path):
    seg, t = swinging_chain(n_frames=4)
    n = render.animate(tmp_path / "m.gif", seg, RADII, t, max_frames=200)
    with Image.open(tmp_path / "m.gif") as im:
        assert n == 4 and im.n_frames == 4


def test_failed_render_keeps_old_file(tmp_path, monkeypatch):
    out = tmp_path / "f.png"
    out.write_bytes(b"old picture")
    seg, t = swinging_chain()

    def boom(*a, **k):
        raise RuntimeError("disk full")
    monkeypatch.setattr(render.Figure, "savefig", boom)
    with pytest.raises(RuntimeError):
        render.filmstrip(out, seg, RADII, t)
    assert out.read_bytes() == b"old picture"
    assert no_temp_files(tmp_path)


def test_curve_and_band(tmp_path):
    g = np.arange(30)
    best = 10 / (1 + g)
    best[3] = np.nan
    best[4] = np.inf
    render.curve(tmp_path / "curve.png", g, best, median=best * 2, title="lamp hop")
    assert open_image(tmp_path / "curve.png")[0].format == "PNG"
    series = {"gp": (g, best * 0.8, best, best * 1.2),
              "bsr": (g, g * 0 + 1.0, g * 0 + 2.0, g * 0 + 3.0)}
    render.curves_band(tmp_path / "band.png", series, "evaluations", "score")
    assert open_image(tmp_path / "band.png")[0].format == "PNG"


def test_curve_rejects_empty_or_mismatched(tmp_path):
    with pytest.raises(ValueError):
        render.curve(tmp_path / "c.png", [], [])
    with pytest.raises(ValueError):
        render.curve(tmp_path / "c.png", [1, 2, 3], [1.0, 2.0])
    with pytest.raises(ValueError):
        render.curve(tmp_path / "c.png", [1, 2], [np.nan, np.inf])
    with pytest.raises(ValueError):
        render.curves_band(tmp_path / "b.png", {})
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------- what the pictures show

@pytest.fixture
def drawn(monkeypatch):
    """The matplotlib Figures that render would have saved, by file name."""
    figs = {}
    monkeypatch.setattr(render, "_save_png", lambda fig, path, dpi: figs.__setitem__(
        os.path.basename(str(path)), fig))
    return figs


def texts(fig):
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def stars(fig):
    return [ln for ax in fig.axes for ln in ax.lines if ln.get_marker() == "*"]


def lamp_hop_trajectory():
    """A real hop of the lamp: neutral 0.3 s, then the joints snap out."""
    import gpmotion
    fig = gpmotion.load_figure("lamp")
    n = fig.model.neutral
    push = n + np.array([-1.0, 1.0, -1.0])
    return gpmotion.simulate(fig, 1.0, targets=(np.array([0, 0.3, 0.31, 1.0]),
                                                np.array([n, n, push, push])))


def test_filmstrip_of_a_hop_shows_its_apex(tmp_path):
    """The old strip took 10 evenly spaced frames and could skip the flight."""
    from gpmotion.render3d import motion_events
    traj = lamp_hop_trajectory()
    air = traj.contact_force[0].max(axis=1) == 0
    air[0] = False
    z = traj.com[0][:, 1]
    apex = int(np.argmax(np.where(air, z, -np.inf)))
    assert z[apex] > z[0] + 0.05                              # it really flies
    events = motion_events(traj)
    assert (apex, "apex") in events
    frames = render.filmstrip(tmp_path / "f.png", traj.segments()[0], traj.figure.model.seg_r,
                              traj.times, events=events, n_frames=6)
    assert apex in frames and len(frames) == 6


def test_render_any_passes_motion_events(monkeypatch, tmp_path):
    from gpmotion import render3d
    seen = {}
    monkeypatch.setattr(render, "filmstrip", lambda *a, **kw: seen.update(kw))
    render3d.render_any(lamp_hop_trajectory(), tmp_path / "f.png")
    assert "apex" in [lab for _, lab in seen["events"]]


def test_passive_render_draws_no_goal(drawn, tmp_path):
    """`gpmotion render --figure lamp` drew the scene's placeholder goal (0, 0) as a star."""
    from gpmotion import cli
    assert cli.main(["render", "--figure", "lamp", "--seconds", "0.05",
                     "-o", str(tmp_path / "p.png")]) == 0
    assert stars(drawn["p.png"]) == []


def test_a_task_goal_and_limbo_pole_are_drawn_and_labelled(drawn, tmp_path):
    import gpmotion
    from gpmotion import render3d
    task = gpmotion.get_task("lamp_limbo", pole_height=0.40)
    traj = gpmotion.simulate(task.figure, 0.05, scene=task.scene())
    render3d.render_any(traj, tmp_path / "limbo.png", task=task)
    fig = drawn["limbo.png"]
    assert len(stars(fig)) == 1 + 10 * 0 + len(fig.axes) - 1   # big one + one per small multiple
    words = texts(fig)
    assert "target" in words
    assert "pole: underside 0.40 m up" in words                  # not an unlabelled dot
    # no task, no goal; the pole (part of the scene) stays
    render3d.render_any(traj, tmp_path / "scene.png")
    assert stars(drawn["scene.png"]) == [] and "target" not in texts(drawn["scene.png"])
    assert "pole: underside 0.40 m up" in texts(drawn["scene.png"])


def test_pole_label_without_ground():
    assert render.pole_text((0.3, 0.43, 0.01), None) == "pole: underside z = 0.42 m"


# ------------------------------------------------------------- run curves

def log_rows(n=21, final=True):
    rows = []
    for g in range(n):
        p = g / (n - 1)
        rows.append({"generation": str(g), "evaluations": str(100 * (g + 1)), "progress": f"{p:.6f}",
                     "best_so_far": str(0.01 + 0.07 * p), "gen_median": str(0.5 + 2 * (g == 8)),
                     **({"best_final": str(0.2 - 0.1 * p)} if final else {})})
    return rows


def test_run_curve_marks_phase_ins_and_says_which_weights(drawn, tmp_path):
    """curve.png said "lower is better" over a rising best, with no phase-in marks."""
    import gpmotion
    task = gpmotion.get_task("lamp_hop")
    render.run_curve(tmp_path / "curve.png", log_rows(final=False), task, title="lamp_hop (gp)")
    fig = drawn["curve.png"]
    main, strip = fig.axes
    assert "current weights" in main.get_ylabel() and "lower is better" in main.get_ylabel()
    # one bar per ramp window, captioned with the terms that ramp in it
    windows = {(t.phase, t.name) for t in task.terms if t.phase[1] > t.phase[0] and t.weight}
    caps = " ".join(texts(fig))
    assert all(name in caps for _, name in windows)
    assert len(strip.patches) == len({w for w, _ in windows})
    # the shaded windows sit where progress crosses each ramp: fell ramps over 0.1..0.4
    spans = sorted(tuple(np.round(p.get_x(), 3) for p in [bar]) for bar in strip.patches)
    assert spans[0] == (300.0,)                                   # progress 0.1 → 300 evaluations
    labels = [ln.get_label() for ln in main.lines]
    assert labels == ["best so far (current weights)", "generation median (current weights)"]


def test_run_curve_plots_best_under_final_weights_when_logged(drawn, tmp_path):
    import gpmotion
    render.run_curve(tmp_path / "curve.png", log_rows(final=True), gpmotion.get_task("lamp_limbo"))
    fig = drawn["curve.png"]
    main = fig.axes[0]
    assert "best final (final weights)" in [ln.get_label() for ln in main.lines]
    assert "pole_height (curriculum)" in " ".join(texts(fig))
    lo, hi = main.get_ylim()
    assert lo < 0.01 and hi >= 0.2 and hi < 2.0                # the best curves whole, not the median spike


def test_run_curve_of_a_task_without_phases_or_progress(drawn, tmp_path):
    import gpmotion
    rows = [{k: v for k, v in r.items() if k != "progress"} for r in log_rows(final=False)]
    render.run_curve(tmp_path / "c.png", rows, gpmotion.get_task("lamp_hop"))
    assert len(drawn["c.png"].axes) == 1
    with pytest.raises(ValueError, match="no rows"):
        render.run_curve(tmp_path / "c.png", [], None)
    with pytest.raises(ValueError, match="best_so_far"):
        render.run_curve(tmp_path / "c.png", [{"generation": "0"}], None)
