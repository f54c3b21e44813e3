"""Plain-Python twin of the generated GP interpreter (gpmotion.gp.interpreter).

Reads the same (ci, cf) layout (see gpmotion.gp.bytecode) and applies the
same value rule: senses and primitive results pass through ``clamp``
(NaN -> 0, saturate to +-1e6); a malformed stream gives 0.0.
"""
from gpmotion.gp.primitives import clamp


def run_tree_ref(ci, cf, tree_index, senses, funcs, stack_cap=64):
    """funcs[k] is the Python function of opcode 2 + k."""
    h = 2 + 3 * tree_index
    pos, n_ops = int(ci[h + 1]), int(ci[h + 2])
    stack = []
    for _ in range(n_ops):
        op, arg = int(ci[pos]), int(ci[pos + 1])
        pos += 2
        if op in (0, 1):
            if len(stack) >= stack_cap:
                return 0.0
            stack.append(clamp(senses[arg]) if op == 0 else float(cf[arg]))
        elif 2 <= op < 2 + len(funcs):
            f = funcs[op - 2]
            n = f.__code__.co_argcount
            if len(stack) < n:
                return 0.0
            args = stack[len(stack) - n:]
            del stack[len(stack) - n:]
            stack.append(clamp(f(*args)))
        else:
            return 0.0
    return stack[0] if len(stack) == 1 else 0.0


def control_ref(ci, cf, senses, targets, funcs):
    for k in range(int(ci[0])):
        targets[int(ci[2 + 3 * k])] = run_tree_ref(ci, cf, k, senses, funcs)
