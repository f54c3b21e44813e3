"""Conditional: if a <= b then c else d (both branches are evaluated; pure)."""
from gpmotion.gp.primitives import primitive


@primitive("iflte", arity=4, symbol="iflte")
def iflte(a, b, c, d):
    if a <= b:
        return c
    return d
