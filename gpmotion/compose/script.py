"""The composite-motion script language (Auslander et al. 1995, Table 4).

The animator states what each phase of a composite motion should achieve and
how the phases combine into one score (higher is better).  The paper's
example, accepted as written (``×``, ``≟``, ``Δ`` and ``{}`` included):

    phase cartwheel = Δcm_x × (Δtime ≟ 1.59)
    phase jump      = max_t{min_i{y_i(t)}} × (Δtime ≟ 0.90)
    phase shuffle   = Δcm_x × (Δtime ≟ 1.00)
    total = (1.0 + cartwheel) × (1.0 + jump) × (1.0 + shuffle)

and in ASCII: ``phase jump = max_t(min_i(y_i)) * (dtime ~= 0.9)``.
Durations are in seconds.

Grammar (lark, LALR(1); ``#`` starts a comment, ``;`` separates like a newline)::

    start   : line*
    line    : stmt? NEWLINE
    stmt    : "phase" NAME "=" expr        # the next phase's credit (k-th phase → k-th controller)
            | NAME "=" expr                # a named expression, inlined where it is used
    expr    : sum (("~=" | "≟" | "<" | "<=" | ">" | ">=") sum)?
    sum     : product (("+" | "-") product)*
    product : unary (("*" | "×" | "·" | "/") unary)*
    unary   : "-" unary | atom ("^" unary)?
    atom    : NUMBER | NAME | NAME "(" args ")" | NAME "{" args "}" | "(" expr ")"
    args    : (expr | STRING) ("," (expr | STRING))*

Semantics
* A ``phase`` expression is evaluated over that phase's frames (from the
  switch into it to the switch out of it, both included); any other name is a
  macro, evaluated in the window where it is used.  ``total`` (required) is
  evaluated over the whole motion and is the score.
* Every expression has a kind: a *number* per episode, a *signal* (one value
  per frame) or *points* (per frame, per contact point).  ``min_i``/``max_i``/
  ``sum_i``/``mean_i`` reduce points to a signal, ``max_t``/``min_t``/
  ``mean_t``/``sum_t``/``first``/``last``/``delta`` a signal to a number.
  Phase credits and ``total`` must be numbers; kinds are checked when the
  script is parsed.  ``y_i(t)`` (the paper's notation) is ``y_i``.
* ``a ≟ b`` (``a ~= b``) is 1 when a = b and falls linearly to 0 as they
  differ: max(0, 1 − |a − b| / max(|a|, |b|)) (scale-free, so seconds and
  ticks give the same credit).  Comparisons give 1.0 or 0.0.
* The measures are listed in :mod:`gpmotion.compose.measures` (``MEASURES``).

A syntax or name error raises :class:`ScriptError` with ``line:col: message``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from lark import Lark, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from .measures import FUNCTIONS, KIND_NAMES, MEASURES, NUMBER, POINTS, SIGNAL, Context, Window

GRAMMAR = r"""
start: line*
?line: stmt? _NL
stmt: "phase" NAME "=" expr   -> phase
    | NAME "=" expr           -> let
?expr: sum | sum CMP sum      -> compare
?sum: product | sum ADD product -> binop
?product: unary | product MUL unary -> binop
?unary: power | "-" unary     -> neg
?power: atom | atom "^" unary -> pow
?atom: NUMBER                 -> number
     | NAME                   -> name
     | NAME "(" [args] ")"    -> call
     | NAME "{" [args] "}"    -> call
     | "(" expr ")"
args: arg ("," arg)*
?arg: expr | STRING           -> string
CMP: "~=" | "≟" | "<=" | ">=" | "<" | ">"
ADD: "+" | "-" | "−"
MUL: "*" | "×" | "·" | "/"
NAME: /(?!phase\b)[A-Za-zΔ_][A-Za-z0-9_Δ]*/
STRING: /"[^"\n]*"/
NUMBER: /\d+(\.\d*)?([eE][-+]?\d+)?|\.\d+([eE][-+]?\d+)?/
_NL: /(\r?\n|;)/
COMMENT: /#[^\n]*/
%ignore COMMENT
%ignore /[ \t]+/
"""

_READABLE = {"_NL": "end of line", "NAME": "a name", "NUMBER": "a number", "STRING": "a string",
             "EQUAL": "'='", "LPAR": "'('", "RPAR": "')'", "LBRACE": "'{'", "RBRACE": "'}'",
             "COMMA": "','", "CMP": "'~='", "ADD": "'+'", "MUL": "'*'", "MINUS": "'-'",
             "CIRCUMFLEX": "'^'", "PHASE": "'phase'", "$END": "end of script"}
MAX_SCRIPT = 100_000        # characters: a script is a few lines
MAX_DEPTH = 200             # nesting: deeper would overflow Python's recursion


class ScriptError(ValueError):
    """A bad script: ``line:col: message`` (the CLI prints it and exits 2)."""

    def __init__(self, line: int, col: int, message: str):
        super().__init__(f"{line}:{col}: {message}")
        self.line, self.col, self.message = line, col, message


@dataclass(frozen=True)
class Node:
    """One expression node: op is number, name, call, neg, pow, binop, compare."""
    op: str
    value: object           # number: float; name/call: str; binop/compare: operator
    args: tuple             # child Nodes (call: Nodes or str literals)
    line: int
    col: int


@dataclass(frozen=True)
class Statement:
    is_phase: bool
    name: str
    expr: Node
    line: int
    col: int


@dataclass
class Script:
    """A parsed, kind-checked script (see the module docstring)."""
    statements: list[Statement]
    phases: list[str]                 # phase names in order
    kinds: dict[str, int]             # every defined name → its kind
    source: str = ""

    @property
    def n_phases(self) -> int:
        return len(self.phases)


@lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=False)


def _canon(name: str) -> str:
    """Δx and dx are one name (the paper writes Δcm_x, ASCII scripts dcm_x)."""
    return "d" + name[1:] if name.startswith("Δ") else name


class _ToNodes(Transformer):
    @staticmethod
    def _pos(tok):
        return tok.line, tok.column

    def number(self, items):
        (tok,) = items
        return Node("number", float(tok), (), *self._pos(tok))

    def name(self, items):
        (tok,) = items
        return Node("name", _canon(str(tok)), (), *self._pos(tok))

    def string(self, items):
        (tok,) = items
        return str(tok)[1:-1]

    def args(self, items):
        return tuple(items)

    def call(self, items):
        tok, *rest = items
        args = rest[0] if rest and rest[0] is not None else ()
        return Node("call", _canon(str(tok)), tuple(args), *self._pos(tok))

    @v_args(meta=True)
    def neg(self, meta, items):
        return Node("neg", None, (items[0],), meta.line, meta.column)

    @v_args(meta=True)
    def pow(self, meta, items):
        return Node("pow", None, (items[0], items[1]), meta.line, meta.column)

    def binop(self, items):
        a, op, b = items
        sym = {"×": "*", "·": "*", "−": "-"}.get(str(op), str(op))
        return Node("binop", sym, (a, b), op.line, op.column)

    def compare(self, items):
        a, op, b = items
        sym = "~=" if str(op) == "≟" else str(op)
        return Node("compare", sym, (a, b), op.line, op.column)

    def phase(self, items):
        tok, expr = items
        return Statement(True, _canon(str(tok)), expr, tok.line, tok.column)

    def let(self, items):
        tok, expr = items
        return Statement(False, _canon(str(tok)), expr, tok.line, tok.column)

    def start(self, items):
        return [s for s in items if isinstance(s, Statement)]


def _syntax_error(e: UnexpectedInput, text: str) -> ScriptError:
    line, col = getattr(e, "line", 1) or 1, getattr(e, "column", 1) or 1
    if isinstance(e, UnexpectedCharacters):
        return ScriptError(line, col, f"unexpected character {text[e.pos_in_stream]!r}")
    if isinstance(e, UnexpectedEOF) or (isinstance(e, UnexpectedToken) and e.token.type == "$END"):
        return ScriptError(line, col, "unexpected end of script")
    tok = e.token
    if tok.type == "_NL":
        what = "end of line"
    else:
        what = repr(str(tok))
    expected = sorted({_READABLE.get(t, t) for t in e.expected if not t.startswith("__")})
    hint = f"; expected {', '.join(expected[:6])}" if expected else ""
    return ScriptError(line, col, f"unexpected {what}{hint}")


def parse(text: str) -> Script:
    """Parse and kind-check a script; raise ScriptError(line:col) on any error."""
    if len(text) > MAX_SCRIPT:
        raise ScriptError(1, 1, f"script longer than {MAX_SCRIPT} characters")
    try:
        statements = _ToNodes().transform(_parser().parse(text + "\n"))
    except UnexpectedInput as e:
        raise _syntax_error(e, text + "\n") from None
    except RecursionError:
        raise ScriptError(1, 1, "expression nested too deeply") from None
    return _check(statements, text)


def load(path) -> Script:
    """Parse a script file; errors name the file: ``path:line:col: message``."""
    from ..records import FormatError, read_text
    path = Path(path)
    try:
        text = read_text(path, 1 << 20)          # a regular file: a FIFO never blocks
    except FormatError as e:
        err = ScriptError(1, 1, f"cannot read script ({e})")
        err.args = (f"{path}: cannot read script ({e})",)
        raise err from None
    try:
        return parse(text)
    except ScriptError as e:
        err = ScriptError(e.line, e.col, e.message)
        err.args = (f"{path}:{e.line}:{e.col}: {e.message}",)
        raise err from None


# ---------------------------------------------------------------------- checking

def _check(statements: list[Statement], text: str) -> Script:
    kinds: dict[str, int] = {}
    phases: list[str] = []
    for s in statements:
        if s.name in kinds or s.name in MEASURES or s.name in FUNCTIONS:
            what = "a measure" if s.name in MEASURES else "a function" if s.name in FUNCTIONS else "defined above"
            raise ScriptError(s.line, s.col, f"{s.name!r} is already {what}; pick another name")
        if s.is_phase and s.name == "total":
            raise ScriptError(s.line, s.col, "'total' is the score, not a phase: write `total = ...`")
        kind = kind_of(s.expr, kinds, depth=0)
        if s.is_phase or s.name == "total":
            if kind != NUMBER:
                raise ScriptError(s.expr.line, s.expr.col,
                                  f"{'phase ' + s.name if s.is_phase else 'total'} must be a number "
                                  f"per episode, not a {KIND_NAMES[kind]} (reduce it with max_t, last, …)")
        if s.is_phase:
            phases.append(s.name)
        kinds[s.name] = kind
    if "total" not in kinds:
        n = text.count("\n") + 1
        raise ScriptError(n, 1, "the script needs a line `total = ...` (the score)")
    if not phases:
        raise ScriptError(1, 1, "the script declares no phase (`phase NAME = ...`)")
    return Script(statements, phases, kinds, text)


def kind_of(node: Node, kinds: dict[str, int], depth: int) -> int:
    """The node's kind (NUMBER, SIGNAL, POINTS); ScriptError on unknown names or bad kinds."""
    if depth > MAX_DEPTH:
        raise ScriptError(node.line, node.col, "expression nested too deeply")
    if node.op == "number":
        return NUMBER
    if node.op == "name":
        if node.value in kinds:
            return kinds[node.value]
        if node.value in MEASURES:
            return MEASURES[node.value].kind
        hint = " (a function: call it with arguments)" if node.value in FUNCTIONS else ""
        raise ScriptError(node.line, node.col, f"unknown name {node.value!r}{hint}")
    if node.op == "call":
        return _call_kind(node, kinds, depth)
    return max(kind_of(a, kinds, depth + 1) for a in node.args)                      # arithmetic broadcasts numbers over signals over points


def _call_kind(node: Node, kinds: dict[str, int], depth: int) -> int:
    name = node.value
    if name in MEASURES and MEASURES[name].kind != NUMBER:      # the paper's y_i(t)
        if len(node.args) == 1 and isinstance(node.args[0], Node) and node.args[0].op == "name" \
                and node.args[0].value == "t":
            return MEASURES[name].kind
        raise ScriptError(node.line, node.col, f"{name} is a measure: write {name} or {name}(t)")
    fn = FUNCTIONS.get(name)
    if fn is None:
        raise ScriptError(node.line, node.col, f"unknown function {name!r}")
    if len(node.args) != len(fn.args):
        raise ScriptError(node.line, node.col, f"{name} takes {len(fn.args)} argument"
                          f"{'s' if len(fn.args) != 1 else ''} ({', '.join(fn.args)}), got {len(node.args)}")
    sub = []
    for a, want in zip(node.args, fn.args):
        is_str = not isinstance(a, Node)
        line, col = (node.line, node.col) if is_str else (a.line, a.col)
        if (want == "name") != is_str:
            raise ScriptError(line, col, f"{name}: argument must be "
                              f"{'a quoted name' if want == 'name' else 'an expression'}")
        k = None if is_str else kind_of(a, kinds, depth + 1)
        sub.append(k)
        if want in ("signal", "points") and k != {"signal": SIGNAL, "points": POINTS}[want]:
            raise ScriptError(line, col, f"{name} needs {want} ({'a value per frame' if want == 'signal' else 'a value per frame and point'}), "
                              f"got a {KIND_NAMES[k]}")
    if fn.result == "same":
        return max(k for k in sub if k is not None)
    return {"number": NUMBER, "signal": SIGNAL}[fn.result]


# -------------------------------------------------------------------- binding

def bind(script: Script, figure) -> None:
    """Check the script against a figure: quoted site / contact names exist (ScriptError at line:col)."""
    def walk(node):
        if not isinstance(node, Node):
            return
        if node.op == "call" and node.value in FUNCTIONS and "name" in FUNCTIONS[node.value].args:
            what = FUNCTIONS[node.value].names
            known = figure.site_names if what == "site" else figure.contact_names
            for a in node.args:
                if isinstance(a, str) and a not in known:
                    raise ScriptError(node.line, node.col, f"{figure.name} has no {what} {a!r} "
                                      f"({what}s: {', '.join(known) or 'none'})")
        for a in node.args:
            walk(a)
    for s in script.statements:
        walk(s.expr)


# ----------------------------------------------------------------- evaluation

def evaluate(script: Script, traj, bounds, scenes=None) -> dict[str, np.ndarray]:
    """Every phase credit and ``total`` [E] of a (composite) trajectory.

    ``bounds`` int[E, P + 1]: frame of each switch, ``bounds[:, 0] = 0`` and
    ``bounds[:, P]`` the last frame; phase k spans frames bounds[:, k]..bounds[:, k + 1].
    A non-finite total (0/0, √−1, a diverged episode) becomes −inf: the worst.
    ``scenes``: each phase's Scene (a composite's; goals are the phase's), default the trajectory's.
    """
    ctx = Context(traj)
    bounds = np.asarray(bounds, dtype=np.int64)
    E, F = ctx.E, ctx.F
    if bounds.shape != (E, script.n_phases + 1):
        raise ValueError(f"bounds must be [{E}, {script.n_phases + 1}] (one switch per phase), got {bounds.shape}")
    if np.any(np.diff(bounds, axis=1) < 0) or bounds.min() < 0 or bounds.max() > F - 1:
        raise ValueError("bounds must be non-decreasing frame indices within the trajectory")
    values: dict[str, np.ndarray] = {}
    macros = {s.name: s.expr for s in script.statements if not s.is_phase}
    whole = Window.whole(E, F)
    k = 0
    for s in script.statements:
        if s.is_phase:
            win = Window(bounds[:, k], bounds[:, k + 1], F, None if scenes is None else scenes[k])
            values[s.name] = _per_episode(_eval(s.expr, ctx, win, values, macros), E)
            k += 1
    out = {name: values[name] for name in script.phases}
    total = _per_episode(_eval(macros["total"], ctx, whole, values, macros), E)
    out["total"] = np.where(np.isfinite(total) & ~traj.diverged, total, -np.inf)
    return out


def _per_episode(x: np.ndarray, E: int) -> np.ndarray:
    return np.broadcast_to(x, (E, 1, 1)).reshape(E).astype(np.float64)


_BINOPS = {"+": np.add, "-": np.subtract, "*": np.multiply}
_COMPARE = {"<": np.less, "<=": np.less_equal, ">": np.greater, ">=": np.greater_equal}


def _eval(node: Node, ctx: Context, win: Window, values: dict, macros: dict) -> np.ndarray:
    """The node's value [E, F|1, n|1] in window ``win`` (phase credits are already in ``values``)."""
    op = node.op
    if op == "number":
        return np.full((1, 1, 1), node.value)
    if op == "name":
        if node.value in values:
            return values[node.value].reshape(-1, 1, 1)
        if node.value in macros:
            return _eval(macros[node.value], ctx, win, values, macros)
        return MEASURES[node.value].fn(ctx, win)
    if op == "call" and node.value in MEASURES:                 # y_i(t)
        return MEASURES[node.value].fn(ctx, win)
    args = [_eval(a, ctx, win, values, macros) if isinstance(a, Node) else a for a in node.args]
    with np.errstate(all="ignore"):
        if op == "call":
            return FUNCTIONS[node.value].fn(ctx, win, *args)
        if op == "neg":
            return -args[0]
        if op == "pow":
            return np.power(args[0], args[1])
        if op == "binop":
            if node.value == "/":
                return np.divide(args[0], args[1])
            return _BINOPS[node.value](args[0], args[1])
        from .measures import close
        if node.value == "~=":
            return close(args[0], args[1])
        return _COMPARE[node.value](args[0], args[1]).astype(np.float64)
