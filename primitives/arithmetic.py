"""Arithmetic primitives (Koza's function set): +, -, * and protected division."""
from gpmotion.gp.primitives import primitive


@primitive("add", arity=2, symbol="+")
def add(a, b):
    return a + b


@primitive("sub", arity=2, symbol="-")
def sub(a, b):
    return a - b


@primitive("mul", arity=2, symbol="*")
def mul(a, b):
    return a * b


@primitive("div", arity=2, symbol="%")
def div(a, b):
    """Koza's protected division: 1.0 when the divisor is (nearly) zero."""
    if abs(b) < 1e-9:
        return 1.0
    return a / b
