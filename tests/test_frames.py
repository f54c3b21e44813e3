"""frames.py: motion events (take-off, apex, landing), the frames a
filmstrip keeps, and GIF timing at a stated speed."""
import numpy as np
import pytest

from gpmotion.frames import choose_frames, event_labels, flight_events, gif_timing


def ballistic_hop(step=0.01):
    """Stand 0.3 s, fly 0.4 s (up 0.2 m, apex at 0.5 s), stand 0.3 s."""
    t = np.arange(0.0, 1.0 + step / 2, step)
    z = np.full(t.shape, 0.3)
    fly = (t > 0.3) & (t < 0.7)
    z[fly] += 0.2 - 0.2 * ((t[fly] - 0.5) / 0.2) ** 2
    air = fly.copy()
    air[0] = False
    return t, z, air


def test_a_hop_has_take_off_apex_and_landing():
    t, z, air = ballistic_hop()
    ev = flight_events(t, z, air)
    assert [lab for _, lab in ev] == ["take-off", "apex", "landing"]
    (i0, _), (ia, _), (i1, _) = ev
    assert t[i0] == pytest.approx(0.31) and t[ia] == pytest.approx(0.5) and t[i1] == pytest.approx(0.7)


def test_chatter_a_drop_and_no_ground_are_not_flights():
    t, z, air = ballistic_hop()
    chatter = np.zeros_like(air)
    chatter[40:42] = True                       # 2 frames: 0.02 s off the ground
    assert flight_events(t, z, chatter) == []
    dropped = np.zeros_like(air)
    dropped[:20] = True                         # falls, lands at frame 20
    assert flight_events(t, z, dropped) == [(20, "landing")]
    assert flight_events(t, z, np.ones_like(air)) == []      # never on the ground
    # frame 0 closes no interval: its "no contact yet" is not a flight
    standing = np.zeros_like(air)
    standing[0] = True
    assert flight_events(t, z, standing) == []
    with pytest.raises(ValueError, match="one entry per frame"):
        flight_events(t, z[:-1], air)


def test_choose_frames_keeps_events_and_fills_in_evenly():
    t, z, air = ballistic_hop()
    ok = np.arange(len(t))
    ev = flight_events(t, z, air)
    frames = choose_frames(ok, t, 8, ev)
    assert len(frames) == 8 and list(frames) == sorted(frames)
    assert {0, len(t) - 1} | {i for i, _ in ev} <= set(frames.tolist())
    # too few frames for every event: the apex wins
    assert 50 in choose_frames(ok, t, 3, ev)
    # skipped (non-finite) frames are never chosen, even as events
    assert 50 not in choose_frames(np.delete(ok, 50), t, 8, ev)
    assert event_labels(4, [(1, "apex"), (1, "landing")]) == ["", "apex, landing", "", ""]


def test_gif_timing_is_real_time_without_drift():
    t = np.arange(0, 301) * 0.01
    shown, d = gif_timing(np.arange(301), t)
    assert d == [40] * len(d) and len(shown) == 76          # every 4th frame, 40 ms
    t = np.arange(0, 101) * 0.013                             # 13 ms: no exact stride ≤ 2k
    shown, d = gif_timing(np.arange(101), t, speed=1.0)
    assert all(v % 10 == 0 for v in d)
    ends = np.cumsum(d)[:-1]
    starts = 1000 * (t[shown[1:]] - t[0])
    assert np.abs(ends - starts).max() <= 5.0                 # rounded on the cumulative clock
    with pytest.raises(ValueError, match="fps"):
        gif_timing(np.arange(10), t[:10], max_fps=60)
