"""Pictures of 3-D motions: strobe filmstrips and GIFs (DESIGN.md §8), plus
:func:`render_any`, which picks the planar or the 3-D renderer for a Trajectory.

Like :mod:`gpmotion.render`, decoupled from the simulator: everything takes
plain arrays.  Segments are ``float[F, n_seg, 2, 3]`` — frame, segment,
endpoint (a, b), (x, y, z), z up — and each is drawn as a thick line with
round caps whose width is 3/4 of the capsule's diameter at the scene's scale
(limbs look like capsules, overlaid frames stay readable), with a dot at every
segment end (the joints).

matplotlib's ``mplot3d`` with a fixed camera (``elev``, ``azim``): every
frame of a picture uses the same axis limits, taken from the whole motion,
at equal scale on x, y and z (``set_box_aspect``).  The ground is a grid of
lines every 0.25 m on z = ``ground_z`` (wider spacing on very large scenes,
at most ~40 lines a side).  Limbo poles (x, z, radius) are horizontal bars
along y on two posts, labelled with the height of their underside; the goal
is a gold star (``goal_label`` captions it; :func:`render_any` draws it only
for a task that names it); ``targets`` (points, e.g. the object to touch) are
red dots.  Frames and GIF timing as in :mod:`gpmotion.render`
(:mod:`gpmotion.frames`).  Object API with an Agg canvas (no pyplot, no
screen); outputs are written atomically (:func:`gpmotion.records.atomic_output`).
Frames containing NaN/inf are skipped; no usable frame is a ValueError.
"""
from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.gridspec import GridSpec
from matplotlib.ticker import MaxNLocator, NullFormatter
from mpl_toolkits.mplot3d import proj3d
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

from gpmotion.records import atomic_output

GRID = 0.25          # ground grid spacing (m)
from .frames import (choose_frames, crossing_events, event_labels, flight_events,  # noqa: E402
                     gif_timing)
from .render import _check_motion, pole_text, record_gif  # noqa: E402  (shared with the planar renderer)

_MAX_GRID_LINES = 40


# ------------------------------------------------------------------ input

def _check_motion3d(segments, radii, times):
    """Validated arrays and the indices of frames that are entirely finite."""
    return _check_motion(segments, radii, times, dims=3)


def _check_scene3d(goal, targets, poles):
    if goal is not None:
        goal = np.asarray(goal, float).reshape(-1)
        if goal.size == 2:                      # a planar goal (x, z)
            goal = np.array([goal[0], 0.0, goal[1]])
        if goal.size != 3 or not np.isfinite(goal).all():
            goal = None
    if targets is not None:
        targets = np.asarray(targets, float).reshape(-1, 3)
        targets = targets[np.isfinite(targets).all(1)]
        if not len(targets):
            targets = None
    if poles is not None:
        poles = np.asarray(poles, float).reshape(-1, 3)
        poles = poles[np.isfinite(poles).all(1) & (poles[:, 2] > 0)]
        if not len(poles):
            poles = None
    return goal, targets, poles


def _limits(points, rad, ground_z, goal, targets, poles, pad=0.06):
    """Axis limits (lo, hi) [3] holding every point, with a margin; every axis
    spans at least a fifth of the widest one (and 0.2 m)."""
    pts = points.reshape(-1, 3)
    r = float(rad.max())
    lo, hi = pts.min(0) - r, pts.max(0) + r
    extra = [p for p in (goal, targets) if p is not None]
    for p in extra:
        p = np.asarray(p).reshape(-1, 3)
        lo, hi = np.minimum(lo, p.min(0)), np.maximum(hi, p.max(0))
    if poles is not None:
        lo[[0, 2]] = np.minimum(lo[[0, 2]], (poles[:, :2] - poles[:, 2:3]).min(0))
        hi[[0, 2]] = np.maximum(hi[[0, 2]], (poles[:, :2] + poles[:, 2:3]).max(0))
    if ground_z is not None:
        lo[2], hi[2] = min(lo[2], ground_z), max(hi[2], ground_z)
    span = hi - lo
    need = max(0.2, 0.2 * span.max())
    grow = np.maximum(need - span, 0.0) / 2
    lo, hi = lo - grow, hi + grow
    m = pad * (hi - lo).max()
    return lo - m, hi + m


def _screen_aspect(lo, hi, elev, azim) -> float:
    """Height / width of the box [lo, hi] as the camera sees it (orthographic)."""
    a, e = np.radians(azim), np.radians(elev)
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    up = np.array([-np.sin(e) * np.cos(a), -np.sin(e) * np.sin(a), np.cos(e)])
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    return float(np.ptp(corners @ up) / max(np.ptp(corners @ right), 1e-9))


# ---------------------------------------------------------------- drawing

def _setup(ax, lo, hi, elev, azim, small=False):
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo), zoom=1.3 if small else 0.85)   # room for tick labels
    ax.view_init(elev=elev, azim=azim)
    ax.computed_zorder = False          # draw order: ground, then older → newer frames
    if small:
        ax.set_axis_off()
    else:
        for lab, setter in (("x (m)", ax.set_xlabel), ("y (m)", ax.set_ylabel), ("z (m)", ax.set_zlabel)):
            setter(lab, fontsize=8, labelpad=12)
        ax.tick_params(labelsize=7, pad=4)
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
            axis.pane.set_alpha(0.15)


def _ground(ax, lo, hi, ground_z, small=False):
    if ground_z is None:
        return
    step = GRID
    while max((hi[0] - lo[0]), (hi[1] - lo[1])) / step > _MAX_GRID_LINES:
        step *= 2
    xs = np.arange(np.ceil(lo[0] / step), np.floor(hi[0] / step) + 1) * step
    ys = np.arange(np.ceil(lo[1] / step), np.floor(hi[1] / step) + 1) * step
    quad = [[(lo[0], lo[1], ground_z), (hi[0], lo[1], ground_z),
             (hi[0], hi[1], ground_z), (lo[0], hi[1], ground_z)]]
    ax.add_collection3d(Poly3DCollection(quad, facecolors=[(0.85, 0.85, 0.85, 0.5)],
                                         edgecolors="none"))
    lines = ([[(x, lo[1], ground_z), (x, hi[1], ground_z)] for x in xs]
             + [[(lo[0], y, ground_z), (hi[0], y, ground_z)] for y in ys])
    if lines:
        ax.add_collection3d(Line3DCollection(lines, colors="0.55", linewidths=0.3 if small else 0.5))


def _markers(ax, lo, hi, goal, targets, poles, ppm, small=False, ground_z=None,
             goal_label=None):
    if poles is not None:
        # a bar along y resting on a post at each end, labelled with its height
        base = ground_z if ground_z is not None else lo[2]
        y0, y1 = lo[1] + 0.1 * (hi[1] - lo[1]), hi[1] - 0.1 * (hi[1] - lo[1])
        bars = [[(x, y0, z), (x, y1, z)] for x, z, _ in poles]
        posts = [[(x, y, base), (x, y, z)] for x, z, _ in poles for y in (y0, y1)]
        ax.add_collection3d(Line3DCollection(posts, colors="0.5", linewidths=1.0 if small else 2.0))
        ax.add_collection3d(Line3DCollection(bars, colors="tab:red", alpha=0.9,
                                             linewidths=np.clip(2 * poles[:, 2] * ppm, 1, 40)))
        if not small:
            for x, z, r in poles:
                ax.text(x, y1, z + r, " " + pole_text((x, z, r), ground_z), fontsize=8,
                        color="tab:red", va="bottom")
    if targets is not None:
        ax.plot(targets[:, 0], targets[:, 1], targets[:, 2], ls="none", marker="o",
                ms=4 if small else 8, color="tab:red", mec="k", mew=0.6)
    if goal is not None:
        ax.plot([goal[0]], [goal[1]], [goal[2]], ls="none", marker="*",
                ms=7 if small else 14, color="gold", mec="k", mew=0.6, zorder=9)
        if goal_label and not small:           # above the figure, on a pale ground
            ax.text(goal[0], goal[1], goal[2], "   " + goal_label, fontsize=8, va="center",
                    zorder=10, bbox=dict(fc="white", ec="none", alpha=0.7, pad=1))


def _points_per_metre(ax, lo, hi) -> float:
    """Display scale of the (laid out) 3-D axes: points per metre of the
    least foreshortened coordinate axis, at the centre of the box."""
    fig = ax.figure
    M = ax.get_proj()
    c = (lo + hi) / 2
    d = 0.25 * (hi - lo).max()

    def disp(p):
        x, y, _ = proj3d.proj_transform(p[0], p[1], p[2], M)
        return ax.transData.transform((x, y))

    c0 = disp(c)
    px = max(np.hypot(*(disp(c + d * e) - c0)) for e in np.eye(3)) / d
    return float(px * 72.0 / fig.dpi)


def _fit_ticks(ax, lo, hi, spacing: float = 45.0) -> None:
    """Tick labels that do not overlap (call once the axes are laid out):
    about one tick per ``spacing`` points of each axis's projected length;
    an axis seen nearly end-on keeps two grid lines and no numbers."""
    M = ax.get_proj()

    def disp(p):
        x, y, _ = proj3d.proj_transform(p[0], p[1], p[2], M)
        return ax.transData.transform((x, y))

    for i, axis in enumerate((ax.xaxis, ax.yaxis, ax.zaxis)):
        end = np.array(lo, float)
        end[i] = hi[i]
        points = np.hypot(*(disp(end) - disp(lo))) * 72.0 / ax.figure.dpi
        n = int(points // spacing)
        axis.set_major_locator(MaxNLocator(nbins=max(n, 2)))
        if n < 2:
            axis.set_major_formatter(NullFormatter())


def _body_style(rad, ppm):
    """Line widths (points): 3/4 of each capsule's diameter at the scene's
    scale (a little slimmer than true, so overlaid frames stay readable)."""
    return np.clip(1.5 * rad * ppm, 1.2, 60.0)


def _draw_figure(ax, seg_frame, rad, color, ppm, alpha=1.0, joint_size=None):
    """The figure at one frame: capsule-thick lines with round caps and dots
    at the segment ends; returns (lines, dots) for animation."""
    lw = _body_style(rad, ppm)
    dark = tuple(0.55 * v for v in color[:3]) + (1.0,)
    lines = Line3DCollection(seg_frame, colors=[color], linewidths=lw, alpha=alpha,
                             capstyle="round", joinstyle="round")
    ax.add_collection3d(lines)
    pts = seg_frame.reshape(-1, 3)
    ms = joint_size if joint_size is not None else float(np.clip(0.6 * lw.min(), 2.0, 7.0))
    (dots,) = ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], ls="none", marker="o", ms=ms,
                      color=dark, mec="none", alpha=alpha)
    return lines, dots


def _save_png(fig: Figure, path, dpi: int) -> None:
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)


# -------------------------------------------------------------- filmstrip

def filmstrip3d(path, segments, radii, times, *, ground_z=0.0, goal=None, goal_label=None,
                targets=None, poles=None, n_frames: int = 8, events=None,
                title: str | None = None, elev: float = 15, azim: float = -60,
                strip: bool = True, dpi: int = 110) -> np.ndarray:
    """Strobe picture of a 3-D motion, saved as PNG; returns the indices of
    the recorded frames drawn.

    Top: the figure at ``n_frames`` finite frames — the first, the last, the
    ``events`` (``[(frame, word)]``, e.g. take-off/apex/landing) and evenly
    spaced fill-ins — overlaid in one view, later frames darker, over the
    ground grid, with the goal (x, y, z; a planar (x, z) is lifted to y = 0;
    captioned ``goal_label``), target points ``[n, 3]`` and poles ``[n, 3]``
    (x, z, radius; bars along y on posts, labelled with their height).
    Bottom (``strip=True``): the same frames as small multiples at one
    common scale and camera, each centred on the figure (x, y) and captioned
    with its time and event.
    """
    seg, rad, t, ok = _check_motion3d(segments, radii, times)
    goal, targets, poles = _check_scene3d(goal, targets, poles)
    frames = choose_frames(ok, t, n_frames, list(events or []))
    words = event_labels(seg.shape[0], list(events or []))
    lo, hi = _limits(seg[frames], rad, ground_z, goal, targets, poles)
    n = len(frames)
    width = float(np.clip(1.7 * n, 8.0, 16.0))
    top_h = float(np.clip(0.75 * width * _screen_aspect(lo, hi, elev, azim), 3.0, 7.5))
    # small multiples: one common box, centred on each frame's figure in x, y
    pts = seg[frames].reshape(n, -1, 3)
    mid_xy = 0.5 * (pts[..., :2].min(1) + pts[..., :2].max(1))
    half = max(0.5 * np.ptp(pts[..., :2], axis=1).max() + rad.max(), 0.3 * (hi[2] - lo[2]), 0.1)
    half *= 1.1
    cell_h = float(np.clip(width / n * 1.05, 1.3, 3.0)) if strip else 0.0
    fig = Figure(figsize=(width, top_h + cell_h + (0.3 if title else 0.1)))
    FigureCanvasAgg(fig)
    gs = GridSpec(2 if strip else 1, n, figure=fig, height_ratios=[top_h, cell_h] if strip else None,
                  left=0.02, right=0.98, bottom=0.01, top=0.95 if title else 0.99, hspace=0.02,
                  wspace=0.0)
    ax = fig.add_subplot(gs[0, :], projection="3d")
    _setup(ax, lo, hi, elev, azim)
    if title:
        fig.suptitle(title, fontsize=11)
    subs = []
    if strip:
        for k in range(n):
            sub = fig.add_subplot(gs[1, k], projection="3d")
            slo = np.array([mid_xy[k, 0] - half, mid_xy[k, 1] - half, lo[2]])
            shi = np.array([mid_xy[k, 0] + half, mid_xy[k, 1] + half, hi[2]])
            _setup(sub, slo, shi, elev, azim, small=True)
            subs.append((sub, slo, shi))
    fig.canvas.draw()          # lay out, so the display scale is known
    cmap = colormaps["Blues"]
    colors = [cmap(v) for v in np.linspace(0.35, 1.0, n)]
    ppm = _points_per_metre(ax, lo, hi)
    _fit_ticks(ax, lo, hi)
    _ground(ax, lo, hi, ground_z)
    _markers(ax, lo, hi, goal, targets, poles, ppm, ground_z=ground_z, goal_label=goal_label)
    for i, c in zip(frames, colors):
        _draw_figure(ax, seg[i], rad, c, ppm, alpha=0.9)
    for (sub, slo, shi), i, c in zip(subs, frames, colors):
        sppm = _points_per_metre(sub, slo, shi)
        _ground(sub, slo, shi, ground_z, small=True)
        _markers(sub, slo, shi, goal, targets, poles, sppm, small=True, ground_z=ground_z)
        _draw_figure(sub, seg[i], rad, c, sppm)
        caption = f"t={t[i]:.2f}s" + (f"\n{words[i]}" if words[i] else "")
        sub.text2D(0.5, 0.97, caption, transform=sub.transAxes, ha="center",
                   va="top", fontsize=7)
    _save_png(fig, path, dpi)
    return frames


# ---------------------------------------------------------------- animate

def animate3d(path, segments, radii, times, *, ground_z=0.0, goal=None, goal_label=None,
              targets=None, poles=None, speed: float = 1.0, fps: float = 25,
              max_frames: int = 150, title: str | None = None, elev: float = 15,
              azim: float = -60, dpi: int = 80) -> int:
    """An animated GIF of a 3-D motion; returns the number of frames written.

    Plays at ``speed`` × real time (default 1; written in a corner beside the
    recorded time) with at most ``fps`` frames per second and ``max_frames``
    frames (:func:`gpmotion.frames.gif_timing`); the camera and axis limits
    come from the whole motion so they stay still.  Frames are
    palette-quantized as drawn.
    """
    seg, rad, t, ok = _check_motion3d(segments, radii, times)
    goal, targets, poles = _check_scene3d(goal, targets, poles)
    frames, durations = gif_timing(ok, t, speed, fps, int(max_frames))
    lo, hi = _limits(seg[ok], rad, ground_z, goal, targets, poles)
    fig = Figure(figsize=(6.0, float(np.clip(6.0 * _screen_aspect(lo, hi, elev, azim), 3.5, 7.0))))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 0.94 if title else 1.0), projection="3d")
    _setup(ax, lo, hi, elev, azim)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.canvas.draw()
    ppm = _points_per_metre(ax, lo, hi)
    _fit_ticks(ax, lo, hi)
    _ground(ax, lo, hi, ground_z)
    _markers(ax, lo, hi, goal, targets, poles, ppm, ground_z=ground_z, goal_label=goal_label)
    lines, dots = _draw_figure(ax, seg[frames[0]], rad, colormaps["Blues"](0.85), ppm)
    clock = ax.text2D(0.02, 0.97, "", transform=ax.transAxes, va="top",
                      family="monospace", fontsize=9)

    def pose(i):
        lines.set_segments(seg[i])
        p = seg[i].reshape(-1, 3)
        dots.set_data_3d(p[:, 0], p[:, 1], p[:, 2])
    return record_gif(path, fig, clock, pose, frames, durations, t, speed)


# ------------------------------------------------------------- dispatcher

def motion_events(traj, e: int = 0) -> list[tuple[int, str]]:
    """Take-off, apex and landing frames of episode ``e`` (airborne = no
    ground contact force at any contact point over a frame's interval,
    height = the centre of mass's; :func:`gpmotion.frames.flight_events`)
    and the frames where the centre of mass passes under each limbo pole."""
    cf = traj.contact_force[e]
    poles = [(float(x), "under the pole") for x in traj.scene.poles[:, 0]]
    events = crossing_events(traj.times, traj.com[e][:, 0], poles)
    if traj.scene.ground and cf.shape[-1]:
        height = traj.com[e][:, 2 if traj.is3d else 1]
        events += flight_events(traj.times, height, cf.max(axis=1) == 0)
    return sorted(events)


def motion_frames(traj, e: int = 0, *, task=None, view: dict | None = None) -> dict:
    """What a picture of episode ``e`` shows, frame by frame: the one source of
    the PNG/GIF renderers' frames and the HTML report's (gpmotion.report).

    Keys: ``dims`` (2: x–z, 3: x, y, z), ``segments`` [F, n_seg, 2, dims],
    ``radii``, ``times``, ``poles`` (x, z, r rows or None), ``ground_z`` (None:
    no ground), ``goal`` (None unless the task names it), ``goal_label``,
    ``events`` ([(frame, word)]), ``body_index`` (the segments kept by a 3-D
    view's ``bodies``, else all) and ``view`` (3-D camera settings left over).
    """
    if not 0 <= e < traj.n_episodes:
        raise ValueError(f"episode {e} out of range (the trajectory has {traj.n_episodes})")
    sc = traj.scene
    seg = traj.segments()[e]
    radii = traj.figure.model.seg_r
    poles = sc.poles if len(sc.poles) else None
    ground_z = sc.ground_z if sc.ground else None
    goal_label = getattr(task, "goal_label", None)
    events = motion_events(traj, e)
    if hasattr(task, "picture_events"):        # a task's own moments, e.g. "touch"
        events = sorted(events + list(task.picture_events(traj, e)))
    keep = np.arange(seg.shape[1])
    out = dict(dims=traj.figure.dimensions, times=traj.times, poles=poles, events=events,
               goal_label=goal_label, view={})
    if traj.figure.dimensions == 2:
        return dict(out, segments=seg, radii=radii, ground_z=ground_z, body_index=keep,
                    goal=tuple(sc.goal) if goal_label else None)
    if view is None:
        view = getattr(task, "view", None) or {}
    view = dict(view)
    bodies = view.pop("bodies", None)
    if bodies is not None:
        names = traj.figure.body_names
        unknown = [b for b in bodies if b not in names]
        if unknown:
            raise ValueError(f"view: unknown bodies {unknown}")
        keep = np.array([names.index(b) for b in bodies], dtype=int)
        seg, radii = seg[:, keep], radii[keep]
    if not view.pop("ground", True):
        ground_z = None
    goal = (float(sc.goal[0]), float(sc.goal_y), float(sc.goal[1])) if goal_label else None
    return dict(out, segments=seg, radii=radii, ground_z=ground_z, body_index=keep, goal=goal,
                view=view)


def render_any(traj, filmstrip=None, gif=None, title=None, e: int = 0, *, task=None,
               targets=None, view: dict | None = None, speed: float = 1.0) -> None:
    """Filmstrip PNG and/or GIF of episode ``e`` of a Trajectory: the planar
    renderer (:mod:`gpmotion.render`) for planar figures, the 3-D one otherwise.

    Scene: ground (if any) and limbo poles come from ``traj.scene``; the goal
    is drawn only when ``task`` names it (its ``goal_label``, e.g.
    "target"): a passive figure's scene has a placeholder goal at the origin
    that means nothing.  Filmstrip frames include the motion's take-offs,
    apexes, landings and pole passages (:func:`motion_events`) and the
    task's ``picture_events(traj, e)`` (``[(frame, word)]``) if it has them.  The GIF plays at ``speed``
    × real time.  ``targets`` (3-D only): extra points ``[n, 3]`` to mark.
    ``view`` (3-D only; default: the task's ``view``): camera
    ``elev``/``azim``, ``bodies`` to draw (a close-up: the axis limits follow
    them) and ``ground`` (False: no grid).
    """
    m = motion_frames(traj, e, task=task, view=view)
    seg, radii, events = m["segments"], m["radii"], m["events"]
    if m["dims"] == 2:
        from . import render
        kw = dict(poles=m["poles"], ground_z=m["ground_z"], title=title,
                  goal_label=m["goal_label"], goal=m["goal"])
        if filmstrip:
            render.filmstrip(filmstrip, seg, radii, traj.times, events=events, **kw)
        if gif:
            render.animate(gif, seg, radii, traj.times, speed=speed, **kw)
        return
    kw = dict(poles=m["poles"], ground_z=m["ground_z"], goal=m["goal"],
              goal_label=m["goal_label"], targets=targets, title=title, **m["view"])
    if filmstrip:
        filmstrip3d(filmstrip, seg, radii, traj.times, events=events, **kw)
    if gif:
        animate3d(gif, seg, radii, traj.times, speed=speed, **kw)
