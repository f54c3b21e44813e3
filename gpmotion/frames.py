"""Which recorded frames a picture shows, and for how long.

* :func:`flight_events` finds the motion events a strobe picture must not
  skip — take-off, apex and landing of every flight phase — from the contact
  forces and the centre-of-mass height of a recorded episode.
* :func:`choose_frames` keeps those events and fills in evenly spaced frames.
* :func:`gif_timing` picks the frames of a GIF and their display durations so
  that it plays at a stated speed (1 = real time) within GIF's 10 ms clock.

Plain arrays in, plain arrays out: no drawing here.
"""
from __future__ import annotations

import math

import numpy as np

GIF_TICK = 10.0          # ms: GIF delays are whole centiseconds
MAX_GIF_FPS = 50.0       # browsers replace delays under 20 ms by 100 ms


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) index ranges where ``mask`` is True."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(np.int8)))
    return list(zip(d[::2], d[1::2]))


def flights(traj, e: int = 0) -> int:
    """Flight phases of episode ``e`` as a person counts hops and the filmstrip
    marks them: take-offs of :func:`flight_events` (the whole figure off the
    ground for at least its ``min_flight``, after touching it), not every
    frame some contact point lets go."""
    cf = traj.contact_force[e]
    if not cf.shape[-1]:
        return 0
    height = traj.com[e][:, 2 if traj.is3d else 1]
    events = flight_events(traj.times, height, cf.max(axis=1) == 0)
    return sum(label == "take-off" for _, label in events)


def flight_events(times, height, airborne, min_flight: float = 0.06) -> list[tuple[int, str]]:
    """``[(frame, label)]`` sorted by frame: "take-off" (first frame off the
    ground), "apex" (highest centre of mass in the air) and "landing" (first
    frame back on the ground) of every flight phase.

    ``airborne[i]``: no ground contact over the interval ending at frame i
    (a recorded episode's event channels hold the max since the previous
    frame); frame 0 closes no interval, so it takes frame 1's value.  A
    flight phase is a run of airborne frames that starts after a frame on
    the ground and lasts at least ``min_flight`` seconds (shorter ones, with
    an apex under ~5 mm, are bounces and contact chatter).  A figure airborne from the first frame (dropped, or
    never touching the ground, e.g. a fixed-root figure) has no take-off,
    hence no flight: only its landing, if it lands after ``min_flight``, is
    an event.
    """
    t = np.asarray(times, float).reshape(-1)
    z = np.asarray(height, float).reshape(-1)
    air = np.asarray(airborne, bool).reshape(-1)
    if not (t.shape == z.shape == air.shape):
        raise ValueError(f"times, height and airborne must have one entry per frame "
                         f"({t.size}, {z.size}, {air.size})")
    if air.size > 1:
        air = air.copy()
        air[0] = air[1]
    events: list[tuple[int, str]] = []
    for s, e in _runs(air):
        lands = e < t.size
        if t[e - 1] - t[max(s - 1, 0)] < min_flight:   # frames s..e-1 cover (t[s-1], t[e-1]]
            continue
        if s == 0:                       # in the air from the start: no take-off
            if lands:
                events.append((int(e), "landing"))
            continue
        events.append((int(s), "take-off"))
        zz = np.where(np.isfinite(z[s:e]), z[s:e], -np.inf)
        apex = s + int(np.argmax(zz))
        if lands and apex > s and np.isfinite(zz[apex - s]):
            events.append((int(apex), "apex"))
        if lands:
            events.append((int(e), "landing"))
    return events


def crossing_events(times, x, marks: list[tuple[float, str]]) -> list[tuple[int, str]]:
    """``[(frame, label)]``: the first frame at which ``x`` (e.g. the centre
    of mass) reaches each mark (e.g. a limbo pole's x), when it starts short
    of it; moving left, when it starts beyond it."""
    x = np.asarray(x, float).reshape(-1)
    out = []
    for at, label in marks:
        side = np.sign(x - at)
        if not np.isfinite(x[0]) or side[0] == 0:
            continue
        crossed = np.flatnonzero(np.isfinite(x) & (side != side[0]))
        if crossed.size:
            out.append((int(crossed[0]), label))
    return out


def choose_frames(ok: np.ndarray, times, n: int,
                  events: list[tuple[int, str]] | None = None) -> np.ndarray:
    """At most ``n`` frames of ``ok`` (the drawable ones), sorted: the first
    and last, the ``events`` frames (take-offs and landings after the
    others, e.g. apexes, in time order, as many as fit), then fill-ins, each the frame
    farthest in time from every frame already chosen."""
    if n < 1:
        raise ValueError(f"need at least one frame to draw, got {n}")
    ok = np.asarray(ok, int)
    t = np.asarray(times, float)
    if ok.size <= n:
        return ok
    okset = set(ok.tolist())
    rank = {"take-off": 1, "landing": 1}     # after apexes, pole passages, a task's own moments
    wanted = [ok[0], ok[-1]] + [i for i, lab in sorted(events or [], key=lambda ev: rank.get(ev[1], 0))
                                if i in okset]
    chosen: list[int] = []
    for i in wanted:
        if i not in chosen and len(chosen) < n:
            chosen.append(int(i))
    while len(chosen) < n:
        gap = np.min(np.abs(t[ok][:, None] - t[chosen][None, :]), axis=1)
        chosen.append(int(ok[int(np.argmax(gap))]))
    return np.array(sorted(chosen))


def event_labels(n_frames: int, events: list[tuple[int, str]] | None) -> list[str]:
    """One caption word per recorded frame ("" where nothing happens)."""
    out = [""] * n_frames
    for i, lab in events or []:
        if 0 <= i < n_frames:
            out[i] = f"{out[i]}, {lab}" if out[i] else lab
    return out


def gif_timing(ok: np.ndarray, times, speed: float = 1.0, max_fps: float = 25.0,
               max_frames: int = 200) -> tuple[np.ndarray, list[int]]:
    """Frames to show and their durations (ms, multiples of 10) so that the
    GIF plays at ``speed`` × real time.

    The frames are every k-th recorded one, k the smallest stride that keeps
    the playback rate ≤ ``max_fps`` and the count ≤ ``max_frames``,
    preferring (up to doubling k) a stride whose delay is a whole number of
    centiseconds, so every frame lasts the same; frames of ``times`` not in
    ``ok`` (not drawable) are skipped, their time held by the frame shown
    before them.  Frame j is shown from its
    own time to the next shown frame's (the last one for one stride), the
    boundaries rounded to 10 ms on the cumulative clock: the total is the
    shown span plus one stride, over ``speed``, with no drift.
    """
    if not (isinstance(speed, (int, float)) and 0.01 <= speed <= 100):
        raise ValueError(f"speed must be a number in [0.01, 100] (1 = real time), got {speed!r}")
    if not (isinstance(max_fps, (int, float)) and 0 < max_fps <= MAX_GIF_FPS):
        raise ValueError(f"fps must be in (0, {MAX_GIF_FPS:g}] (browsers slow down faster GIFs), "
                         f"got {max_fps!r}")
    if max_frames < 1:
        raise ValueError(f"need at least one frame to draw, got {max_frames}")
    ok = np.asarray(ok, int)
    t = np.asarray(times, float)
    steps = np.diff(t)
    step = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 0.0
    if ok.size == 1 or step == 0.0:
        return ok[:1], [int(GIF_TICK * max(2, math.ceil(1000 / max_fps / GIF_TICK)))]
    play = 1000.0 * step / speed                                  # ms per recorded frame
    span = (t[ok[-1]] - t[ok[0]]) / step + 1
    k = max(1, math.ceil(1000.0 / max_fps / play - 1e-9), math.ceil(span / max_frames - 1e-9))
    exact = [j for j in range(k, 2 * k + 1) if abs(j * play / GIF_TICK - round(j * play / GIF_TICK)) < 1e-6]
    if exact and math.ceil(span / exact[0]) <= max_frames:
        k = exact[0]
    shown, due = [], -np.inf
    for i in ok:                     # every k-th; after a gap, k steps on from the last shown
        if t[i] >= due:
            shown.append(i)
            due = t[i] + (k - 1e-6) * step
    shown = np.array(shown)
    start = (t[shown] - t[shown[0]]) * 1000.0 / speed
    ends = np.append(start[1:], start[-1] + k * play)
    ticks = np.round(np.append(start[:1], ends) / GIF_TICK).astype(int)
    durations = [int(GIF_TICK * max(d, 1)) for d in np.diff(ticks)]
    return shown, durations


def speed_text(speed: float) -> str:
    """What a GIF says about its playback speed."""
    return "real time" if speed == 1 else f"{speed:g}× real time"
