"""The GIF's frames: redrawing only what moves (blitting) gives the pixels of a
full draw, with artists stacked above the figure (goal star, its label, a
limbo pole's label) still drawn over it; every frame shares one palette."""
import numpy as np
from PIL import Image, ImageSequence

from gpmotion import render
from tests.test_render import RADII, swinging_chain


def _scene(seg, t):
    """A figure like animate()'s, the goal right where the chain swings."""
    fig = render.Figure(figsize=(3, 3))
    render.FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    lo, hi = render._scene_limits(seg, RADII, np.arange(len(t)), None, 0.0, None)
    goal = seg[len(t) // 2, -1, 1]                  # the chain's tip passes the star
    render._draw_scene(ax, lo, hi, None, 0.0, goal, goal_label="target")
    ax.set_title("chain")
    fig.set_layout_engine("constrained")
    body = render._figure_body(ax, seg[0], RADII, (0.2, 0.4, 0.8, 1.0))
    clock = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top", family="monospace")
    return fig, body, clock


def _frames(draw_of, seg, t):
    fig, body, clock = _scene(seg, t)
    draw = draw_of(fig, [body, clock])
    out = []
    for i in range(0, len(t), 5):
        body.set_verts(render.capsules(seg[i], RADII))
        clock.set_text(f"t = {t[i]:5.2f} s")
        out.append(np.asarray(draw()))
    return out


def test_blitted_frames_equal_full_draws():
    seg, t = swinging_chain(n_frames=40)
    full = _frames(lambda fig, moving: render._full_draw(fig), seg, t)
    blit = _frames(render._blitter, seg, t)
    assert len(full) == len(blit) == 8
    for a, b in zip(full, blit):
        assert a.shape == b.shape
        assert np.array_equal(a, b)
    assert not np.array_equal(full[0], full[4])      # the frames do differ


def test_gif_frames_share_one_palette(tmp_path):
    seg, t = swinging_chain(n_frames=30)
    n = render.animate(tmp_path / "m.gif", seg, RADII, t, goal=(0.2, 0.5), goal_label="target",
                       dpi=30)
    with Image.open(tmp_path / "m.gif") as im:
        frames = list(ImageSequence.Iterator(im))
        assert len(frames) == n
        palettes = {bytes(f.getpalette() or b"") for f in frames}
    assert len(palettes) == 1
