"""Plain-Python twin of the generated GP interpreter (gpmotion.gp.interpreter).

Reads the same (ci, cf) layout (see gpmotion.gp.bytecode) and applies the
same value rule: senses and primitive results pass through ``clamp``
(NaN -> 0, saturate to +-1e6); a malformed stream gives 0.0.  Opcodes:
0 push sense, 1 push constant, 2 jump forward, 3 push a controller slot
(subgoal flag j in slot j, task sense j in slot MAX_SUBGOALS + j),
4 + k primitive k (operand
0: apply; operand 1: a conditional's selection: branch 0 skips the jump
table that follows, branch j > 0 takes the table's jump j - 1; operand
2 + i: push sense i, then apply).
"""
from gpmotion.gp.primitives import clamp

HEADER = 6      # n_trees, max stack, n_flags, target mode, offset of rate data, n_task_senses
MAX_SUBGOALS = 8


def run_tree_ref(ci, cf, tree_index, senses, funcs, selects=None, stack_cap=64, flags=()):
    """funcs[k] is the Python function of opcode 4 + k; selects[k] its selector
    positions (empty: not a conditional); flags: the controller's slots
    (subgoal flags, then from MAX_SUBGOALS the task senses)."""
    selects = selects or [()] * len(funcs)
    h = HEADER + 3 * tree_index
    pos, n_ops = int(ci[h + 1]), int(ci[h + 2])
    end = pos + 2 * n_ops
    stack = []
    while pos < end:
        op, arg = int(ci[pos]), int(ci[pos + 1])
        pos += 2
        if op in (0, 1):
            if len(stack) >= stack_cap:
                return 0.0
            stack.append(clamp(senses[arg]) if op == 0 else float(cf[arg]))
        elif op == 3:
            if len(stack) >= stack_cap or not 0 <= arg < len(flags):
                return 0.0
            stack.append(float(flags[arg]))
        elif op == 2:
            if arg < 0 or pos + 2 * arg > end:
                return 0.0
            pos += 2 * arg
        elif 4 <= op < 4 + len(funcs) and (arg == 0 or arg >= 2):
            if arg >= 2:                        # fused: push sense arg - 2, then apply
                if len(stack) >= stack_cap:
                    return 0.0
                stack.append(clamp(senses[arg - 2]))
            f = funcs[op - 4]
            n = f.__code__.co_argcount
            if len(stack) < n:
                return 0.0
            args = stack[len(stack) - n:]
            del stack[len(stack) - n:]
            stack.append(clamp(f(*args)))
        elif 4 <= op < 4 + len(funcs) and arg == 1 and selects[op - 4]:
            f, sel = funcs[op - 4], selects[op - 4]
            n = f.__code__.co_argcount
            if len(stack) < len(sel):
                return 0.0
            picked = stack[len(stack) - len(sel):]
            del stack[len(stack) - len(sel):]
            branches = [i for i in range(n) if i not in sel]
            args = [0.0] * n
            for i, v in zip(sel, picked):
                args[i] = v
            for k, i in enumerate(branches):
                args[i] = float(k)
            j = f(*args)
            if j not in range(len(branches)):
                return 0.0
            skip = len(branches) - 1 if j == 0 else int(j) - 1   # past the table / onto J_j
            if pos + 2 * skip >= end:
                return 0.0
            pos += 2 * skip
        else:
            return 0.0
    return stack[0] if len(stack) == 1 else 0.0


def update_flags_ref(ci, cf, senses, flags):
    """Latch subgoal flag j once its test holds: 0 sense > thr, 1 <, 2 |sense| <."""
    b = HEADER + 3 * (int(ci[0]) + int(ci[5]))
    for j in range(int(ci[2])):
        v, code, thr = senses[int(ci[b + 3 * j])], int(ci[b + 3 * j + 1]), cf[int(ci[b + 3 * j + 2])]
        if (v > thr, v < thr, abs(v) < thr)[code]:
            flags[j] = 1.0


def control_ref(ci, cf, senses, targets, funcs, selects=None, flags=None, t=0.0, rate=None):
    """One control step at time ``t``; ``flags`` (a list) and ``rate`` (a dict:
    the previous time and one value per tree) are kept by the caller across
    steps.  ci[3] == 1: each tree k has a law row cf[ci[4] + 4k : +4] =
    (mode, gain, a, b): mode 0 (angle) target = output; 1 (rate) target +=
    (t - previous t) * gain * output, held within [a, b], starting at the
    caller's target; 2 (pi) target = output + I, I += (t - previous t) * gain *
    (output - senses[a]), |I| <= b, I starting at 0."""
    flags = [0.0] * int(ci[2]) if flags is None else flags
    update_flags_ref(ci, cf, senses, flags)
    n = int(ci[0])
    slots = list(flags) + [0.0] * (MAX_SUBGOALS - len(flags))
    slots += [run_tree_ref(ci, cf, n + j, senses, funcs, selects) for j in range(int(ci[5]))]
    acts = [int(ci[HEADER + 3 * k]) for k in range(n)]
    outs = [run_tree_ref(ci, cf, k, senses, funcs, selects, flags=slots) for k in range(n)]
    if int(ci[3]) == 0:
        for a, v in zip(acts, outs):
            targets[a] = v
        return
    rows = [tuple(cf[int(ci[4]) + 4 * k: int(ci[4]) + 4 * k + 4]) for k in range(n)]
    rate = {} if rate is None else rate
    if "t" not in rate:
        rate["t"], rate["v"] = t, [targets[a] if r[0] == 1 else 0.0 for a, r in zip(acts, rows)]
    h, rate["t"] = t - rate["t"], t
    for k, (act, out, (mode, gain, a, b)) in enumerate(zip(acts, outs, rows)):
        v = rate["v"][k]
        if mode == 1:
            rate["v"][k] = targets[act] = min(max(v + h * gain * out, a), b)
        elif mode == 2:
            rate["v"][k] = min(max(v + h * gain * (out - senses[int(a)]), -b), b)
            targets[act] = out + rate["v"][k]
        else:
            targets[act] = out
