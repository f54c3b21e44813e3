"""A composite through the usual commands: ``gpmotion replay / render / export COMPOSITE.json``.

``cli.py`` asks :func:`is_composite` of the source and hands the command to
the functions here.  The motion is simulated once (:func:`gpmotion.compose.composite.run`);
pictures show each phase in its own scene (a limbo pole only while the limbo
controller runs): the filmstrip is one strip per phase, stacked; the GIF plays
the phases one after another.
"""
from __future__ import annotations

import json
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from . import composite as C

_FRAME_CHANNELS = ("q", "qd", "com", "contact_force", "pole_hit", "impact", "energy", "targets")


def is_composite(source) -> bool:
    """True if ``source`` is a composite file (its JSON ``format`` says so); parsed, never run."""
    p = Path(str(source))
    if not p.is_file() or p.stat().st_size > (1 << 20):
        return False
    from ..records import FormatError, read_text
    try:
        obj = json.loads(read_text(p, 1 << 20))          # a regular file, never a FIFO's wait
    except (FormatError, json.JSONDecodeError, RecursionError):
        return False
    return isinstance(obj, dict) and obj.get("format") == f"gpmotion-{C.KIND}"


def simulate(source):
    """(composite, whole-motion Trajectory [1 episode], switch frames [P + 1])."""
    comp = C.load(source)
    traj, bounds = C.run(comp)
    return comp, traj, bounds[0]


def phase_slice(traj, comp, bounds, k: int):
    """Frames of phase k (both switch frames) as a Trajectory in that phase's scene."""
    a, b = int(bounds[k]), int(bounds[k + 1])
    cut = {c: getattr(traj, c)[:, a:b + 1] for c in _FRAME_CHANNELS}
    return replace(traj, scene=comp.scenes[k], times=traj.times[a:b + 1], senses=None, **cut)


def phase_rows(comp, traj, bounds) -> list[dict]:
    """Per phase: its controller, window and what the figure did in it."""
    from ..bsr import secondary
    rows = []
    for k, part in enumerate(comp.parts):
        a, b = int(bounds[k]), int(bounds[k + 1])
        com = traj.com[0, a:b + 1]
        height = com[:, -3] if traj.is3d else com[:, 1]
        row = {"phase": part.name, "task": part.task.name, "family": part.family.name,
               "start_s": float(traj.times[a]), "end_s": float(traj.times[b]),
               "dcm_x": float(com[-1, 0] - com[0, 0]) if b > a else 0.0,
               "max_com_height": float(height.max()), "pole_hit": float(traj.pole_hit[0, a:b + 1].max())}
        if not traj.is3d and b > a:
            row["rotations"] = float(secondary.rotations(traj.base()[0, a:b + 1, 0], whole=False))
        rows.append(row)
    return rows


def replay(args) -> int:
    comp, traj, bounds = simulate(args.source)
    rows = phase_rows(comp, traj, bounds)
    if getattr(args, "json", False):
        print(json.dumps({"composite": str(args.source), "seconds": comp.seconds,
                          "switches": comp.switches.tolist(), "diverged": bool(traj.diverged[0]),
                          "phases": rows}))
    else:
        print(f"{args.source}: composite of {len(comp.parts)} phases, {comp.seconds:g} s, switches "
              f"{np.round(comp.switches, 3).tolist()} s{'  DIVERGED' if traj.diverged[0] else ''}")
        print(f"  {'phase':<12} {'controller':<28} {'window (s)':>13} {'Δcm_x':>8} {'max cm z':>9} "
              f"{'turns':>6} {'pole hit':>9}")
        for r in rows:
            ctl = f"{r['task']} ({r['family']})"
            print(f"  {r['phase']:<12} {ctl:<28} {r['start_s']:>6.2f}–{r['end_s']:<6.2f} {r['dcm_x']:>8.3f} "
                  f"{r['max_com_height']:>9.3f} {r.get('rotations', float('nan')):>6.2f} {r['pole_hit']:>9.4f}")
    if getattr(args, "out", None):
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        render(comp, traj, bounds, out / "filmstrip.png", out / "motion.gif")
        print(f"  wrote {out / 'filmstrip.png'} and {out / 'motion.gif'}")
    return 0


def render_command(args) -> int:
    if getattr(args, "trees", None):
        raise ValueError("--trees needs one GP controller, not a composite")
    if getattr(args, "seconds", None) is not None:
        raise ValueError("--seconds applies to --figure; a composite runs its own 'seconds'")
    comp, traj, bounds = simulate(args.source)
    render(comp, traj, bounds, args.output, args.gif)
    print(f"wrote {args.output}" + (f" and {args.gif}" if args.gif else ""))
    return 0


def export_command(args) -> int:
    from ..bvh import write_bvh
    from ..records import validate_number
    validate_number("--scale", args.scale, lo=1e-6, hi=1e6)
    comp, traj, bounds = simulate(args.source)
    n = write_bvh(args.bvh, traj, scale=args.scale)
    print(f"wrote {args.bvh}: {len(traj.figure.body_names)} joints, {n} frames at "
          f"{1 / (traj.dt * traj.record_every):g} fps — {len(comp.parts)} phases, switches "
          f"{np.round(comp.switches, 3).tolist()} s")
    if traj.diverged[0]:
        print("  the simulation diverged: the frames after it are not written")
    return 0


def render(comp, traj, bounds, filmstrip=None, gif=None) -> None:
    """Filmstrip (one strip per phase, stacked) and/or GIF (phase after phase), each phase in its scene."""
    from ..render3d import render_any
    phases = [k for k in range(len(comp.parts)) if bounds[k + 1] > bounds[k]]
    with tempfile.TemporaryDirectory() as tmp:
        strips, gifs = [], []
        for k in phases:
            sub = phase_slice(traj, comp, bounds, k)
            part = comp.parts[k]
            title = (f"{k + 1}. {part.name}: {part.task.name} ({part.family.name}), "
                     f"{sub.times[0]:.2f}–{sub.times[-1]:.2f} s")
            png = Path(tmp) / f"{k}.png" if filmstrip else None
            anim = Path(tmp) / f"{k}.gif" if gif else None
            render_any(sub, png, anim, title=title, task=part.task)
            strips.append(png)
            gifs.append(anim)
        if filmstrip:
            _stack(filmstrip, strips)
        if gif:
            _chain(gif, gifs)


def _stack(path, pngs) -> None:
    from PIL import Image

    from ..records import atomic_output
    images = [Image.open(p).convert("RGB") for p in pngs]
    width = max(im.width for im in images)
    out = Image.new("RGB", (width, sum(im.height for im in images)), "white")
    y = 0
    for im in images:
        out.paste(im, (0, y))
        y += im.height
    with atomic_output(path) as tmp:
        out.save(tmp, format="PNG")


def _chain(path, gifs) -> None:
    from PIL import Image, ImageSequence

    from ..records import atomic_output
    frames, durations, size = [], [], None
    for g in gifs:
        with Image.open(g) as im:
            for fr in ImageSequence.Iterator(im):
                f = fr.convert("RGB")
                size = size or f.size
                frames.append(f if f.size == size else f.resize(size))
                durations.append(fr.info.get("duration", 40))
    with atomic_output(path) as tmp:
        frames[0].save(tmp, format="GIF", save_all=True, append_images=frames[1:], duration=durations, loop=0)
