"""sin, cos and abs; sin/cos of a non-finite argument give 0.0 (never NaN)."""
import math

from gpmotion.gp.primitives import primitive


@primitive("sin", arity=1)
def sin(a):
    if not math.isfinite(a):
        return 0.0
    return math.sin(a)


@primitive("cos", arity=1)
def cos(a):
    if not math.isfinite(a):
        return 0.0
    return math.cos(a)


@primitive("abs", arity=1, symbol="|x|")
def abs_(a):
    return abs(a)
