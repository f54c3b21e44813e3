"""BVH (Biovision Hierarchy) export of a trajectory, for animators (Blender etc.).

``write_bvh(path, traj, e=0)`` writes episode ``e`` of a planar or 3-D
:class:`~gpmotion.sim.rollout.Trajectory`; ``read_bvh(path)`` is a small,
independent parser (used by the tests, handy for scripts).

Conventions (the same for planar and 3-D figures)
-------------------------------------------------
* **Skeleton.** One BVH joint per *body* of the figure, named after the body;
  the root joint is the figure's root body.  A body's BVH joint sits at the
  origin of the body's frame (the joint that attaches it); the massless
  intermediate links of an ``euler`` joint are folded into it.  Every leaf
  body ends in an ``End Site`` at the tip of its capsule segment (the segment
  end farther from the body's origin).
* **Channels.** The root: ``Xposition Yposition Zposition Zrotation Xrotation
  Yrotation``; every other joint: ``Zrotation Xrotation Yrotation``.  The
  rotations are computed from the recorded world poses (the rotation of a
  body relative to its parent), so this works for any joint type — hinges
  about arbitrary axes, Euler chains in any order, fixed rest rotations —
  without mapping joint coordinates to channels one to one.  A body on a
  ``slide`` joint (3-D specs) also gets position channels.
  BVH semantics: a joint's local transform is ``T(offset) · Rz(z) · Rx(x) ·
  Ry(y)`` (channel order, angles in **degrees**, right-handed, BVH axes).
  Every joint that has position channels has ``OFFSET 0 0 0`` and its
  position channels hold the full translation, so readers that *add* the
  channels to the offset and readers that *replace* the offset with them
  (Blender) agree.
* **Axes.** gpmotion is z-up (x forward, y left); BVH is y-up.  A point
  (x, y, z) of ours is (x, z, −y) in the file — a proper rotation (−90° about
  x).  Blender's BVH importer with its defaults (forward −Z, up Y) maps it
  back, so the figure appears in Blender exactly where it was simulated.
  Planar figures are lifted to 3-D as (x, 0, z) with their rotations about
  −y (the planar CCW convention), which is +Z in the file: a planar motion
  shows up as Zrotation channels only.
* **Units.** Lengths are centimetres (``scale=100``; pass ``scale=1`` for
  metres).  In Blender, import with *Scale* 0.01 to get metres back.
* **Rest pose.** All channels zero (Blender's edit-mode skeleton) is the
  figure with every joint coordinate zero — the spec's rest geometry, joint
  rest rotations included — with the root at the origin, unrotated.
  OFFSETs are that rest geometry, in the parent's (world-aligned) BVH frame.
* **Motion.** ``Frames`` = recorded frames, ``Frame Time`` = dt ×
  record_every.  Euler angles are kept continuous over time (no ±180° jumps).
  A diverged episode is written up to its last finite frame; no finite frame
  at all is a ValueError.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .records import atomic_write_text
from .sim.backend import backend_of

# our z-up (x, y, z) → BVH y-up (x, z, −y)
TO_BVH = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
ROT_CHANNELS = ("Zrotation", "Xrotation", "Yrotation")


# ------------------------------------------------------------- skeleton

@dataclass
class _Body:
    name: str
    link: int                 # model link that carries the body (-1: fixed root)
    parent: int               # parent body index (-1: root)
    slide: bool = False       # a slide joint between this body and its parent
    children: list = field(default_factory=list)


def _skeleton(figure) -> tuple[list[_Body], int]:
    """Bodies with their parent bodies (derived from the model's link tree)."""
    m = figure.model
    seg_link = [int(x) for x in m.seg_link]
    link_body = {L: b for b, L in enumerate(seg_link)}
    root = link_body.get(int(m.base_link))
    if root is None:
        raise ValueError(f"figure {figure.name!r}: no body on the base link")
    backend = backend_of(m)
    bodies = []
    for b, (name, L) in enumerate(zip(figure.body_names, seg_link)):
        bname = re.sub(r"\s+", "_", str(name)) or f"body{b}"
        if b == root:
            bodies.append(_Body(bname, L, -1))
            continue
        slide, p = False, L
        while True:
            if backend.slides(m, p):
                slide = True
            p = int(m.parent[p])
            if p < 0 or p in link_body:
                break
        if p not in link_body:
            raise ValueError(f"figure {figure.name!r}: body {name!r} is not attached to the root body")
        bodies.append(_Body(bname, L, link_body[p], slide))
    for b, body in enumerate(bodies):
        if body.parent >= 0:
            bodies[body.parent].children.append(b)
    return bodies, root


def body_frames(figure, q: np.ndarray):
    """World rotation [..., n_bodies, 3, 3] and origin [..., n_bodies, 3] of every
    body's frame (planar figures lifted to (x, 0, z), rotations about −y)."""
    m = figure.model
    R, P = backend_of(m).world_frames(m, np.asarray(q, dtype=np.float64))
    links = np.asarray(m.seg_link, dtype=np.int64)
    return R[..., links, :, :], P[..., links, :]


def _reference_q(figure) -> np.ndarray:
    """Every joint coordinate zero; a free root at the origin, unrotated."""
    return backend_of(figure.model).reference_q(figure.model)


# ---------------------------------------------------------- Euler angles

def _zxy(M: np.ndarray) -> np.ndarray:
    """(z, x, y) [..., 3] with M = Rz(z)·Rx(x)·Ry(y) (radians)."""
    x = np.arcsin(np.clip(M[..., 2, 1], -1.0, 1.0))
    z = np.arctan2(-M[..., 0, 1], M[..., 1, 1])
    y = np.arctan2(-M[..., 2, 0], M[..., 2, 2])
    return np.stack([z, x, y], -1)


def _continuous_zxy(M: np.ndarray) -> np.ndarray:
    """ZXY Euler angles [F, 3] of rotations M[F, 3, 3], continuous over frames:
    of the two solutions (z, x, y) and (z+π, π−x, y+π), each shifted by whole
    turns toward the previous frame, the nearer one is kept."""
    a = _zxy(M)
    alt = np.stack([a[:, 0] + np.pi, np.pi - a[:, 1], a[:, 2] + np.pi], -1)
    out = np.empty_like(a)
    prev = None
    for f in range(len(a)):
        cands = (a[f], alt[f])
        if prev is None:
            out[f] = cands[0]
            # start in (-180°, 180°]
            out[f] = (out[f] + np.pi) % (2 * np.pi) - np.pi
        else:
            best = None
            for c in cands:
                c = c + 2 * np.pi * np.round((prev - c) / (2 * np.pi))
                d = float(np.abs(c - prev).sum())
                if best is None or d < best[0] - 1e-12:
                    best = (d, c)
            out[f] = best[1]
        prev = out[f]
    return out


# ---------------------------------------------------------------- writer

def _fmt(v) -> str:
    s = f"{float(v):.6f}"
    return "0.000000" if s == "-0.000000" else s


def write_bvh(path, traj, e: int = 0, *, scale: float = 100.0) -> int:
    """Write episode ``e`` of ``traj`` as a BVH file; returns the frame count.

    Lengths are multiplied by ``scale`` (default 100: centimetres); see the
    module docstring for the axes, channels and rest-pose conventions.
    """
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a finite number > 0, got {scale!r}")
    if not 0 <= e < traj.n_episodes:
        raise ValueError(f"episode {e} out of range (the trajectory has {traj.n_episodes})")
    fig = traj.figure
    m = fig.model
    bodies, root = _skeleton(fig)
    q = np.asarray(traj.q[e], dtype=np.float64)
    finite = np.isfinite(q).all(axis=1)
    n_ok = int(np.argmin(finite)) if not finite.all() else len(q)
    if n_ok == 0:
        raise ValueError("write_bvh: the first frame is not finite; nothing to export")
    q = q[:n_ok]

    # rest geometry: A_k (rest orientation relative to the root) and the
    # joint offsets o_k in the parent body's frame
    Rr, Pr = body_frames(fig, _reference_q(fig))
    A = np.einsum("ba,kbc->kac", Rr[root], Rr)
    A[root] = np.eye(3)
    # world frames over the recorded frames: G_k = R_k A_kᵀ (the BVH joint frame)
    R, P = body_frames(fig, q)                       # [F, nb, 3, 3], [F, nb, 3]
    G = np.einsum("fkab,kcb->fkac", R, A)
    C = TO_BVH

    chan_cols = []    # per body: array [F, n_channels]
    offsets = []
    for k, body in enumerate(bodies):
        if body.parent < 0:
            local = G[:, k]
            pos = P[:, k] @ C.T * scale
            offsets.append(np.zeros(3))
        else:
            p = body.parent
            local = np.einsum("fba,fbc->fac", G[:, p], G[:, k])
            if body.slide:
                t = np.einsum("fba,fb->fa", G[:, p], P[:, k] - P[:, p])
                pos = t @ C.T * scale
                offsets.append(np.zeros(3))
            else:
                o = Rr[p].T @ (Pr[k] - Pr[p])
                offsets.append(C @ (A[p] @ o) * scale)
                pos = None
        ang = np.degrees(_continuous_zxy(C @ local @ C.T))
        chan_cols.append(ang if pos is None else np.concatenate([pos, ang], axis=1))

    def tip(k):
        a, b = np.asarray(m.seg_a[k], float), np.asarray(m.seg_b[k], float)
        if a.shape[-1] == 2:
            a, b = np.array([a[0], 0.0, a[1]]), np.array([b[0], 0.0, b[1]])
        s = b if np.linalg.norm(b) >= np.linalg.norm(a) else a
        return C @ (A[k] @ s) * scale

    lines = ["HIERARCHY"]
    order = []

    def emit(k, depth):
        ind = "  " * depth
        body = bodies[k]
        kw = "ROOT" if body.parent < 0 else "JOINT"
        chans = (ROOT_CHANNELS if (body.parent < 0 or body.slide) else ROT_CHANNELS)
        lines.append(f"{ind}{kw} {body.name}")
        lines.append(f"{ind}{{")
        lines.append(f"{ind}  OFFSET {' '.join(_fmt(v) for v in offsets[k])}")
        lines.append(f"{ind}  CHANNELS {len(chans)} {' '.join(chans)}")
        order.append(k)
        if body.children:
            for c in body.children:
                emit(c, depth + 1)
        else:
            lines.append(f"{ind}  End Site")
            lines.append(f"{ind}  {{")
            lines.append(f"{ind}    OFFSET {' '.join(_fmt(v) for v in tip(k))}")
            lines.append(f"{ind}  }}")
        lines.append(f"{ind}}}")

    emit(root, 0)
    frames = np.concatenate([chan_cols[k] for k in order], axis=1)
    lines.append("MOTION")
    lines.append(f"Frames: {len(frames)}")
    lines.append(f"Frame Time: {traj.dt * traj.record_every:.6f}")
    lines.extend(" ".join(_fmt(v) for v in row) for row in frames)
    atomic_write_text(path, "\n".join(lines) + "\n")
    return len(frames)


# ---------------------------------------------------------------- reader

@dataclass
class BvhJoint:
    name: str
    parent: int                   # index into BvhFile.joints, -1 for the root
    offset: np.ndarray            # float[3]
    channels: list[str]
    end_site: np.ndarray | None   # End Site offset, if any
    first_channel: int = 0        # column of its first channel in BvhFile.frames


@dataclass
class BvhFile:
    joints: list[BvhJoint]        # in file order (parents first)
    frame_time: float
    frames: np.ndarray            # float[F, total channels]

    def joint(self, name: str) -> BvhJoint:
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(f"no joint {name!r}; joints: {', '.join(j.name for j in self.joints)}")

    def channel(self, name: str, channel: str) -> np.ndarray:
        """Values [F] of one channel of one joint."""
        j = self.joint(name)
        return self.frames[:, j.first_channel + j.channels.index(channel)]

    @property
    def n_frames(self) -> int:
        return self.frames.shape[0]


_VALID_CHANNELS = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"}


def read_bvh(path) -> BvhFile:
    """Parse a BVH file (single root, any channels); a malformed file is a ValueError."""
    text = Path(path).read_text()
    toks = text.split()
    pos = 0

    def word(desc=None):
        """The next token, whatever it is."""
        nonlocal pos
        if pos >= len(toks):
            raise ValueError(f"{path}: unexpected end of file" + (f" (expected {desc})" if desc else ""))
        pos += 1
        return toks[pos - 1]

    def take(literal=None):
        """The next token, which must be ``literal``."""
        t = word(repr(literal))
        if literal is not None and t != literal:
            raise ValueError(f"{path}: expected {literal!r}, found {t!r} (token {pos})")
        return t

    def number():
        t = word("a number")
        try:
            return float(t)
        except ValueError:
            raise ValueError(f"{path}: expected a number, found {t!r} (token {pos})") from None

    joints: list[BvhJoint] = []
    n_chan = 0

    def joint(parent):
        nonlocal n_chan
        name = word("a joint name")
        take("{")
        take("OFFSET")
        off = np.array([number() for _ in range(3)])
        chans = []
        if pos < len(toks) and toks[pos] == "CHANNELS":
            take("CHANNELS")
            k = int(number())
            chans = [word("a channel name") for _ in range(k)]
            bad = [c for c in chans if c not in _VALID_CHANNELS]
            if bad:
                raise ValueError(f"{path}: joint {name!r}: unknown channels {bad}")
        idx = len(joints)
        joints.append(BvhJoint(name, parent, off, chans, None, n_chan))
        n_chan += len(chans)
        while True:
            t = word("JOINT, End or }")
            if t == "}":
                return
            if t == "JOINT":
                joint(idx)
            elif t == "End":
                take("Site")
                take("{")
                take("OFFSET")
                joints[idx].end_site = np.array([number() for _ in range(3)])
                take("}")
            else:
                raise ValueError(f"{path}: unexpected {t!r} in joint {name!r}")

    take("HIERARCHY")
    take("ROOT")
    joint(-1)
    take("MOTION")
    take("Frames:")
    n = int(number())
    take("Frame")
    take("Time:")
    ft = number()
    vals = toks[pos:]
    if len(vals) != n * n_chan:
        raise ValueError(f"{path}: {len(vals)} motion values for {n} frames × {n_chan} channels")
    frames = np.array(vals, dtype=np.float64).reshape(n, n_chan)
    return BvhFile(joints, ft, frames)
