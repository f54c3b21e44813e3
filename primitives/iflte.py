"""Koza's conditional: if a <= b then c else d.

Declared a conditional (``select=2``: a and b choose), so the interpreter
evaluates only the branch taken; DEAP's compiled twin evaluates both, which
gives the same value because primitives are pure.
"""
from gpmotion.gp.primitives import primitive


@primitive("iflte", arity=4, symbol="iflte", select=2)
def iflte(a, b, c, d):
    if a <= b:
        return c
    return d
