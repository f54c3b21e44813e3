"""What a GP tree's output means, joint by joint (``--targets``, ``GPSettings.targets``).

A spec is a comma list: at most one mode for every controlled joint (default
``angle``) and any number of ``JOINT=MODE`` exceptions, e.g.
``rate,elbow_r=angle,wrist_r_y=angle``: the shoulder's trees give target
rates (integral action against the arm's weight) while the elbow's and the
wrist's give angles (a constant tree holds an angle, where a constant rate
runs its target into a joint limit).  The modes are ``TARGET_MODES``.
"""
from __future__ import annotations

from .opcodes import TARGET_MODES


def parse(spec) -> tuple[str, dict[str, str]]:
    """``spec`` -> (the mode of every joint not named, {joint: mode})."""
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError(f"GP targets must be a mode ({', '.join(TARGET_MODES)}) or a comma list "
                         f"MODE,JOINT=MODE,...; got {spec!r}")
    default, named = None, {}
    for part in (p.strip() for p in spec.split(",")):
        joint, eq, mode = (s.strip() for s in part.partition("="))
        if not eq:
            joint, mode = "", joint
        if mode not in TARGET_MODES:
            raise ValueError(f"GP targets {spec!r}: unknown mode {mode!r} (modes: {', '.join(TARGET_MODES)})")
        if not eq and default is not None:
            raise ValueError(f"GP targets {spec!r}: two modes for every joint ({default}, {mode})")
        if eq and (not joint or joint in named):
            raise ValueError(f"GP targets {spec!r}: {'a joint named twice' if joint else 'JOINT=MODE needs a joint'}")
        if eq:
            named[joint] = mode
        else:
            default = mode
    return default or "angle", named


def joint_modes(spec, joints) -> tuple[str, ...]:
    """The mode of each of ``joints`` (the controlled joints' names, in order)."""
    default, named = parse(spec)
    unknown = [j for j in named if j not in joints]
    if unknown:
        raise ValueError(f"GP targets {spec!r} name joint(s) GP does not control: {', '.join(unknown)} "
                         f"(controlled: {', '.join(joints)})")
    return tuple(named.get(j, default) for j in joints)


_NOTES = {"angle": "target angles", "rate": "target rates", "pi": "angles, PI-corrected"}


def note(spec) -> str:
    """One line for a run's banner: what the trees give."""
    default, named = parse(spec)
    extra = "".join(f", {j}: {_NOTES[m]}" for j, m in named.items())
    return f"trees give {_NOTES[default]}{extra}"


def describe(spec) -> str:
    """``gpmotion show``'s line: the spec and what each mode in it means."""
    default, named = parse(spec)
    modes = dict.fromkeys([default, *named.values()])
    return f"{spec} (" + "; ".join(f"{m}: {TARGET_MODES[m]}" for m in modes) + ")"
