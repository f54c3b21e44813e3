"""Composite controllers: saved controllers run in series (Auslander et al. §3).

A composite is an ordered list of saved controllers (any family, mixed
allowed) and the times at which one hands over to the next.  One episode runs
them in series in one world (one Scene) and the full physical state — joint
angles, position, orientation, velocities and the friction anchors of the
contact points — carries across every switch.  Each phase is a fresh rollout
from the previous phase's end, so a time-based controller's clock starts at
its switch and a sense-based one starts its rule memory fresh.

Switch times live on the frame grid (``dt × record_every``, the script's
tick): a batch of episodes may switch at different frames; each phase is one
batched rollout (each episode runs its own length), and episodes with the
same start and the same switches so far share one simulated episode.

File format (JSON, ``format: gpmotion-composite``, version 1)::

    {"format": "gpmotion-composite", "version": 1,
     "seconds": 3.5,                       # the whole motion (s)
     "phases": [{"name": "cartwheel", "controller": "runs/cart/best.json"},
                {"name": "limbo", "controller": "limbo.json",
                 "scene": {"poles": [[0.9, 0.3, 0.01]], "goal": [1.2, 0.0]}}, ...],
     "switches": [1.6, 2.5],               # P − 1 switch times (s), non-decreasing
     "scene": {"goal": [1.0, 0.0]}}        # optional make_scene settings for every phase

Scenes are per phase: a phase's own ``scene`` (make_scene settings), else the
file's ``scene``, else the scene of the phase's own task.  So a limbo pole is
in the world only while the limbo controller runs, and each phase's goal is
the one its controller steers to (GP senses positions relative to the goal).

Controller paths are relative to the composite file; each is read by the
same safe loader as ``gpmotion replay`` (no code runs).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..model import Scene, make_scene
from ..sim.rollout import Trajectory, rollout

KIND = "composite"
MAX_PHASES = 32
_SCENE_KEYS = {"gravity", "ground", "ground_z", "k_ground", "c_ground", "mu", "k_tangent", "c_tangent",
               "poles", "k_pole", "c_pole", "goal"}


class CompositeError(ValueError):
    """A bad composite (file or arguments): one line, the CLI exits 2."""


@dataclass
class Part:
    """One loaded controller of a composite."""
    name: str
    source: str             # the controller file, resolved (absolute)
    task: object
    family: object
    actuation: str
    genome: object

    def batch(self, n: int, genomes=None):
        """The controller encoded for n identical episodes (or ``genomes``, one an episode)."""
        if genomes is not None:
            return self.family.encode(list(genomes))
        one = self.family.encode([self.genome])
        return one._replace(ci=np.repeat(one.ci, n, axis=0), cf=np.repeat(one.cf, n, axis=0))


@dataclass
class Composite:
    parts: list[Part]
    switches: np.ndarray    # float[P − 1] seconds
    seconds: float
    scene: Scene                         # phase 1's (the whole motion's Trajectory carries it)
    scene_settings: dict | None = None   # as written in the file (None: each phase's task scene)
    scenes: list | None = None           # per phase (None: ``scene`` for all)
    phase_scene_settings: list | None = None   # per phase, as written (None entries: not given)

    def __post_init__(self):
        if self.scenes is None:
            self.scenes = [self.scene] * len(self.parts)
        if self.phase_scene_settings is None:
            self.phase_scene_settings = [None] * len(self.parts)

    @property
    def figure(self):
        return self.parts[0].task.figure

    @property
    def dt(self) -> float:
        return self.parts[0].task.dt

    @property
    def record_every(self) -> int:
        return self.parts[0].task.record_every

    @property
    def frame_seconds(self) -> float:
        return self.dt * self.record_every

    @property
    def n_frames(self) -> int:
        """Frames of the whole motion, both ends included."""
        return int(round(self.seconds / self.frame_seconds)) + 1

    def bounds(self, switches=None) -> np.ndarray:
        """Switch frames int[E, P + 1] (0 first, the last frame last) of switch times [E, P − 1] (s)."""
        sw = np.atleast_2d(self.switches if switches is None else np.asarray(switches, np.float64))
        P = len(self.parts)
        if sw.shape[1] != P - 1 or not np.all(np.isfinite(sw)):
            raise CompositeError(f"need {P - 1} finite switch time(s) per episode for {P} phases, got shape {sw.shape}")
        last = self.n_frames - 1
        frames = np.clip(np.rint(np.sort(sw, axis=1) / self.frame_seconds), 0, last).astype(np.int64)
        E = sw.shape[0]
        return np.concatenate([np.zeros((E, 1), np.int64), frames, np.full((E, 1), last)], axis=1)


# ------------------------------------------------------------------- building

def _check_parts(parts: list[Part]) -> None:
    first = parts[0].task
    for p in parts[1:]:
        if p.task.figure.name != first.figure.name:
            raise CompositeError(f"phase {p.name!r} controls figure {p.task.figure.name!r}, "
                                 f"phase {parts[0].name!r} {first.figure.name!r}: one composite, one figure")
        if p.task.dt != first.dt:
            raise CompositeError(f"phase {p.name!r} runs at dt {p.task.dt}, phase {parts[0].name!r} at {first.dt}")


def load_part(path, name: str | None = None, base: Path | None = None) -> Part:
    from ..replay import load_controller
    full = Path(path) if base is None or Path(path).is_absolute() else base / path
    task, family, actuation, genome, _ = load_controller(full)
    return Part(name or Path(path).stem, str(full.resolve()), task, family, actuation, genome)


def from_controllers(paths, switches=None, seconds=None, scene: dict | None = None, names=None) -> Composite:
    """A composite of controller files.  Default timing: each runs for its own task's seconds."""
    if not 1 <= len(paths) <= MAX_PHASES:
        raise CompositeError(f"a composite needs 1..{MAX_PHASES} controllers, got {len(paths)}")
    names = list(names) if names else [f"phase{k + 1}" for k in range(len(paths))]
    parts = [load_part(p, n) for p, n in zip(paths, names)]
    return assemble(parts, switches, seconds, scene)


def assemble(parts: list[Part], switches=None, seconds=None, scene: dict | None = None,
             phase_scenes: list | None = None) -> Composite:
    _check_parts(parts)
    own = np.cumsum([p.task.motion_seconds for p in parts])
    seconds = float(own[-1] if seconds is None else seconds)
    tick = parts[0].task.dt * parts[0].task.record_every
    if not (np.isfinite(seconds) and tick <= seconds <= 600):
        raise CompositeError(f"seconds must be in [{tick:g}, 600] (one frame at least), got {seconds}")
    sw = own[:-1] if switches is None else np.asarray(switches, dtype=np.float64).reshape(-1)
    if sw.shape != (len(parts) - 1,):
        raise CompositeError(f"{len(parts)} phases need {len(parts) - 1} switch time(s), got {sw.size}")
    if not np.all(np.isfinite(sw)) or np.any(np.diff(sw) < 0) or (sw.size and (sw[0] < 0 or sw[-1] > seconds)):
        raise CompositeError(f"switch times must be non-decreasing within [0, {seconds}] s, got {sw.tolist()}")
    phase_scenes = list(phase_scenes or [None] * len(parts))
    scenes = [_scene(own) if own is not None else _scene(scene) if scene is not None
              else p.task.scene_at(1.0) for p, own in zip(parts, phase_scenes)]
    return Composite(parts, sw.copy(), seconds, scenes[0], scene, scenes, phase_scenes)


def _scene(settings) -> Scene:
    if not isinstance(settings, dict):
        raise CompositeError("scene must be an object of make_scene settings")
    bad = sorted(set(settings) - _SCENE_KEYS)
    if bad:
        raise CompositeError(f"scene: unknown setting(s) {', '.join(bad)} (known: {', '.join(sorted(_SCENE_KEYS))})")
    try:
        return make_scene(**settings)
    except (TypeError, ValueError) as e:
        raise CompositeError(f"scene: {e}") from None


# ---------------------------------------------------------------- the file

def load(path) -> Composite:
    """Read a composite file; every problem is one line naming the file."""
    from ..records import read_json
    path = Path(path)
    obj = read_json(path, kind=KIND, max_bytes=1 << 20)
    try:
        return _from_obj(obj, path.parent)
    except CompositeError as e:
        raise CompositeError(f"{path}: {e}") from None
    except ValueError as e:           # a controller file's own FormatError names that file
        raise CompositeError(f"{path}: {(str(e).splitlines() or ['?'])[0]}") from None


def _from_obj(obj: dict, base: Path) -> Composite:
    unknown = sorted(set(obj) - {"format", "version", "seconds", "phases", "switches", "scene"})
    if unknown:
        raise CompositeError(f"unknown key(s) {', '.join(unknown)}")
    phases = obj.get("phases")
    if not isinstance(phases, list) or not 1 <= len(phases) <= MAX_PHASES:
        raise CompositeError(f"'phases' must be a list of 1..{MAX_PHASES} {{name, controller}} objects")
    parts, scenes = [], []
    for k, ph in enumerate(phases):
        if (not isinstance(ph, dict) or not isinstance(ph.get("controller"), str)
                or set(ph) - {"name", "controller", "scene"}):
            raise CompositeError(f"phases[{k}] must be {{\"name\": ..., \"controller\": \"path\"}} "
                                 "(and optionally \"scene\": {...})")
        scenes.append(ph.get("scene"))
        name = ph.get("name", f"phase{k + 1}")
        if not isinstance(name, str) or not name.isidentifier():
            raise CompositeError(f"phases[{k}].name must be a name (letters, digits, _), got {name!r}")
        parts.append(load_part(ph["controller"], name, base))
    seconds, switches = obj.get("seconds"), obj.get("switches")
    for key, v in (("seconds", seconds), ("switches", switches)):
        ok = v is None or (isinstance(v, (int, float)) and not isinstance(v, bool) if key == "seconds" else
                           isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v))
        if not ok:
            raise CompositeError(f"'{key}' must be {'a number' if key == 'seconds' else 'a list of numbers'}")
    try:
        return assemble(parts, switches, seconds, obj.get("scene"), scenes)
    except CompositeError as e:
        raise CompositeError(str(e)) from None


def to_obj(comp: Composite, base: Path | None = None) -> dict:
    """The file's object; controller paths relative to ``base`` (absolute without one)."""
    import os

    from ..records import envelope
    phases = [{"name": p.name, "controller": p.source if base is None else os.path.relpath(p.source, base),
               **({"scene": sc} if sc is not None else {})}
              for p, sc in zip(comp.parts, comp.phase_scene_settings)]
    obj = {"seconds": comp.seconds, "phases": phases, "switches": [float(s) for s in comp.switches]}
    if comp.scene_settings is not None:
        obj["scene"] = comp.scene_settings
    return envelope(KIND, obj)


def save(path, comp: Composite) -> None:
    """Write atomically; controller paths are written relative to the file's folder."""
    from ..records import atomic_write_json
    atomic_write_json(path, to_obj(comp, Path(path).resolve().parent))


# ---------------------------------------------------------------- running

_CHANNELS = ("q", "qd", "com", "contact_force", "pole_hit", "impact", "energy", "targets")


def run(comp: Composite, switches=None, q0=None, qd0=None, contact0=None,
        threads: int | None = None, variants: tuple | None = None) -> tuple[Trajectory, np.ndarray]:
    """Run the composite for every row of ``switches`` [E, P − 1] (s; default its own).

    ``variants`` = (k, genomes): episode e runs ``genomes[e]`` in phase k instead
    of the phase's own controller (``switches`` then defaults to E rows of the
    composite's own; a phase refinement scores its candidates so).
    Returns the whole-motion Trajectory [E, n_frames] and the switch frames
    ``bounds`` [E, P + 1].  An episode that diverges keeps its last good frame
    for the rest of the motion (as a single rollout does) and runs no later phase.
    """
    if variants is not None and switches is None:
        switches = np.tile(comp.switches, (len(variants[1]), 1))
    bounds = comp.bounds(switches)
    E, F, fig = bounds.shape[0], comp.n_frames, comp.figure
    vk, vgenomes = variants if variants is not None else (len(comp.parts), None)
    if vgenomes is not None and len(vgenomes) != E:
        raise CompositeError(f"{len(vgenomes)} phase-{vk} variants for {E} episodes")
    iq, iqd = comp.parts[0].task.initial_state()
    q = _rows(iq if q0 is None else q0, E, 1)
    qd = _rows(iqd if qd0 is None else qd0, E, 1)
    contact = None if contact0 is None else _rows(contact0, E, 2)
    out, written = None, np.full(E, -1, np.int64)        # last frame written per episode
    diverged, diverged_step = np.zeros(E, bool), np.full(E, -1, np.int64)
    start = _start_ids(q, qd, contact)
    for k, part in enumerate(comp.parts):
        dur = bounds[:, k + 1] - bounds[:, k]
        active = np.flatnonzero((dur > 0) & ~diverged)
        if active.size == 0:
            continue
        # episodes with the same start and the same switches so far have the same past and
        # this same phase: simulate one of them (a search's arrays often share a prefix)
        # (from the varied phase on, an episode's variant is part of its past)
        variant = active if k >= vk else np.zeros_like(active)
        keys = np.concatenate([start[active, None], bounds[active, :k + 2], variant[:, None]], axis=1)
        _, lead, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        reps = active[lead]
        rep_of = reps[inverse.reshape(-1)]                  # each active episode's representative
        batch = part.batch(len(reps), [vgenomes[i] for i in reps] if k == vk else None)
        tr = rollout(fig, comp.scenes[k], batch, n_steps=dur[reps] * comp.record_every,
                     q0=q[reps], qd0=qd[reps], contact0=None if contact is None else contact[reps],
                     dt=comp.dt, record_every=comp.record_every, actuation=part.actuation,
                     default_tau=part.family.default_tau, threads=threads)
        if out is None:
            out = {c: np.zeros((E, F) + getattr(tr, c).shape[2:]) for c in _CHANNELS}
            contact = np.zeros((E,) + tr.contact_end.shape[1:]) if contact is None else contact
        row = np.full(E, -1)
        row[reps] = np.arange(len(reps))
        rows = row[rep_of]                                    # rollout row of each active episode
        end = dur[active]                                     # its last frame in that rollout
        _paste(out, tr, rows, active, bounds[active, k], end, written)
        q[active], qd[active] = tr.q[rows, end], tr.qd[rows, end]
        contact[active] = tr.contact_end[rows]
        bad = tr.diverged[rows]
        diverged[active[bad]] = True
        diverged_step[active[bad]] = bounds[active[bad], k] * comp.record_every + tr.diverged_step[rows[bad]]
    _freeze(out, written)
    traj = Trajectory(figure=fig, scene=comp.scene, dt=comp.dt, record_every=comp.record_every,
                      times=np.arange(F) * comp.frame_seconds, senses=None, diverged=diverged,
                      diverged_step=diverged_step, contact_end=contact, **out)
    return traj, bounds


def _rows(x, E: int, nd: int) -> np.ndarray:
    """x (one episode's [..nd dims] or E of them) as a C-contiguous [E, ...] copy."""
    x = np.asarray(x, dtype=np.float64)
    return np.array(np.broadcast_to(x, (E,) + x.shape[x.ndim - nd:]), order="C")


def _paste(out: dict, tr: Trajectory, rows, idx, start, end, written) -> None:
    """Frames 1..end[j] of rollout row ``rows[j]`` after episode ``idx[j]``'s switch frame (frame 0
    repeats the switch frame the previous phase recorded; the motion's very first frame is its own)."""
    for j, e in enumerate(idx):
        lo = 0 if written[e] < 0 else 1
        for c in _CHANNELS:
            out[c][e, start[j] + lo:start[j] + end[j] + 1] = getattr(tr, c)[rows[j], lo:end[j] + 1]
        written[e] = start[j] + end[j]


def _start_ids(q, qd, contact) -> np.ndarray:
    """An id per episode; equal ids: the same initial state."""
    parts = [q, qd] + ([] if contact is None else [contact.reshape(len(q), -1)])
    _, ids = np.unique(np.concatenate(parts, axis=1), axis=0, return_inverse=True)
    return ids.reshape(-1)


def _freeze(out: dict, written) -> None:
    """After a divergence: the last good pose, no velocity, no events (the rollout's convention)."""
    F = out["q"].shape[1]
    for e in np.flatnonzero(written < F - 1):
        w = written[e]
        for c in ("q", "com", "targets"):
            out[c][e, w + 1:] = out[c][e, w]
        for c in ("qd", "contact_force", "pole_hit", "impact", "energy"):
            out[c][e, w + 1:] = 0.0
