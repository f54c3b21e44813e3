"""``gpmotion replay``, ``render`` and ``export``: a saved controller re-simulated, drawn or written as BVH."""
from __future__ import annotations

from pathlib import Path

from .common import _activate_plugins
from .runs import refuse_series


def cmd_replay(args):
    from ..replay import load_controller, replay_genome
    from ..run import render_trajectory
    _activate_plugins(args)
    from ..compose import playback                       # a composite file: its phases in series
    if playback.is_composite(args.source):
        return playback.replay(args)
    refuse_series(Path(args.source), "replay")
    task, family, actuation, genome, _ = load_controller(args.source)
    traj, costs, measures, ok = replay_genome(task, family, actuation, genome)
    if args.json:
        import json
        print(json.dumps({"task": task.name, "family": family.name, "actuation": actuation,
                          "cost": float(costs[0]), "success": bool(ok[0]),
                          "diverged": bool(traj.diverged[0]),
                          "terms": task.breakdown(measures, 0, 1.0),
                          "facts": task.describe(traj, measures)}))
    else:
        _print_replay(task, family, actuation, traj, costs, measures, ok)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        render_trajectory(traj, out / "filmstrip.png", out / "motion.gif", title=task.name, task=task)
        print(f"  wrote {out / 'filmstrip.png'} and {out / 'motion.gif'}")
        if family.plot_file:
            family.plot(out / family.plot_file, genome)


def _verdict(task, ok: bool) -> str:
    """SOLVED / not solved with the test's threshold, or that the task has no test."""
    from ..task import Task
    if type(task).success is Task.success:
        return "no success test"
    threshold = task.success_threshold
    return ("SOLVED" if ok else "not solved") + (f"  [{threshold}]" if threshold else "")


def _print_replay(task, family, actuation, traj, costs, measures, ok):
    print(f"{task.name} ({family.name}, {actuation}): cost {costs[0]:.4f}  {_verdict(task, ok[0])}")
    print(f"  {'term':<16} {'value':>10} {'weight':>8} {'phase':>6} {'contribution':>13}")
    for r in task.breakdown(measures, 0, 1.0):
        print(f"  {r['term']:<16} {r['value']:>10.4f} {r['weight']:>8.3f} {r['phase']:>6.2f} "
              f"{r['contribution']:>13.4f}{'  (main)' if r['main'] else ''}")
    for fact in task.describe(traj, measures):
        print(f"  {fact}")
    if traj.diverged[0]:
        print("  the simulation diverged")


def cmd_render(args):
    from ..run import render_trajectory
    if bool(args.source) == bool(args.figure):
        raise ValueError("render: give a run directory/controller file or --figure NAME (one)")
    if args.figure and args.trees:
        raise ValueError("--trees draws a controller's structure, not a --figure's")
    if args.source and args.seconds is not None:
        raise ValueError("--seconds applies to --figure; a controller runs its task's episode "
                         "(the task's 'seconds' parameter)")
    _activate_plugins(args)
    from ..compose import playback
    if args.source and playback.is_composite(args.source):
        return playback.render_command(args)
    if args.figure:
        from .. import load_figure, simulate
        from ..records import validate_number
        seconds = validate_number("--seconds", 2.0 if args.seconds is None else args.seconds,
                                  lo=0.01, hi=120)
        fig = load_figure(args.figure)
        traj = simulate(fig, seconds)
        title, task = f"{fig.name}: holding its neutral pose", None
    else:
        from ..replay import load_controller, replay_genome
        refuse_series(Path(args.source), "render")
        task, family, actuation, genome, _ = load_controller(args.source)
        traj = replay_genome(task, family, actuation, genome)[0]
        title = f"{task.name} ({family.name})"
        if args.trees:
            family.plot(args.trees, genome)       # a family with nothing to draw says so
            print(f"wrote {args.trees}")
    render_trajectory(traj, args.output, args.gif, title=title, task=task)
    print(f"wrote {args.output}" + (f" and {args.gif}" if args.gif else ""))


def cmd_export(args):
    from ..bvh import write_bvh
    from ..records import validate_number
    from ..replay import load_controller, replay_genome
    validate_number("--scale", args.scale, lo=1e-6, hi=1e6)
    _activate_plugins(args)
    from ..compose import playback
    if playback.is_composite(args.source):
        return playback.export_command(args)
    refuse_series(Path(args.source), "export")
    task, family, actuation, genome, _ = load_controller(args.source)
    traj = replay_genome(task, family, actuation, genome)[0]
    n = write_bvh(args.bvh, traj, scale=args.scale)
    print(f"wrote {args.bvh}: {len(traj.figure.body_names)} joints, {n} frames at "
          f"{1 / (traj.dt * traj.record_every):g} fps (y-up, units of 1/{args.scale:g} m)")
    if traj.diverged[0]:
        print("  the simulation diverged: the frames after it are not written")
