"""Define a GP primitive and check it (run: python examples/user_primitive.py)."""
import math

from gpmotion import check_primitive, primitive


@primitive("tanh", arity=1)
def tanh(a):
    return math.tanh(a)          # pure scalar code numba can compile


check_primitive("tanh")          # raises AssertionError with the reason if unfit
print("tanh passes check_primitive")
