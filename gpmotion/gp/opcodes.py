"""The GP bytecode's numbers, shared by the encoder (gpmotion.gp.bytecode) and
the interpreter it generates (gpmotion.gp.interpreter); the layout they
describe is in bytecode's docstring."""

STACK_CAP = 64          # interpreter stack = cstate; trees needing more are rejected
HEADER = 6              # ci[0:6] = n_trees, max stack need, n_flags, law flag, law block,
#                         n_task_senses
# what a tree's output is (gpmotion.gp.bytecode, gpmotion.gp.targets), in code order
TARGET_MODES = {"angle": "a tree's output is its joint's target angle",
                "rate": "a tree's output drives its target's rate of change: integral action",
                "pi": "a tree's output is its joint's angle, reached without the PD servo's sag "
                      "(an integral term corrects the target)"}
# OP_PUSH_FLAG reads a value the controller keeps: subgoal flag j (j < MAX_SUBGOALS)
# or task sense j - MAX_SUBGOALS
OP_PUSH_SENSE, OP_PUSH_CONST, OP_JUMP, OP_PUSH_FLAG, OP_PRIM0 = 0, 1, 2, 3, 4
# a primitive's operand: 0 apply, 1 select (conditionals), OP_ARG_SENSE0 + i: push
# sense i then apply (one fused dispatch for the pair)
OP_ARG_SENSE0 = 2
LAW_WIDTH = 4           # law block per tree: mode code, gain, a, b
RATE_STATE = 2          # rate/pi cstate slots before one value a tree: previous t, started
