"""The GP bytecode's numbers, shared by the encoder (gpmotion.gp.bytecode) and
the interpreter it generates (gpmotion.gp.interpreter); the layout they
describe is in bytecode's docstring."""

STACK_CAP = 64          # interpreter stack = cstate; trees needing more are rejected
HEADER = 3              # ci[0:3] = n_trees, max stack need, n_flags
OP_PUSH_SENSE, OP_PUSH_CONST, OP_JUMP, OP_PUSH_FLAG, OP_PRIM0 = 0, 1, 2, 3, 4
