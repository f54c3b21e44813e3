"""A fast sine and cosine for the GP interpreter (opt-in: GP family option ``fast_trig``).

libm's ``sin``/``cos`` are calls numba cannot inline, and in a lamp tree
they take over half of the interpreter's time (docs/speed.md).  These are
fdlibm's algorithms written as plain scalar code that numba inlines:

* within pi/4, the polynomial alone;
* beyond, Cody-Waite range reduction to [-pi/4, pi/4]: x - n pi/2 with
  pi/2 split in 33-bit parts (n < 2^20, so n times a part is exact), a
  second and a third part only when the first cancels most of x; the
  remainder is kept as a head and a tail (fdlibm's ``__ieee754_rem_pio2``,
  medium range);
* the minimax polynomials of fdlibm's ``__kernel_sin``/``__kernel_cos``
  (FreeBSD msun) on the reduced argument.

Beyond |x| >= 2^20 pi/2 (past the interpreter's clamp, 1e6) and for NaN or
inf they call libm, so every input gives what libm's definition gives up
to a few ulp (``benchmarks/gp_fast_trig_ab.py`` measures the error; the
tests bound it).  Results are not libm's bit for bit, which is why the
option is off by default.

The interpreter copies this file's constants and functions into its
generated module (:func:`gpmotion.gp.interpreter.fast_trig_source`), so the
module's hash covers them.  Plain Python runs the same operations (no
fused multiply-add: the kernel compiles with ``fastmath=False``).
"""
import math

_FT_PIO4 = 0.78539816339744830962          # pi/4 rounded: no reduction below
_FT_LIMIT = 1647099.3291652855              # 2^20 pi/2: n fits 20 bits, n * part exact
_FT_INVPIO2 = 6.36619772367581382433e-01
_FT_ROUND = 6755399441055744.0              # 1.5 * 2^52: adding it rounds to an integer
_FT_PIO2_1 = 1.57079632673412561417e+00     # first 33 bits of pi/2
_FT_PIO2_1T = 6.07710050650619224932e-11    # pi/2 - _FT_PIO2_1
_FT_PIO2_2 = 6.07710050630396597660e-11     # next 33 bits
_FT_PIO2_2T = 2.02226624879595063154e-21
_FT_PIO2_3 = 2.02226624871116645580e-21     # next 33 bits
_FT_PIO2_3T = 8.47842766036889956997e-32
_FT_S1 = -1.66666666666666324348e-01
_FT_S2 = 8.33333333332248946124e-03
_FT_S3 = -1.98412698298579493134e-04
_FT_S4 = 2.75573137070700676789e-06
_FT_S5 = -2.50507602534068634195e-08
_FT_S6 = 1.58969099521155010221e-10
_FT_C1 = 4.16666666666666019037e-02
_FT_C2 = -1.38888888888741095749e-03
_FT_C3 = 2.48015872894767294178e-05
_FT_C4 = -2.75573143513906633035e-07
_FT_C5 = 2.08757232129817482790e-09
_FT_C6 = -1.13596475577881948265e-11


def _ft_reduce(x):
    """(n mod 4, y0, y1): x - n pi/2 = y0 + y1, |y0| <= ~pi/4, for |x| < _FT_LIMIT."""
    ax = abs(x)
    fn = (x * _FT_INVPIO2 + _FT_ROUND) - _FT_ROUND     # nearest integer, no call to floor
    r = x - fn * _FT_PIO2_1
    w = fn * _FT_PIO2_1T
    y0 = r - w
    if abs(y0) * 65536.0 < ax:               # the first part cancelled 16+ bits: a second part
        t = r
        w = fn * _FT_PIO2_2
        r = t - w
        w = fn * _FT_PIO2_2T - ((t - r) - w)
        y0 = r - w
        if abs(y0) * 562949953421312.0 < ax:     # 49+ bits (2^49): a third part
            t = r
            w = fn * _FT_PIO2_3
            r = t - w
            w = fn * _FT_PIO2_3T - ((t - r) - w)
            y0 = r - w
    y1 = (r - y0) - w
    return int(fn) & 3, y0, y1


def _ft_ksin(x, y):
    """sin(x + y) for |x| <= ~pi/4, y the tail of x."""
    z = x * x
    w = z * z
    r = _FT_S2 + z * (_FT_S3 + z * _FT_S4) + z * w * (_FT_S5 + z * _FT_S6)
    v = z * x
    return x - ((z * (0.5 * y - v * r) - y) - v * _FT_S1)


def _ft_ksin0(x):
    """sin x for |x| <= ~pi/4 (no tail)."""
    if abs(x) < 7.450580596923828e-09:       # 2^-27: sin x rounds to x (keeps -0.0)
        return x
    z = x * x
    r = _FT_S2 + z * (_FT_S3 + z * _FT_S4) + z * (z * z) * (_FT_S5 + z * _FT_S6)
    return x + (z * x) * (_FT_S1 + z * r)


def _ft_kcos(x, y):
    """cos(x + y) for |x| <= ~pi/4, y the tail of x."""
    z = x * x
    w = z * z
    r = z * (_FT_C1 + z * (_FT_C2 + z * _FT_C3)) + w * w * (_FT_C4 + z * (_FT_C5 + z * _FT_C6))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + (z * r - x * y))


# Within pi/4 the kernel alone.  Beyond it both kernels are computed and the
# quadrant weighs them by 0 or +-1 (exact: the other term is a signed zero): a
# branch on the quadrant, which a tree's arguments make hard to predict (one
# call site serves every node), costs more (benchmarks/gp_fast_trig_ab.py).

def _ft_sin(x):
    if not abs(x) < _FT_LIMIT:               # large, inf, NaN: libm
        return math.sin(x)
    if abs(x) < _FT_PIO4:
        return _ft_ksin0(x)
    n, y0, y1 = _ft_reduce(x)
    odd = float(n & 1)
    sign = 1.0 - float(n & 2)
    return _ft_ksin(y0, y1) * (sign - sign * odd) + _ft_kcos(y0, y1) * (sign * odd)


def _ft_cos(x):
    if not abs(x) < _FT_LIMIT:
        return math.cos(x)
    if abs(x) < _FT_PIO4:
        return _ft_kcos(x, 0.0)
    n, y0, y1 = _ft_reduce(x)
    odd = float(n & 1)
    sign = 1.0 - float((n + 1) & 2)
    return _ft_kcos(y0, y1) * (sign - sign * odd) + _ft_ksin(y0, y1) * (sign * odd)
