"""render3d.py: 3-D filmstrips and GIFs are valid images, NaN frames are
tolerated, bad input is a clear ValueError (and leaves no file), and
render_any draws planar and 3-D trajectories."""
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageSequence

import gpmotion
from gpmotion import render3d
from gpmotion.figures import load_spec, planar_spec_to_3d

RADII = np.array([0.06, 0.05, 0.04])
LAMP = Path(gpmotion.__file__).parent / "figures" / "lamp.toml"


def walking_chain(n_frames=40, duration=2.0):
    """float[F, 3, 2, 3]: a three-link chain swinging in 3-D while it travels along x and y."""
    t = np.linspace(0.0, duration, n_frames)
    swing = 0.8 * np.sin(2 * np.pi * t / 1.5)
    p = np.stack([0.5 * t, 0.2 * t, 0.3 + 0.1 * np.abs(np.sin(3 * t))], -1)
    segs = []
    for k in range(3):
        a = np.pi / 2 + swing * (k + 1) * 0.5
        yaw = 0.5 * k * t
        q = p + 0.4 * np.stack([np.cos(a) * np.cos(yaw), np.cos(a) * np.sin(yaw), np.sin(a)], -1)
        segs.append(np.stack([p, q], 1))
        p = q
    return np.stack(segs, 1), t


def open_image(path):
    assert path.exists() and path.stat().st_size > 0
    with Image.open(path) as im:
        im.load()
        return im, getattr(im, "n_frames", 1)


def no_temp_files(directory):
    return [p.name for p in directory.iterdir() if p.name.endswith(".tmp")] == []


@pytest.mark.parametrize("strip", [True, False])
def test_filmstrip3d_writes_png(tmp_path, strip):
    seg, t = walking_chain()
    out = tmp_path / "strip.png"
    render3d.filmstrip3d(out, seg, RADII, t, goal=(1.0, 0.2, 0.0), targets=[[0.5, 0.5, 0.8]],
                         poles=[[0.6, 1.2, 0.05]], title="walk", strip=strip)
    im, n = open_image(out)
    assert im.format == "PNG" and n == 1
    assert im.size[0] >= 800 and im.size[1] > 300
    assert no_temp_files(tmp_path)


def test_animate3d_writes_gif_with_at_most_max_frames(tmp_path):
    seg, t = walking_chain(n_frames=40)
    out = tmp_path / "walk.gif"
    written = render3d.animate3d(out, seg, RADII, t, max_frames=12, fps=20, title="walk")
    im, n = open_image(out)
    assert im.format == "GIF"
    assert n == written <= 12 and written >= 2
    # a short motion: every frame
    out2 = tmp_path / "short.gif"
    assert render3d.animate3d(out2, seg[:5], RADII, t[:5]) == 5
    assert open_image(out2)[1] == 5
    assert no_temp_files(tmp_path)


def test_nan_frames_are_skipped(tmp_path):
    seg, t = walking_chain(n_frames=30)
    seg[10:, 1] = np.nan                       # a diverged tail
    seg[3, 0, 0, 2] = np.inf
    render3d.filmstrip3d(tmp_path / "nan.png", seg, RADII, t)
    n = render3d.animate3d(tmp_path / "nan.gif", seg, RADII, t, max_frames=100)
    assert n == 9                              # frames 0..9 less frame 3
    assert open_image(tmp_path / "nan.gif")[1] == 9


def test_bad_input_is_a_value_error_and_writes_nothing(tmp_path):
    seg, t = walking_chain(n_frames=10)
    out = tmp_path / "x.png"
    cases = [
        (np.zeros((0, 3, 2, 3)), RADII, np.zeros(0)),           # empty
        (seg[..., :2], RADII, t),                                  # planar shape
        (np.full_like(seg, np.nan), RADII, t),                     # nothing finite
        (seg, RADII[:2], t),                                       # radii count
        (seg, RADII, t[:-1]),                                      # times count
    ]
    for s, r, tt in cases:
        with pytest.raises(ValueError):
            render3d.filmstrip3d(out, s, r, tt)
        with pytest.raises(ValueError):
            render3d.animate3d(tmp_path / "x.gif", s, r, tt)
    with pytest.raises(ValueError, match="fps"):
        render3d.animate3d(tmp_path / "x.gif", seg, RADII, t, fps=0)
    with pytest.raises(ValueError):
        render3d.filmstrip3d(out, seg, RADII, t, n_frames=0)
    assert list(tmp_path.iterdir()) == []


def test_a_still_figure_and_a_figure_without_ground_render(tmp_path):
    seg, t = walking_chain(n_frames=5)
    still = np.repeat(seg[:1], 5, axis=0)
    render3d.filmstrip3d(tmp_path / "still.png", still, RADII, t, ground_z=None)
    assert open_image(tmp_path / "still.png")[0].format == "PNG"


@pytest.mark.parametrize("figure", ["lamp", "lamp3d"])
def test_render_any_draws_planar_and_3d_trajectories(tmp_path, figure):
    spec = "lamp" if figure == "lamp" else planar_spec_to_3d(load_spec(LAMP), root="free")
    fig = gpmotion.load_figure(spec)
    traj = gpmotion.simulate(fig, 0.5, record_every=25)
    assert traj.is3d == (figure == "lamp3d")
    render3d.render_any(traj, tmp_path / "f.png", tmp_path / "m.gif", title=figure)
    assert open_image(tmp_path / "f.png")[0].format == "PNG"
    im, n = open_image(tmp_path / "m.gif")
    assert im.format == "GIF" and 2 <= n <= traj.q.shape[1]
    with Image.open(tmp_path / "m.gif") as im:                # real time: 0.5 s + one frame
        assert 500 <= sum(f.info["duration"] for f in ImageSequence.Iterator(im)) <= 560
    # only what was asked for
    render3d.render_any(traj, gif=tmp_path / "only.gif")
    assert (tmp_path / "only.gif").exists() and not (tmp_path / "only.png").exists()
    with pytest.raises(ValueError, match="episode"):
        render3d.render_any(traj, tmp_path / "g.png", e=1)


def test_a_task_view_draws_a_close_up_of_some_bodies(tmp_path, monkeypatch):
    task = gpmotion.get_task("herman_touch_nose")
    traj = gpmotion.simulate(task.figure, 0.05, record_every=25)
    seen = {}
    monkeypatch.setattr(render3d, "filmstrip3d", lambda path, seg, rad, t, **kw: seen.update(
        seg=seg, rad=rad, **kw))
    render3d.render_any(traj, tmp_path / "f.png", view=task.view)
    names = task.view["bodies"]
    assert seen["seg"].shape[1] == len(names) == len(seen["rad"]) < len(task.figure.body_names)
    i = task.figure.body_names.index(names[-1])
    np.testing.assert_array_equal(seen["seg"][:, -1], traj.segments()[0, :, i])
    assert seen["ground_z"] is None and seen["azim"] == task.view["azim"]
    assert task.view["bodies"] == names                   # the task's view is not consumed
    with pytest.raises(ValueError, match="unknown bodies"):
        render3d.render_any(traj, tmp_path / "g.png", view={"bodies": ["tail"]})


# ---------------------------------------------------- what the pictures show

@pytest.fixture
def drawn(monkeypatch):
    """The matplotlib Figures render3d would have saved, by file name."""
    figs = {}
    monkeypatch.setattr(render3d, "_save_png", lambda fig, path, dpi: figs.__setitem__(
        Path(path).name, fig))
    return figs


def stars(fig):
    return [ln for ax in fig.axes for ln in ax.lines if ln.get_marker() == "*"]


def texts(fig):
    return [t.get_text().strip() for ax in fig.axes for t in ax.texts]


def test_a_3d_goal_is_drawn_only_for_a_task_that_names_it(drawn, tmp_path):
    task = gpmotion.get_task("herman_touch_nose")
    traj = gpmotion.simulate(task.figure, 0.05, scene=task.scene())
    render3d.render_any(traj, tmp_path / "task.png", task=task)
    assert len(stars(drawn["task.png"])) >= 1 and "nose at rest" in texts(drawn["task.png"])
    render3d.render_any(traj, tmp_path / "passive.png", view=task.view)
    assert stars(drawn["passive.png"]) == []


def test_a_3d_pole_is_a_bar_on_posts_labelled_with_its_height(drawn, tmp_path):
    seg, t = walking_chain(n_frames=10)
    render3d.filmstrip3d(tmp_path / "p.png", seg, RADII, t, poles=[[0.6, 1.2, 0.05]], strip=False)
    ax = drawn["p.png"].axes[0]
    assert "pole: underside 1.15 m up" in texts(drawn["p.png"])
    drawn["p.png"].canvas.draw()                              # projects the 3-D segments
    widths = sorted(len(c.get_segments()) for c in ax.collections if hasattr(c, "get_segments"))
    assert 1 in widths and 2 in widths                        # one bar, two posts


def _tick_gaps(fig):
    """Per axis of the big 3-D axes: the screen distances (points) between
    consecutive numbered ticks, measured along the box edge."""
    from mpl_toolkits.mplot3d import proj3d
    fig.canvas.draw()
    ax = fig.axes[0]
    lims = [ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()]
    M = ax.get_proj()
    gaps = {}
    for i, axis in enumerate((ax.xaxis, ax.yaxis, ax.zaxis)):
        lo, hi = sorted(lims[i])
        locs = [v for v in axis.get_majorticklocs() if lo <= v <= hi]
        if not axis.get_major_formatter().format_ticks(locs)[0]:
            continue                                        # numbers hidden
        pts = []
        for v in locs:
            p = [lim[0] for lim in lims]
            p[i] = v
            x, y, _ = proj3d.proj_transform(*p, M)
            pts.append(ax.transData.transform((x, y)) * 72.0 / fig.dpi)
        gaps["xyz"[i]] = np.hypot(*np.diff(np.array(pts), axis=0).T)
    return gaps


def test_3d_tick_labels_have_room(drawn, tmp_path):
    """The close-up of Herman crammed eleven x tick labels into 2 cm, one
    running into the next (and "z (m)" sat on the z tick labels: checked by
    eye, the label now has padding)."""
    task = gpmotion.get_task("herman_touch_nose")
    traj = gpmotion.simulate(task.figure, 0.05, scene=task.scene())
    render3d.render_any(traj, tmp_path / "nose.png", view=task.view)
    seg, t = walking_chain(n_frames=10)
    render3d.filmstrip3d(tmp_path / "walk.png", seg, RADII, t)
    for name in ("nose.png", "walk.png"):
        gaps = _tick_gaps(drawn[name])
        assert "z" in gaps                                    # the height is always numbered
        for axis, g in gaps.items():
            assert g.min() >= 30, (name, axis, g)


def test_animate3d_plays_in_real_time(tmp_path):
    seg, t = walking_chain(n_frames=151, duration=1.5)         # 100 frames/s
    render3d.animate3d(tmp_path / "w.gif", seg, RADII, t, fps=10, dpi=30)
    with Image.open(tmp_path / "w.gif") as im:
        d = [f.info["duration"] for f in ImageSequence.Iterator(im)]
    assert set(d) == {100} and 1500 <= sum(d) <= 1600


def test_a_task_adds_its_own_moments_to_the_filmstrip(monkeypatch, tmp_path):
    task = gpmotion.get_task("herman_touch_nose")
    traj = gpmotion.simulate(task.figure, 0.05, scene=task.scene())
    seen = {}
    monkeypatch.setattr(render3d, "filmstrip3d", lambda *a, **kw: seen.update(kw))
    monkeypatch.setattr(task, "picture_events", lambda traj, e: [(3, "first touch")], raising=False)
    render3d.render_any(traj, tmp_path / "f.png", task=task)
    assert (3, "first touch") in seen["events"]
