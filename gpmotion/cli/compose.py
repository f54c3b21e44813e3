"""``gpmotion compose``: chain saved controllers and search their switch times with a script.

    gpmotion compose SCRIPT --controllers A.json B.json C.json [--transitions 1.6,2.5]
    gpmotion compose SCRIPT --composite careless.json [--out DIR] [--resume]
    gpmotion compose SCRIPT --controllers ... --no-search        # score the given switches only
    gpmotion compose SCRIPT --controllers ... --refine limbo     # then refine a phase's controller

``python -m gpmotion.compose`` runs the same command.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

HELP = "chain saved controllers; search their switch times with a composite-motion script"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("script", help="composite-motion script (Table 4 language; docs/howto/composite.md)")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--controllers", nargs="+", metavar="CTRL",
                     help="saved controllers (best.json or run directories), one per script phase")
    src.add_argument("--composite", metavar="FILE", help="a gpmotion-composite file instead")
    p.add_argument("--transitions", metavar="T1,T2,...",
                   help="initial switch times (s); default: each controller runs its own task's duration")
    p.add_argument("--seconds", type=float, help="length of the whole motion (s)")
    p.add_argument("--arrays", type=int, default=16, metavar="Q", help="transition-point arrays (default 16)")
    p.add_argument("--rounds", type=int, default=16, metavar="G", help="rounds (default 16)")
    p.add_argument("--mutations", type=int, default=4, metavar="H", help="mutations per array per round (default 4)")
    p.add_argument("--perturb", type=float, help="σ of a perturbation (s; default 5%% of the motion)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", help="run directory (default runs/compose-SCRIPT-seedN)")
    p.add_argument("--resume", action="store_true", help="continue the run directory's search")
    p.add_argument("--no-search", action="store_true", help="only score the given switch times")
    p.add_argument("--refine", metavar="PHASE,...",
                   help="after the search, refine these phases' controllers in place: a (1 + λ) "
                        "climb from each, scored by the whole composite (off by default)")
    p.add_argument("--refine-rounds", type=int, metavar="R", help="rounds of each refinement (default 16)")
    p.add_argument("--refine-mutants", type=int, metavar="M",
                   help="mutants of the incumbent a round (default 16)")
    p.add_argument("--no-artifacts", action="store_true", help="skip the filmstrips")
    p.add_argument("--quiet", action="store_true")


def _floats(text: str | None, what: str):
    if text is None:
        return None
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"{what} must be a comma list of numbers, got {text!r}") from None


def run_command(args) -> int:
    from ..compose import composite as C
    from ..compose import optimize, session
    from ..compose import script as S
    from ..records import read_text, validate_number
    validate_number("--seed", args.seed, lo=0, hi=2**32 - 1, integer=True)
    script = S.load(args.script)
    text = read_text(args.script, 1 << 20)
    switches = _floats(args.transitions, "--transitions")
    if args.composite:
        comp = C.load(args.composite)
        if switches is not None or args.seconds is not None:
            comp = C.assemble(comp.parts, comp.switches if switches is None else switches,
                              args.seconds or comp.seconds, comp.scene_settings, comp.phase_scene_settings)
    else:
        if len(args.controllers) != script.n_phases:
            raise C.CompositeError(f"the script has {script.n_phases} phase(s) ({', '.join(script.phases)}) "
                                   f"but {len(args.controllers)} controller(s) were given")
        comp = C.from_controllers(args.controllers, switches, args.seconds, names=script.phases)
    optimize.check_match(comp, script)
    refine = _refine_settings(args, script)
    say = (lambda m: None) if args.quiet else print
    if args.no_search:
        totals, credits, traj, _ = optimize.score(comp, script, [comp.switches])
        print(f"switches {comp.switches.tolist()} s: total {totals[0]:.6g}  "
              + "  ".join(f"{k} {credits[k][0]:.6g}" for k in script.phases))
        return 0
    out = Path(args.out or f"runs/compose-{Path(args.script).stem}-seed{args.seed}")
    if args.out is not None and not args.out.strip():
        raise ValueError(f"--out must name a folder, got {args.out!r}")
    result = session.compose_run(out, text, comp, Q=args.arrays, G=args.rounds, H=args.mutations,
                                 seed=args.seed, perturb=args.perturb, resume=args.resume, log=say,
                                 refine=refine)
    for key in ("careless", "searched", "best") if refine else ("careless", "best"):
        r = result[key]
        print(f"{key}: switches {r['switches']} s  total {r['total']}  "
              + "  ".join(f"{k} {v:.4g}" if v is not None else f"{k} -" for k, v in r["credits"].items()))
    if not args.no_artifacts:
        _filmstrips(out, comp, C.load(out / "composite.json"))
    print(f"wrote {out}/composite.json ({result['simulations']} simulations)")
    return 0


def _refine_settings(args, script) -> dict | None:
    """The --refine settings, or None; an option that cannot apply is an error."""
    from ..compose import composite as C
    if args.refine is None:
        extra = [f for f, v in (("--refine-rounds", args.refine_rounds),
                                ("--refine-mutants", args.refine_mutants)) if v is not None]
        if extra:
            raise C.CompositeError(f"{', '.join(extra)} needs --refine PHASE,...")
        return None
    if args.no_search:
        raise C.CompositeError("--refine refines after the search; it does not apply with --no-search")
    phases = [p.strip() for p in args.refine.split(",") if p.strip()]
    unknown = [p for p in phases if p not in script.phases]
    if not phases or unknown:
        raise C.CompositeError(f"--refine names {unknown or 'no phase'}; the script's phases: "
                               f"{', '.join(script.phases)}")
    for flag, v in (("--refine-rounds", args.refine_rounds), ("--refine-mutants", args.refine_mutants)):
        if v is not None and not 1 <= v <= 10_000:
            raise C.CompositeError(f"{flag} must be in 1..10000, got {v}")
    return {"phases": phases, "rounds": args.refine_rounds or 16, "mutants": args.refine_mutants or 16}


def _filmstrips(out: Path, careless, best) -> None:
    from ..render3d import render_any
    from ..compose import composite as C
    for name, comp in (("careless", careless), ("composite", best)):
        traj, _ = C.run(comp)
        render_any(traj, out / f"{name}.png", None, title=f"{name}: switches {comp.switches.round(2).tolist()} s")


def main(argv=None) -> int:
    """``python -m`` entry: the same as ``gpmotion compose ...`` (one error path, in cli.main)."""
    from . import main as cli_main
    return cli_main(["compose", *(sys.argv[1:] if argv is None else argv)])
