"""Task senses: terminals a task derives from its figure's senses (Gritz &
Hahn's "distance to the nearest obstacle", "the pole relative to the head").

A task declares each as a name and an arithmetic formula over the figure's
sense names, written in its own file::

    def task_senses(self):
        return (TaskSense("pole_dx", f"px + {self.p['distance'] / 2}",
                          "base forward of the pole (m)"),)

and names it in its ``terminals`` like any sense.  The formula is parsed here
(never evaluated as Python) into the GP interpreter's own bytecode, and the
GP controller computes every task sense once per control step, before its
trees, into its own state (``cstate``): the simulator kernels are untouched,
and a tree reads a task sense as cheaply as a sense.

Grammar (``+ - * /`` left-associative, ``* /`` binding tighter, unary minus
tightest)::

    formula := sum
    sum     := product (("+" | "-") product)*
    product := unary (("*" | "/") unary)*
    unary   := "-" unary | atom
    atom    := NUMBER | SENSE | PRIMITIVE "(" sum ("," sum)* ")" | "(" sum ")"

``+ - * /`` are the primitives ``add sub mul div`` (``div`` is protected:
x / 0 gives 1, as in a tree), ``-x`` is ``sub(0, x)``, and a call names any
primitive of the run's primitive set with its arity (``sin(pitch)``,
``abs(px)``, ``iflte(a, b, c, d)``).  Values follow the trees' rule: every
sense read and every result is clamped (NaN -> 0, saturated at +-1e6).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from gpmotion.gp import primitives as registry
from gpmotion.gp.opcodes import OP_PRIM0, OP_PUSH_CONST, OP_PUSH_SENSE, STACK_CAP

MAX_TASK_SENSES = 8
MAX_FORMULA = 2000          # characters
INFIX = {"+": "add", "-": "sub", "*": "mul", "/": "div"}
_TOKEN = re.compile(r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(?P<name>[A-Za-z_]\w*)"
                    r"|(?P<op>[-+*/(),]))")


class FormulaError(ValueError):
    """A formula that does not parse or names something unknown; says where."""


@dataclass(frozen=True)
class TaskSense:
    name: str            # the terminal's name
    formula: str         # arithmetic over the figure's sense names (the grammar above)
    doc: str = ""
    tree: tuple = field(default=(), compare=False, repr=False)    # parsed: see parse()

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"task sense name {self.name!r} must be an identifier")
        if not isinstance(self.formula, str) or not self.formula.strip():
            raise ValueError(f"task sense {self.name}: the formula must be a non-empty string")


# A parsed formula is a nested tuple: ("const", x) | ("sense", name) | (primitive, *args).

def parse(formula: str, sense_names, primitive_names, what: str = "formula") -> tuple:
    """The formula's tree; FormulaError with the column of the first problem."""
    if len(formula) > MAX_FORMULA:
        raise FormulaError(f"{what}: longer than {MAX_FORMULA} characters")
    return _Parser(formula, set(sense_names), tuple(primitive_names), what).formula()


class _Parser:
    def __init__(self, text, senses, prims, what):
        self.text, self.senses, self.prims, self.what = text, senses, prims, what
        self.toks = self._lex()
        self.i = 0

    def _lex(self):
        out, pos = [], 0
        while pos < len(self.text):
            if self.text[pos:].strip() == "":
                break
            m = _TOKEN.match(self.text, pos)
            if not m:
                col = pos + len(self.text[pos:]) - len(self.text[pos:].lstrip()) + 1
                self._fail(f"unexpected character {self.text[col - 1]!r}", col)
            kind = m.lastgroup
            out.append((kind, m.group(kind), m.start(kind) + 1))
            pos = m.end()
        out.append(("end", "", len(self.text) + 1))
        return out

    def _fail(self, msg, col):
        raise FormulaError(f"{self.what}: {msg} at column {col}")

    def _peek(self):
        return self.toks[self.i]

    def _take(self, value=None):
        tok = self.toks[self.i]
        if value is not None and tok[1] != value:
            self._fail(f"expected {value!r}, found {tok[1] or 'the end'!r}", tok[2])
        self.i += 1
        return tok

    def formula(self):
        tree = self._sum()
        kind, value, col = self._peek()
        if kind != "end":
            self._fail(f"unexpected {value!r}", col)
        return tree

    def _binary(self, ops, operand):
        left = operand()
        while self._peek()[1] in ops and self._peek()[0] == "op":
            op = self._take()
            left = (self._prim(INFIX[op[1]], 2, op[2]), left, operand())
        return left

    def _sum(self):
        return self._binary("+-", self._product)

    def _product(self):
        return self._binary("*/", self._unary)

    def _unary(self):
        if self._peek()[1] == "-":
            col = self._take()[2]
            return (self._prim("sub", 2, col), ("const", 0.0), self._unary())
        return self._atom()

    def _prim(self, name, arity, col):
        if name not in self.prims:
            self._fail(f"{name!r} is not in this run's primitive set ({', '.join(self.prims)})", col)
        if arity is not None and registry.get(name).arity != arity:
            self._fail(f"{name} takes {registry.get(name).arity} arguments, got {arity}", col)
        return name

    def _atom(self):
        kind, value, col = self._take()
        if kind == "num":
            x = float(value)
            if not math.isfinite(x) or abs(x) > registry.CLAMP:
                self._fail(f"constant {value} out of range", col)
            return ("const", x)
        if kind == "name" and self._peek()[1] == "(":
            self._prim(value, None, col)           # a primitive's name, before its arguments
            self._take("(")
            args = [self._sum()]
            while self._peek()[1] == ",":
                self._take(",")
                args.append(self._sum())
            self._take(")")
            return (self._prim(value, len(args), col), *args)
        if kind == "name":
            if value not in self.senses:
                self._fail(f"unknown sense {value!r}", col)
            return ("sense", value)
        if value == "(":
            inner = self._sum()
            self._take(")")
            return inner
        self._fail(f"expected a number, a sense or '(', found {value or 'the end'!r}", col)


def compile_formula(tree, sense_names, opcode_names) -> tuple[list, list, int]:
    """A parsed formula -> (ops, constants, stack need), as gp.bytecode's
    compile_tree gives for a tree (every primitive applied eagerly);
    ``opcode_names``: the kernel's primitives in opcode order (PsetInfo.opcode_names)."""
    sense_names, prims = list(sense_names), list(opcode_names)
    ops, consts = [], []

    def emit(node) -> int:
        head = node[0]
        if head == "const":
            ops.append((OP_PUSH_CONST, len(consts)))
            consts.append(float(node[1]))
            return 1
        if head == "sense":
            ops.append((OP_PUSH_SENSE, sense_names.index(node[1])))
            return 1
        need = max(i + emit(arg) for i, arg in enumerate(node[1:]))
        ops.append((OP_PRIM0 + prims.index(head), 0))
        return need

    need = emit(tree)
    if need > STACK_CAP:
        raise FormulaError(f"formula needs a stack of {need} > {STACK_CAP}")
    return ops, consts, need


def evaluate(tree, senses: dict) -> float:
    """The plain-Python twin of a compiled formula: ``senses`` maps sense
    names to values; the interpreter's clamping."""
    head = tree[0]
    if head == "const":
        return float(tree[1])
    if head == "sense":
        return registry.clamp(float(senses[tree[1]]))
    return registry.clamp(registry.get(head).func(*(evaluate(a, senses) for a in tree[1:])))


def task_senses(task, primitive_names, used=None) -> tuple[TaskSense, ...]:
    """The senses a task declares (``task_senses()``), parsed against its
    figure's senses and ``primitive_names``; ValueError naming the task.
    ``used``: the names a run's trees read; only those are parsed (a sense no
    tree reads may use functions outside the run's set, e.g. the paper's)."""
    decl = getattr(task, "task_senses", None)
    found = tuple(decl() if callable(decl) else (decl or ()))
    if len(found) > MAX_TASK_SENSES:
        raise ValueError(f"task {task.name}: at most {MAX_TASK_SENSES} task senses, got {len(found)}")
    names = [s.name for s in found]
    if len(set(names)) != len(names):
        raise ValueError(f"task {task.name}: repeated task sense names {names}")
    out = []
    for s in found:
        if not isinstance(s, TaskSense):
            raise ValueError(f"task {task.name}: task_senses() must give TaskSense objects, got {s!r}")
        if s.name in task.figure.sense_names:
            raise ValueError(f"task {task.name}: task sense {s.name!r} has a figure sense's name")
        tree = None if used is not None and s.name not in used else parse(
            s.formula, task.figure.sense_names, primitive_names,
            what=f"task {task.name}, sense {s.name} = {s.formula!r}")
        out.append(TaskSense(s.name, s.formula, s.doc, tree))
    return tuple(out)


def _rotated(ox: float, oz: float, angle: str) -> tuple[list[str], list[str]]:
    """x and z terms of the offset (ox, oz) turned by ``angle`` (a formula; "" is 0)."""
    if not angle:
        return ([repr(ox)] if ox else []), ([repr(oz)] if oz else [])
    c, s = f"cos({angle})", f"sin({angle})"
    xs = ([f"{ox!r} * {c}"] if ox else []) + ([f"-{oz!r} * {s}"] if oz else [])
    zs = ([f"{ox!r} * {s}"] if ox else []) + ([f"{oz!r} * {c}"] if oz else [])
    return xs, zs


def planar_site_formulas(figure, site: str) -> tuple[str, str]:
    """Formulas of a planar figure's site's world (x, z) minus the scene goal
    (the frame of the senses ``px``, ``pz``), by forward kinematics over
    ``pitch`` and the joints' ``angle_*`` senses; a task adds a point's
    offset to refer the site to that point (``f"{x} + 0.3"``).  Read from the
    figure's model, so a figure variant gets its own lengths."""
    if figure.dimensions != 2 or figure.root != "planar":
        raise ValueError(f"planar_site_formulas: {figure.name} is not a planar free figure")
    m, names = figure.model, figure.link_names
    k = figure.site_names.index(site)
    chain, link = [], int(figure.site_link[k])
    while link >= 0:
        chain.append(link)
        link = int(m.parent[link])
    xs, zs, angle = ["px"], ["pz"], ""
    for i in reversed(chain):
        a, ox, oz = (float(v) for v in m.xtree[i])
        dx, dz = _rotated(ox, oz, angle)
        xs, zs = xs + dx, zs + dz
        if int(m.jtype[i]) == 0:               # a hinge: the frame turns by its angle sense
            sense = "pitch" if names[i] == "root_pitch" else f"angle_{names[i]}"
            if sense not in figure.sense_names:
                raise ValueError(f"planar_site_formulas: {figure.name} has no sense {sense!r}")
            angle = " + ".join(p for p in (angle, repr(a) if a else "", sense) if p)
    dx, dz = _rotated(*(float(v) for v in figure.site_pos[k]), angle)
    return (" + ".join(xs + dx).replace("+ -", "- "), " + ".join(zs + dz).replace("+ -", "- "))
