"""Pictures of runs: strobe filmstrips, GIFs, learning curves (DESIGN.md §8).

Decoupled from the simulator: everything takes plain arrays, so a
Trajectory, a replay file or a test's synthetic figure draw the same way.
Segments are ``float[F, n_seg, 2, 2]`` — frame, segment, endpoint (a, b),
(x, z) — and each is drawn as a capsule *polygon* of its radius in data units,
so limbs have their true thickness at any zoom (a line width in points would
not).

GIFs play in real time unless asked otherwise, and say their speed;
filmstrips keep the motion's events (take-off, apex, landing, ...) besides
evenly spaced frames (:mod:`gpmotion.frames`).  :func:`run_curve` draws a
run's curve.png with its phase-in windows.

Uses matplotlib's object API with an Agg canvas — no pyplot, no global
backend switch, no screen.  Every output goes to a temp file beside the
target and is moved into place only when complete
(:func:`gpmotion.records.atomic_output`), so a crash never leaves a
half-written picture.  Frames containing NaN/inf (a diverged episode's tail)
are skipped; no usable frame at all is a ValueError.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.gridspec import GridSpec
from matplotlib.patches import Circle
from PIL import Image

from gpmotion.frames import choose_frames, event_labels, gif_timing, speed_text
from gpmotion.records import atomic_output

_ARC = 9  # points per half-circle of a capsule (odd: the tip is a vertex)


# ------------------------------------------------------------------ geometry

def capsules(seg: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Outline polygons ``float[n_seg, 2*_ARC, 2]`` of segments ``[n_seg, 2, 2]``
    with the given radii; a zero-length segment becomes a disc."""
    a, b = seg[:, 0], seg[:, 1]
    d = b - a
    phi = np.arctan2(d[:, 1], d[:, 0])[:, None]
    half = np.linspace(-np.pi / 2, np.pi / 2, _ARC)[None, :]
    r = np.asarray(radii, float)[:, None]
    ang_b, ang_a = phi + half, phi + half + np.pi
    pts_b = b[:, None, :] + r[..., None] * np.stack([np.cos(ang_b), np.sin(ang_b)], -1)
    pts_a = a[:, None, :] + r[..., None] * np.stack([np.cos(ang_a), np.sin(ang_a)], -1)
    return np.concatenate([pts_b, pts_a], axis=1)


def _check_motion(segments, radii, times, dims: int = 2):
    """Validated arrays and the indices of frames that are entirely finite
    (``dims`` = 2 for x–z drawings, 3 for the 3-D renderer)."""
    seg = np.asarray(segments, dtype=float)
    if seg.ndim != 4 or seg.shape[2:] != (2, dims):
        raise ValueError(f"segments must have shape [frames, n_seg, 2, {dims}], got {seg.shape}")
    if seg.shape[0] == 0 or seg.shape[1] == 0:
        raise ValueError(f"no frames or no segments to draw (shape {seg.shape})")
    rad = np.asarray(radii, dtype=float).reshape(-1)
    if rad.shape != (seg.shape[1],) or not np.all(np.isfinite(rad)) or np.any(rad < 0):
        raise ValueError(f"radii must be {seg.shape[1]} finite values ≥ 0, got {rad}")
    t = np.asarray(times, dtype=float).reshape(-1)
    if t.shape != (seg.shape[0],):
        raise ValueError(f"times must have {seg.shape[0]} entries, got {t.shape[0]}")
    ok = np.flatnonzero(np.isfinite(seg).all(axis=(1, 2, 3)) & np.isfinite(t))
    if ok.size == 0:
        raise ValueError("every frame contains NaN/inf: nothing to draw")
    return seg, rad, t, ok


def _scene_limits(seg, rad, frames, poles, ground_z, goal, pad=0.1):
    pts = seg[frames].reshape(-1, 2)
    r = rad.max()
    lo, hi = pts.min(0) - r, pts.max(0) + r
    if poles is not None and len(poles):
        lo = np.minimum(lo, (poles[:, :2] - poles[:, 2:3]).min(0))
        hi = np.maximum(hi, (poles[:, :2] + poles[:, 2:3]).max(0))
    if goal is not None:
        lo, hi = np.minimum(lo, goal), np.maximum(hi, goal)
    if ground_z is not None:
        lo[1], hi[1] = min(lo[1], ground_z), max(hi[1], ground_z)
    span = np.maximum(hi - lo, 1e-3)
    m = pad * span.max()
    return lo - m, hi + m


def _check_scene(poles, goal):
    if poles is not None:
        poles = np.asarray(poles, float).reshape(-1, 3)
        poles = poles[np.isfinite(poles).all(1)]
    if goal is not None:
        goal = np.asarray(goal, float).reshape(-1)[:2]
        if goal.size != 2 or not np.isfinite(goal).all():
            goal = None
    return poles, goal


def pole_text(x_z_r, ground_z) -> str:
    """A limbo pole's label: the height of its underside (what the figure
    must pass below), above the ground when there is one."""
    _, z, r = x_z_r
    if ground_z is None:
        return f"pole: underside z = {z - r:.2f} m"
    return f"pole: underside {z - r - ground_z:.2f} m up"


def _draw_scene(ax, lo, hi, poles, ground_z, goal, small=False, goal_label=None):
    if ground_z is not None:
        ax.axhspan(lo[1] - 10 * (hi[1] - lo[1]), ground_z, color="0.9", zorder=0)
        ax.axhline(ground_z, color="0.35", lw=0.8 if small else 1.2, zorder=1)
    if poles is not None:
        for x, z, r in poles:
            # the bar runs along y (into the page): its end-on section, and
            # the post it rests on (at its end, behind the figure: dashed)
            base = ground_z if ground_z is not None else lo[1]
            ax.plot([x, x], [base, z], color="0.6", lw=0.8 if small else 1.5, ls=(0, (4, 3)),
                    zorder=1.5)
            ax.add_patch(Circle((x, z), r, color="tab:red", alpha=0.9, zorder=2))
            if not small:
                ax.annotate(pole_text((x, z, r), ground_z), (x + r, z), xytext=(6, 4),
                            textcoords="offset points", fontsize=8, color="tab:red", zorder=6)
    if goal is not None:
        ax.plot([goal[0]], [goal[1]], marker="*", ms=7 if small else 14,
                color="gold", mec="k", mew=0.6, zorder=5, ls="none")
        if goal_label and not small:
            ax.annotate(goal_label, (goal[0], goal[1]), xytext=(0, -9), textcoords="offset points",
                        ha="center", va="top", fontsize=8, zorder=6)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")


def _figure_body(ax, seg_frame, rad, color, zorder=3, alpha=1.0):
    pc = PolyCollection(capsules(seg_frame, rad), facecolors=[color],
                        edgecolors=[tuple(c * 0.6 for c in color[:3]) + (1.0,)],
                        linewidths=0.5, alpha=alpha, zorder=zorder)
    ax.add_collection(pc)
    return pc


def _save_png(fig: Figure, path, dpi: int) -> None:
    FigureCanvasAgg(fig)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)


# -------------------------------------------------------------- filmstrip

def _captions(n: int, labels, events) -> list[str]:
    """Per recorded frame: the event word(s) and the caller's label."""
    words = event_labels(n, list(events or []))
    for i, lab in enumerate(labels or []):
        if lab:
            words[i] = f"{words[i]}, {lab}" if words[i] else str(lab)
    return words


def filmstrip(path, segments, radii, times, *, poles=None, ground_z=0.0,
              goal=None, goal_label: str | None = None, n_frames: int = 10,
              title: str | None = None, labels: Sequence[str | None] | None = None,
              events: Sequence[tuple[int, str]] | None = None, strip: bool = True,
              dpi: int = 120) -> np.ndarray:
    """The papers' strobe picture, saved as PNG; returns the indices of the
    recorded frames drawn.

    Top: the figure at ``n_frames`` finite frames overlaid on one axis,
    later frames darker, with ground, limbo poles (``float[n, 3]`` = x, z,
    radius; drawn as the bar's section on its post, labelled with its
    height) and the goal (x, z; a star, captioned ``goal_label``).  The
    frames are the first, the last, the ``events`` (``[(frame, word)]``,
    e.g. :func:`gpmotion.frames.flight_events`' take-off/apex/landing) and
    evenly spaced fill-ins.  Bottom (``strip=True``): the same frames as
    small multiples at one common scale, each centred on the figure and
    captioned with its time and its event; ``labels`` (one per *recorded*
    frame, entries may be None/"") add further words to a caption.
    """
    seg, rad, t, ok = _check_motion(segments, radii, times)
    poles, goal = _check_scene(poles, goal)
    if labels is not None and len(labels) != seg.shape[0]:
        raise ValueError(f"labels must have one entry per frame ({seg.shape[0]}), "
                         f"got {len(labels)}")
    frames = choose_frames(ok, t, n_frames, list(events or []))
    words = _captions(seg.shape[0], labels, events)
    lo, hi = _scene_limits(seg, rad, frames, poles, ground_z, goal)
    span = hi - lo
    n = len(frames)
    width = max(7.0, min(1.3 * n, 16.0))
    top_h = float(np.clip(width * span[1] / span[0], 1.5, 7.0))
    # Small multiples share the strobe's z range (heights stay comparable,
    # the ground stays in view) and one x window centred on each frame.
    xs = seg[frames][..., 0].reshape(n, -1)
    x_mid = 0.5 * (xs.min(1) + xs.max(1))
    half_x = max(0.5 * np.ptp(xs, axis=1).max() + rad.max() + 0.05 * span[1],
                 0.25 * span[1])
    cell_w = width / n
    bot_h = float(np.clip(cell_w * span[1] / (2 * half_x), 0.8, 3.0)) + 0.3 if strip else 0.0

    fig = Figure(figsize=(width, top_h + bot_h + (0.4 if title else 0.1)))
    gs = GridSpec(2 if strip else 1, n, figure=fig,
                  height_ratios=[top_h, bot_h] if strip else None)
    ax = fig.add_subplot(gs[0, :])
    cmap = colormaps["Blues"]
    colors = [cmap(v) for v in np.linspace(0.35, 1.0, n)]
    _draw_scene(ax, lo, hi, poles, ground_z, goal, goal_label=goal_label)
    for k, (i, c) in enumerate(zip(frames, colors)):
        _figure_body(ax, seg[i], rad, c, zorder=3 + k / n, alpha=0.85)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    if title:
        ax.set_title(title)
    if strip:
        for k, (i, c) in enumerate(zip(frames, colors)):
            sub = fig.add_subplot(gs[1, k])
            _draw_scene(sub, (x_mid[k] - half_x, lo[1]), (x_mid[k] + half_x, hi[1]),
                        poles, ground_z, goal, small=True)
            _figure_body(sub, seg[i], rad, c)
            caption = f"t={t[i]:.2f}s" + (f"\n{words[i]}" if words[i] else "")
            sub.set_title(caption, fontsize=7)
            sub.set_xticks([])
            sub.set_yticks([])
    fig.set_layout_engine("constrained")
    _save_png(fig, path, dpi)
    return frames


# ---------------------------------------------------------------- animate

def animate(path, segments, radii, times, *, poles=None, ground_z=0.0,
            goal=None, goal_label: str | None = None, speed: float = 1.0,
            fps: float = 25, max_frames: int = 200, title: str | None = None,
            dpi: int = 80) -> int:
    """An animated GIF of the motion; returns the number of frames written.

    It plays at ``speed`` × real time (default 1: real time; the speed is
    written in a corner beside the recorded time): the frames are every k-th
    recorded one with k chosen so that at most ``fps`` frames play per second
    and at most ``max_frames`` are written, and each lasts its share of
    simulated time (:func:`gpmotion.frames.gif_timing`).  Axis limits come
    from the whole motion so the camera stays still.  Frames are quantized to
    a palette as they are drawn, so memory stays small.
    """
    seg, rad, t, ok = _check_motion(segments, radii, times)
    poles, goal = _check_scene(poles, goal)
    frames, durations = gif_timing(ok, t, speed, fps, int(max_frames))
    lo, hi = _scene_limits(seg, rad, ok, poles, ground_z, goal)
    span = hi - lo
    width = 6.0
    fig = Figure(figsize=(width, float(np.clip(width * span[1] / span[0], 2.0, 6.0))))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    _draw_scene(ax, lo, hi, poles, ground_z, goal, goal_label=goal_label)
    if title:
        ax.set_title(title)
    ax.set_xticks([])
    ax.set_yticks([])
    fig.set_layout_engine("constrained")
    body = _figure_body(ax, seg[frames[0]], rad, colormaps["Blues"](0.85))
    clock = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top",
                    family="monospace", fontsize=9)
    return record_gif(path, fig, clock, lambda i: body.set_verts(capsules(seg[i], rad)),
                      frames, durations, t, speed, moving=[body, clock])


def record_gif(path, fig, clock, pose, frames, durations, times, speed, moving=()) -> int:
    """Draw each frame (``pose(i)`` moves the figure to frame i, ``clock`` shows
    its time), quantize it to a palette as it is drawn, write the GIF; returns
    the number of frames written.

    ``moving``: the artists ``pose`` and ``clock`` change, all in one axes.
    Then the rest of the picture is drawn (and laid out) once, and each frame
    redraws only those artists and the ones stacked above them, on a copy of
    that background (blitting: the same pixels as a full draw).  Every frame
    is mapped to one palette, taken from the first frame (a fast octree), so
    neither a per-frame palette search nor the GIF writer's remapping runs
    per frame.
    """
    draw = _blitter(fig, moving) if moving else _full_draw(fig)
    images, palette = [], None
    for i in frames:
        pose(i)
        clock.set_text(f"t = {times[i]:5.2f} s\n{speed_text(speed)}")
        image = draw()
        if palette is None:
            palette = image.quantize(256, method=Image.Quantize.FASTOCTREE)
        images.append(image.quantize(palette=palette, dither=Image.Dither.NONE))
    save_gif(path, images, durations)
    return len(images)


def _rgb(canvas) -> Image.Image:
    return Image.fromarray(np.asarray(canvas.buffer_rgba())).convert("RGB")


def _full_draw(fig):
    """Each frame drawn whole; a layout engine runs at the first draw only
    (nothing that moves changes the layout: the axis limits are fixed)."""
    def draw():
        fig.canvas.draw()
        if fig.get_layout_engine() is not None:
            fig.set_layout_engine("none")
        return _rgb(fig.canvas)
    return draw


def _blitter(fig, moving):
    """Each frame: the still background, then the moving artists and every
    artist stacked above the lowest of them, in drawing order."""
    ax = moving[0].axes
    z = min(a.get_zorder() for a in moving)
    # outside the data area or beneath everything: never overdrawn by the figure
    titles = (getattr(ax, n, None) for n in ("title", "_left_title", "_right_title"))
    static = {ax.patch, *titles, *ax.spines.values()}
    top = sorted((a for a in ax.get_children()
                  if a.get_visible() and a.get_zorder() >= z and a not in static),
                 key=lambda a: a.get_zorder())          # stable: the axes' own order
    for a in top:
        a.set_animated(True)
    canvas = fig.canvas
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)

    def draw():
        canvas.restore_region(background)
        for a in top:
            ax.draw_artist(a)
        return _rgb(canvas)
    return draw


def save_gif(path, images, durations) -> None:
    """Write palette frames with per-frame durations (ms), looping."""
    with atomic_output(path) as tmp:
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                       duration=list(durations) if len(images) > 1 else durations[0], loop=0)


# ----------------------------------------------------------------- curves

def _finite_xy(x, y, name):
    x = np.asarray(x, float).reshape(-1)
    y = np.asarray(y, float).reshape(-1)
    if x.size == 0:
        raise ValueError(f"{name}: no points to plot")
    if y.shape != x.shape:
        raise ValueError(f"{name}: {y.size} values for {x.size} x positions")
    y = np.where(np.isfinite(y), y, np.nan)
    return x, y


def curve(path, generations_or_evals, best, median=None, xlabel: str = "generation",
          ylabel: str = "fitness (lower is better)", title: str | None = None,
          dpi: int = 120) -> None:
    """Learning curve: best (and optionally median) score per generation.
    Non-finite values leave gaps rather than wrecking the autoscale."""
    x, yb = _finite_xy(generations_or_evals, best, "best")
    if not np.isfinite(yb).any():
        raise ValueError("best: every value is NaN/inf")
    fig = Figure(figsize=(6, 4))
    ax = fig.add_subplot()
    ax.plot(x, yb, lw=1.8, label="best")
    if median is not None:
        _, ym = _finite_xy(x, median, "median")
        ax.plot(x, ym, lw=1.2, ls="--", label="median")
    _save_curves(fig, ax, path, xlabel, ylabel, title, dpi)


def _save_curves(fig, ax, path, xlabel, ylabel, title, dpi) -> None:
    """Label, grid and legend a plot of learning curves, then write it."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend()
    if title:
        ax.set_title(title)
    fig.set_layout_engine("constrained")
    _save_png(fig, path, dpi)


def curves_band(path, series: Mapping[str, tuple], xlabel: str = "generation",
                ylabel: str = "fitness (lower is better)", title: str | None = None,
                dpi: int = 120) -> None:
    """Several families' learning curves: median line with the 25–75 %
    quartile band, ``series[name] = (x, q25, q50, q75)``."""
    if not series:
        raise ValueError("curves_band: no series to plot")
    fig = Figure(figsize=(6.5, 4))
    ax = fig.add_subplot()
    drawn = 0
    for name, data in series.items():
        if len(data) != 4:
            raise ValueError(f"{name}: expected (x, q25, q50, q75)")
        x, q25 = _finite_xy(data[0], data[1], name)
        _, q50 = _finite_xy(x, data[2], name)
        _, q75 = _finite_xy(x, data[3], name)
        (line,) = ax.plot(x, q50, lw=1.6, label=str(name))
        ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.25, lw=0)
        drawn += np.isfinite(q50).any()
    if not drawn:
        raise ValueError("curves_band: every median value is NaN/inf")
    _save_curves(fig, ax, path, xlabel, ylabel, title, dpi)


# ------------------------------------------------------- a run's curve.png

def _column(rows, key) -> np.ndarray | None:
    """A log column as floats (blank or unparsable cells NaN); None when the
    log has no such column or it is blank throughout."""
    if not rows or key not in rows[0]:
        return None
    out = np.full(len(rows), np.nan)
    for i, r in enumerate(rows):
        try:
            out[i] = float(r.get(key) or "nan")
        except ValueError:
            pass
    return out if np.isfinite(out).any() else None


def phase_windows(task) -> list[tuple[float, float, str]]:
    """The (a, b) progress windows over which a task's weights change, with
    what changes: style terms ramping in (grouped by window) and curriculum
    parameters easing to their values."""
    groups: dict[tuple[float, float], list[str]] = {}
    for term in getattr(task, "terms", ()):
        a, b = (float(v) for v in term.phase)
        if b > a and term.weight != 0:
            groups.setdefault((a, b), []).append(term.name)
    for name, ease in getattr(task, "curriculum", {}).items():
        a, b = (float(v) for v in ease.phase)
        if b > a:
            groups.setdefault((a, b), []).append(f"{name} (curriculum)")
    return [(a, b, ", ".join(names)) for (a, b), names in sorted(groups.items())]


def run_curve(path, rows: Sequence[Mapping[str, str]], task, title: str | None = None,
              dpi: int = 120) -> None:
    """A run's learning curve from its log rows (log.csv as dicts of strings).

    Plots the best so far and the generation median, both under the weights
    in force at each generation ("current weights": they grow as style terms
    phase in, so these curves may rise), and, when the log has the column
    ``best_final``, the best so far re-scored under the final weights (which
    never rises).  Below, a strip shows each phase-in window (the terms
    ramping from weight 0 to full), also shaded on the curve.  x is
    evaluations (generations when the log lacks them).
    """
    if not rows:
        raise ValueError("run_curve: the log has no rows")
    x = _column(rows, "evaluations")
    xlabel = "evaluations"
    if x is None:
        x, xlabel = _column(rows, "generation"), "generation"
    best = _column(rows, "best_so_far")
    if x is None or best is None:
        raise ValueError("run_curve: the log needs 'best_so_far' and 'evaluations' or 'generation'")
    median, final = _column(rows, "gen_median"), _column(rows, "best_final")
    progress = _column(rows, "progress")
    windows = phase_windows(task) if progress is not None else []

    fig = Figure(figsize=(7, 4.8 if windows else 4.2))
    gs = GridSpec(2 if windows else 1, 1, figure=fig,
                  height_ratios=[4, 0.35 + 0.28 * len(windows)] if windows else None)
    ax = fig.add_subplot(gs[0])
    ax.plot(x, best, lw=1.8, color="tab:blue", label="best so far (current weights)")
    if median is not None:
        ax.plot(x, median, lw=1.0, ls="--", color="tab:blue", alpha=0.6,
                label="generation median (current weights)")
    if final is not None:
        ax.plot(x, final, lw=1.8, color="tab:green", label="best final (final weights)")
    _cost_limits(ax, best, final, median)
    ax.set_ylabel("cost (lower is better)" if final is not None
                  else "cost (lower is better),\ncurrent weights")
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title)
    if windows:
        xs = [(float(np.interp(a, progress, x)), float(np.interp(b, progress, x)), names)
              for a, b, names in windows]
        for x0, x1, _ in xs:
            ax.axvspan(x0, x1, color="tab:orange", alpha=0.08, lw=0)
        ax.tick_params(labelbottom=False)
        ax.legend(fontsize=8, loc="upper right")
        _phase_strip(fig.add_subplot(gs[1], sharex=ax), xs, xlabel)
    else:
        ax.set_xlabel(xlabel)
        ax.legend(fontsize=8)
    fig.set_layout_engine("constrained")
    _save_png(fig, path, dpi)


def _cost_limits(ax, best, final, median):
    """y limits that show the best curves whole and the median up to its
    own middle value: it can spike by orders of magnitude while terms
    phase in, and would flatten the best curves (the spikes leave the top)."""
    keep = np.concatenate([v[np.isfinite(v)] for v in (best, final) if v is not None])
    lo, hi = keep.min(), keep.max()
    if median is not None and np.isfinite(median).any():
        lo, hi = min(lo, np.nanmin(median)), max(hi, np.nanmedian(median))
    pad = 0.05 * max(hi - lo, abs(hi) * 0.1, 1e-9)
    ax.set_ylim(lo - pad, hi + pad)


def _phase_strip(ax, xs, xlabel):
    """One bar per phase-in window, captioned with the terms that ramp in it."""
    for k, (x0, x1, names) in enumerate(xs):
        y = len(xs) - 1 - k
        ax.barh(y, x1 - x0, left=x0, height=0.7, color="tab:orange", alpha=0.45, lw=0)
        ax.text(x0, y, f" {names}", va="center", ha="left", fontsize=7)
    ax.set_ylim(-0.6, len(xs) - 0.4)
    ax.set_yticks([])
    ax.set_ylabel("ramping\nin", fontsize=7, rotation=0, ha="right", va="center")
    ax.set_xlabel(xlabel)
    ax.grid(alpha=0.3, axis="x")
