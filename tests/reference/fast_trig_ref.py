"""Plain-numpy twin of gpmotion.gp.fast_trig: the same operations, written a
second way (whole arrays, the quadrant and the parts of the reduction picked
by masks), so the compiled fast sin/cos can be checked bit for bit.

fdlibm (FreeBSD msun): ``__ieee754_rem_pio2`` (medium range), ``__kernel_sin``
and ``__kernel_cos``; within pi/4 the polynomial alone; libm for
|x| >= 2^20 pi/2, inf and NaN.
"""
import math

import numpy as np

PIO4 = np.pi / 4
LIMIT = 2.0 ** 20 * (np.pi / 2)
INVPIO2 = 2 / np.pi
PIO2 = [float.fromhex(h) for h in ("0x1.921fb54400000p+0", "0x1.0b4611a600000p-34",
                                   "0x1.3198a2e000000p-69")]
PIO2T = [float.fromhex(h) for h in ("0x1.0b4611a626331p-34", "0x1.3198a2e037073p-69",
                                    "0x1.b839a252049c1p-104")]
S = [-1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04,
     2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10]
C = [4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05,
     -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11]


def reduce(x):
    """(n mod 4, y0, y1) with x - n pi/2 = y0 + y1 (fdlibm's medium range)."""
    fn = np.rint(x * INVPIO2)                     # nearest, ties to even
    r = x - fn * PIO2[0]
    w = fn * PIO2T[0]
    y0 = r - w
    for k, bits in ((1, 2.0 ** 16), (2, 2.0 ** 49)):
        more = np.abs(y0) * bits < np.abs(x)      # the parts so far cancelled that many bits
        t = r
        w2 = fn * PIO2[k]
        r2 = t - w2
        w2 = fn * PIO2T[k] - ((t - r2) - w2)
        r, w = np.where(more, r2, r), np.where(more, w2, w)
        y0 = np.where(more, r2 - w2, y0)
        if not more.any():
            break
    return fn.astype(np.int64) & 3, y0, (r - y0) - w


def ksin(x, y):
    z = x * x
    w = z * z
    r = S[1] + z * (S[2] + z * S[3]) + z * w * (S[4] + z * S[5])
    v = z * x
    return x - ((z * (0.5 * y - v * r) - y) - v * S[0])


def ksin0(x):
    z = x * x
    r = S[1] + z * (S[2] + z * S[3]) + z * (z * z) * (S[4] + z * S[5])
    out = x + (z * x) * (S[0] + z * r)
    return np.where(np.abs(x) < 2.0 ** -27, x, out)


def kcos(x, y):
    z = x * x
    w = z * z
    r = z * (C[0] + z * (C[1] + z * C[2])) + w * w * (C[3] + z * (C[4] + z * C[5]))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + (z * r - x * y))


def _trig(x, cos: bool):
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(all="ignore"):
        mid = np.abs(x) < LIMIT
        xm = np.where(mid, x, 0.0)
        n, y0, y1 = reduce(xm)
        s, c = ksin(y0, y1), kcos(y0, y1)
        q = (n + 1) & 3 if cos else n                 # cos x = sin(x + pi/2)
        reduced = np.select([q == 0, q == 1, q == 2], [s, c, -s], -c)
        small = kcos(xm, 0.0) if cos else ksin0(xm)
        out = np.where(np.abs(x) < PIO4, small, reduced)
    f = math.cos if cos else math.sin
    libm = [f(v) if math.isfinite(v) else math.nan for v in x.ravel()[~mid.ravel()]]
    out = out.copy()
    out[~mid] = libm                                  # libm's own calls, not numpy's loops
    return out


def sin(x):
    return _trig(x, cos=False)


def cos(x):
    return _trig(x, cos=True)
