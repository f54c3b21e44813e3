"""render.py on a synthetic 3-segment swinging chain: files are valid images
of the expected kind and size, NaN frames are tolerated, bad input is a
clear ValueError, and a failed render leaves no file behind."""
import os

import numpy as np
import pytest
from PIL import Image

from gpmotion import render

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


def open_image(path):
    assert path.exists() and path.stat().st_size > 0
    with Image.open(path) as im:
        im.load()
        return im


def no_temp_files(directory):
    return [p.name for p in directory.iterdir() if p.name.endswith(".tmp")] == []


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
    im = open_image(out)
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
    assert open_image(tmp_path / "f.png").format == "PNG"


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


def test_animate_writes_gif_within_frame_budget(tmp_path):
    seg, t = swinging_chain(n_frames=50)
    seg[5:9] = np.nan
    out = tmp_path / "motion.gif"
    n = render.animate(out, seg, RADII, t, poles=[[0.6, 1.2, 0.05]], goal=(1.0, 0.0),
                       fps=20, max_frames=12, title="swing")
    with Image.open(out) as im:
        assert im.format == "GIF"
        assert 2 <= im.n_frames <= 12 and n <= 12
        assert im.info.get("duration") == 50
        assert im.size[0] > 100 and im.size[1] > 50
    assert no_temp_files(tmp_path)


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
    assert open_image(tmp_path / "curve.png").format == "PNG"
    series = {"gp": (g, best * 0.8, best, best * 1.2),
              "bsr": (g, g * 0 + 1.0, g * 0 + 2.0, g * 0 + 3.0)}
    render.curves_band(tmp_path / "band.png", series, "evaluations", "score")
    assert open_image(tmp_path / "band.png").format == "PNG"


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
