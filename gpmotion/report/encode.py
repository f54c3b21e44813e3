"""One episode's motion as the report page's compact JSON: times as
little-endian float32 and positions as 16-bit integers over their range
(:func:`q16`), in base64, from the same frames the PNG/GIF renderers
draw (:func:`gpmotion.render3d.motion_frames`).

A diverged episode's tail (NaN/inf) is cut at the first frame that is not
finite.  ``fps`` keeps every k-th recorded frame (the film's reduced rate);
None keeps them all.
"""
from __future__ import annotations

import base64
import math

import numpy as np

from ..render3d import motion_frames


def f32(a) -> str:
    """An array as base64 little-endian float32 (the page decodes it)."""
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


def q16(a) -> dict:
    """Positions quantised to 16 bits over their own range (``lo + (v + 32767) * step``):
    half of float32's bytes, at most step / 2 off (0.08 mm over a 10 m range)."""
    a = np.asarray(a, dtype=float)
    lo = float(a.min()) if a.size else 0.0
    span = float(a.max()) - lo if a.size else 0.0
    step = span / 65534 if span > 0 else 1.0
    v = np.round((a - lo) / step) - 32767
    return {"lo": lo, "step": step,
            "q": base64.b64encode(np.ascontiguousarray(v, dtype="<i2").tobytes()).decode("ascii")}


def u8(a) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=np.uint8).tobytes()).decode("ascii")


def _finite_prefix(seg: np.ndarray, times: np.ndarray) -> int:
    bad = ~(np.isfinite(seg).reshape(len(times), -1).all(axis=1) & np.isfinite(times))
    return int(np.argmax(bad)) if bad.any() else len(times)


def _stride(times, fps) -> int:
    if fps is None or len(times) < 2:
        return 1
    step = float(times[1] - times[0])
    return max(1, int(math.floor(1.0 / (fps * step) + 1e-9)))


def _xyz(points: np.ndarray, dims: int) -> np.ndarray:
    """Planar (x, z) points as (x, 0, z): the page draws every figure in 3-D space."""
    if dims == 3:
        return points
    zeros = np.zeros(points.shape[:-1] + (1,))
    return np.concatenate([points[..., :1], zeros, points[..., 1:2]], axis=-1)


def encode_motion(traj, e: int = 0, *, task=None, fps: float | None = None,
                  details: bool = True, frames: dict | None = None) -> dict:
    """The page's record of episode ``e``: times, capsules, scene; with
    ``details`` also contact points (drawn while they push), the figure's
    sites and centre of mass (trails) and events."""
    m = frames or motion_frames(traj, e, task=task)
    dims = m["dims"]
    seg = np.asarray(m["segments"], float)
    times = np.asarray(m["times"], float)
    n = _finite_prefix(seg, times)
    if n == 0:
        raise ValueError("every frame of the motion contains NaN/inf: nothing to show")
    keep = np.arange(0, n, _stride(times, fps))
    out = {"dims": dims, "n": int(len(keep)), "n_seg": int(seg.shape[1]),
           "times": f32(times[keep]), "segs": q16(_xyz(seg[keep], dims)),
           "radii": [float(r) for r in m["radii"]],
           "ground_z": None if m["ground_z"] is None else float(m["ground_z"]),
           "poles": [] if m["poles"] is None else np.asarray(m["poles"], float).tolist(),
           "goal": None if m["goal"] is None else [float(v) for v in _xyz(np.asarray(m["goal"], float), dims)],
           "goal_label": m["goal_label"], "view": _view(m["view"]),
           "diverged_at": None if n == len(times) else float(times[n])}
    if traj.obj is not None:
        from ..sim.grip3d import O_RADIUS
        ob = np.asarray(traj.obj[e][keep], float)
        out["ball"] = {"r": float(traj.scene.obj[O_RADIUS]), "xyz": q16(ob[:, :3]),
                       "held": u8(ob[:, 6] > 0.5)}
    if details:
        out.update(_details(traj, e, keep, dims, m["events"], times))
    return out


def _view(view: dict) -> dict:
    return {k: float(view[k]) for k in ("elev", "azim") if k in view}


def _details(traj, e, keep, dims, events, times) -> dict:
    fig, model = traj.figure, traj.figure.model
    cps = traj._points(model.cp_link, model.cp_pos)[e][keep]
    touching = np.asarray(traj.contact_force[e][keep] > 0)
    sites = traj.sites()[e][keep] if len(fig.site_names) else np.zeros((len(keep), 0, dims))
    com = np.asarray(traj.com[e][keep][:, :dims], float)
    points = np.concatenate([com[:, None, :], sites], axis=1)
    shown = set(keep.tolist())
    return {"contacts": q16(_xyz(np.nan_to_num(cps), dims)), "n_contacts": int(cps.shape[1]),
            "touching": u8(touching), "points": q16(_xyz(np.nan_to_num(points), dims)),
            "point_names": ["centre of mass", *fig.site_names],
            "events": [[float(times[i]), str(w)] for i, w in events if i in shown]}
