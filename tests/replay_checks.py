"""Comparing a replay with the numbers a ledger or a controller file recorded.

The simulation kernels give the same bits on every x86-64 CPU we test on (the
golden runs), but the measures and costs computed after it with numpy do not:
numpy picks SIMD versions of ``arctan2``, ``arccos``, sums, ... by CPU (an
AVX-512 machine and an AVX2-only one differ in the last bits), and a later
stage that starts where an earlier one ended inherits the difference.  So a
recorded number is checked to ``REL`` and a label, a flag or a count exactly
(docs/determinism.md)."""
import math

import numpy as np

REL, ABS = 1e-8, 1e-12


def _close(a, b) -> bool:
    return math.isclose(a, b, rel_tol=REL, abs_tol=ABS)


def same_numbers(got, want, where: str = "") -> None:
    """Assert ``got`` is ``want``: floats to ``REL``, everything else exactly."""
    if isinstance(want, dict):
        assert isinstance(got, dict) and sorted(got) == sorted(want), (where, sorted(got), sorted(want))
        for k in want:
            same_numbers(got[k], want[k], f"{where}.{k}")
    elif isinstance(want, (list, tuple)):
        assert len(got) == len(want), (where, got, want)
        for i, (g, w) in enumerate(zip(got, want)):
            same_numbers(g, w, f"{where}[{i}]")
    elif isinstance(want, (float, np.floating)) and not isinstance(got, (bool, np.bool_)):
        assert isinstance(got, (int, float, np.floating, np.integer)) and _close(float(got), float(want)), \
            (where, got, want)
    else:
        assert type(got) is type(want) or (isinstance(got, (bool, np.bool_)) and isinstance(want, bool)) \
            or (isinstance(got, (int, np.integer)) and isinstance(want, int)), (where, got, want)
        assert got == want, (where, got, want)
