"""The expression of ``synthesize function``: y = f(x) parsed by a grammar (pyparsing), never eval.

Numbers, x, pi, e, + - * / ** (also ^), parentheses and the functions in :data:`FUNCS`.  The
parsed tree is evaluated on numpy arrays with floating-point errors silenced; the caller then
checks that the values are finite and continuous over its interval (:func:`check_interval`).
"""

from __future__ import annotations

import numpy as np
import pyparsing as pp

from rigfem.errors import InputError, plain

__all__ = ["FUNCS", "MAX_LENGTH", "MAX_DEPTH", "parse_function", "check_interval"]

FUNCS = {n: getattr(np, n) for n in ("sin", "cos", "tan", "arcsin", "arccos", "arctan", "sinh", "cosh", "tanh",
                                     "exp", "log", "log10", "log2", "sqrt", "abs")}
CONSTS = {"pi": np.pi, "e": np.e}
#: longest expression accepted (characters) and deepest nesting of parentheses
MAX_LENGTH, MAX_DEPTH = 10_000, 60
_ALLOWED = f"x, numbers, + - * / ** ^, ( ), pi, e and {', '.join(FUNCS)}"


def _grammar() -> pp.ParserElement:
    """expr = term (+|- term)*; term = factor (*|/ factor)*; factor = (+|-) factor | power;
    power = atom [(**|^) factor] (right-associative, the exponent may carry a sign, as in Python)."""
    number = pp.Regex(r"(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?").set_parse_action(lambda t: ("num", float(t[0])))
    name = pp.Word(pp.alphas + "_", pp.alphanums + "_")
    expr, factor = pp.Forward(), pp.Forward()
    call = (name + pp.Suppress("(") - expr - pp.Suppress(")")).set_parse_action(lambda t: ("call", t[0], t[1]))
    var = name.copy().set_parse_action(lambda t: ("name", t[0]))
    atom = call | number | var | (pp.Suppress("(") + expr - pp.Suppress(")"))
    power = (atom + pp.Optional(pp.one_of("** ^").suppress() + factor)).set_parse_action(
        lambda t: ("**", t[0], t[1]) if len(t) == 2 else t[0])
    signed = (pp.one_of("+ -") + factor).set_parse_action(lambda t: ("neg", t[1]) if t[0] == "-" else t[1])
    factor <<= (signed | power).set_name("an expression")  # the name a refusal says it expected
    term = (factor + pp.ZeroOrMore(pp.one_of("* /") + factor)).set_parse_action(lambda t: _fold_left(t))
    expr <<= (term + pp.ZeroOrMore(pp.one_of("+ -") + term)).set_parse_action(lambda t: _fold_left(t))
    return expr


def _fold_left(items) -> tuple:
    """A left-to-right chain ``a op b op c ...`` as one flat node, so a long sum needs no recursion."""
    if len(items) == 1:
        return items[0]
    return ("chain", items[0], [(items[i], items[i + 1]) for i in range(1, len(items), 2)])


_OPS = {"+": np.add, "-": np.subtract, "*": np.multiply, "/": np.true_divide, "**": np.power}
pp.ParserElement.enable_packrat()
_GRAMMAR = _grammar()


def _depth(expr: str) -> int:
    """Deepest nesting of parentheses (what the parser and the evaluator recurse on)."""
    depth = best = 0
    for ch in expr:
        depth += (ch == "(") - (ch == ")")
        best = max(best, depth)
    return best


def _build(node, expr: str):
    while isinstance(node, pp.ParseResults):
        node = node[0]
    kind = node[0]
    if kind == "num":
        v = node[1]
        if not np.isfinite(v):
            raise InputError(f"EXPR: the number in {plain(expr, 60)!r} overflows (largest 1.8e308)")
        return lambda x: v
    if kind == "name":
        if node[1] == "x":
            return lambda x: x
        if node[1] in CONSTS:
            v = CONSTS[node[1]]
            return lambda x: v
        raise InputError(f"EXPR: unknown name {plain(node[1], 40)!r}; allowed {_ALLOWED}")
    if kind == "call":
        if node[1] not in FUNCS:
            raise InputError(f"EXPR: unknown function {plain(node[1], 40)!r}; allowed {_ALLOWED}")
        f, arg = FUNCS[node[1]], _build(node[2], expr)
        return lambda x: f(arg(x))
    if kind == "neg":
        arg = _build(node[1], expr)
        return lambda x: -arg(x)
    if kind == "chain":
        first = _build(node[1], expr)
        rest = [(_OPS[op], _build(arg, expr)) for op, arg in node[2]]

        def chain(x):
            out = first(x)
            for op, arg in rest:
                out = op(out, arg(x))
            return out
        return chain
    op = _OPS[kind]
    a, b = _build(node[1], expr), _build(node[2], expr)
    return lambda x: op(a(x), b(x))


def parse_function(expr: str):
    """A function of ``x`` (numpy array in, float array out) from the text ``expr``; InputError
    naming what is wrong (syntax with its column, unknown names, too long or too deeply nested)."""
    text = str(expr)
    if not text.strip():
        raise InputError("EXPR is empty; give f(x), e.g. 'x*log(x)'")
    if len(text) > MAX_LENGTH:
        raise InputError(f"EXPR is {len(text)} characters long; allowed at most {MAX_LENGTH}")
    if _depth(text) > MAX_DEPTH:
        raise InputError(f"EXPR nests parentheses {_depth(text)} deep; allowed at most {MAX_DEPTH}")
    try:
        tree = _GRAMMAR.parse_string(text, parse_all=True)[0]
        fn = _build(tree, text)
    except pp.ParseBaseException as exc:
        raise InputError(f"EXPR = {plain(text, 60)!r} is not an expression of x: {plain(exc.msg, 60)} at "
                         f"column {exc.col}; allowed {_ALLOWED}") from None
    except RecursionError:
        raise InputError(f"EXPR nests too deeply; allowed at most {MAX_DEPTH} levels") from None

    def f(x):
        x = np.asarray(x, float)
        with np.errstate(all="ignore"):
            return np.asarray(fn(x), float) + np.zeros_like(x)
    return f


def check_interval(f, expr: str, x0: float, x1: float, samples: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """(xs, f(xs)) on [x0, x1]; InputError naming the x where f is not finite (overflow, division by
    zero, outside its domain) or has a pole or jump (the steepest step does not shrink when halved)."""
    xs = np.linspace(x0, x1, samples)
    ys = f(xs)
    bad = ~np.isfinite(ys)
    if bad.any():
        raise InputError(f"EXPR = {plain(expr, 60)!r} is not finite at x = {xs[bad][0]:.6g} (division by zero, "
                         f"overflow or outside its domain); give an interval [X0, X1] where it is finite")
    i = int(np.argmax(np.abs(np.diff(ys))))
    a, b = xs[i], xs[i + 1]
    first = abs(ys[i + 1] - ys[i])
    for _ in range(60):
        if first == 0:
            break
        m = 0.5 * (a + b)
        fa, fm, fb = f(np.array([a, m, b]))
        if not np.isfinite(fm):
            raise InputError(f"EXPR = {plain(expr, 60)!r} is not finite at x = {m:.6g} (a pole); give an "
                             f"interval [X0, X1] where it is finite")
        a, b = (a, m) if abs(fm - fa) >= abs(fb - fm) else (m, b)
        if max(abs(fm - fa), abs(fb - fm)) < 0.25 * first:
            break
    else:
        raise InputError(f"EXPR = {plain(expr, 60)!r} has a pole or a jump near x = {0.5 * (a + b):.6g}; give an "
                         f"interval [X0, X1] where it is continuous")
    return xs, ys
