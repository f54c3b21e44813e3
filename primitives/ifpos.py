"""Gritz & Hahn's three-argument conditional: evaluate the first subtree; if
it is positive return the second, else the third (only the branch taken is
evaluated).

The paper's text (stop-words stripped in our copy) reads "takes three
subtrees as arguments, evaluates the first, if its value is ... evaluates and
returns the second subtree, [else] evaluates and returns the third"; the
test itself is written in symbols, which the copy drops, so "> 0" is our
reading.  Not in the standard set (``gpmotion.gp.primitives.STANDARD``):
adding it there would change every default run's random trees; the
``gritz-hahn`` preset and ``--primitives`` name it.
"""
from gpmotion.gp.primitives import primitive


@primitive("ifpos", arity=3, symbol="if", select=1)
def ifpos(a, b, c):
    if a > 0.0:
        return b
    return c
