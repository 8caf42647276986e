"""Independent truths of the formula language of ``synthesize function`` (rigfem.linkage.expression)
and of the interval check: Python's operator precedence and associativity, numbers and functions
computed with math in the test, a jump's place known by construction, and the documented one-line
refusals (naming EXPR, its value and the x where it fails).

The grammar is built afresh for every test (``fresh_grammar``): the module builds it once at import,
so a test that only used the import-time grammar could never see a change to ``_grammar``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigfem.errors import InputError
from rigfem.linkage import expression
from rigfem.linkage.expression import check_interval, parse_function
from rigfem.linkage.synthesis import FunctionTask


@pytest.fixture(autouse=True)
def fresh_grammar(monkeypatch):
    """parse_function with a grammar built now, not the one built when the module was imported."""
    monkeypatch.setattr(expression, "_GRAMMAR", expression._grammar())


X = np.array([0.5, 1.0, 2.0, 3.0])

#: expression -> the same function written in Python (whose precedence and associativity the
#: grammar documents: ** binds tighter than unary minus on its left, is right-associative and its
#: exponent may carry a sign; * / before + -, both left-associative)
CASES = {
    "1+2*x": lambda x: 1 + 2 * x,
    "2*x+1": lambda x: 2 * x + 1,
    "1-x*3/2": lambda x: 1 - x * 3 / 2,
    "x-2-3": lambda x: x - 2 - 3,
    "24/x/2": lambda x: 24 / x / 2,
    "12-x+1": lambda x: 12 - x + 1,
    "(1+2)*x": lambda x: (1 + 2) * x,
    "x**2": lambda x: x**2,
    "x^2": lambda x: x**2,
    "2**x": lambda x: 2**x,
    "x**x": lambda x: x**x,
    "2**3**x": lambda x: 2 ** (3**x),
    "-x**2": lambda x: -(x**2),
    "2**-x": lambda x: 2 ** (-x),
    "-x": lambda x: -x,
    "--x": lambda x: x,
    "+x": lambda x: x,
    "-(x-4)*2": lambda x: -(x - 4) * 2,
    "x*-3": lambda x: x * -3,
    "3": lambda x: 3.0 + 0 * x,
    "2.5*x": lambda x: 2.5 * x,
    ".25+x": lambda x: 0.25 + x,
    "3.+x": lambda x: 3.0 + x,
    "1.5e2*x": lambda x: 150.0 * x,
    "x*2E-1": lambda x: 0.2 * x,
    "pi*x": lambda x: math.pi * x,
    "e**x": lambda x: math.e**x,
    "sin(x)": lambda x: math.sin(x),
    "cos(pi*x)": lambda x: math.cos(math.pi * x),
    "sqrt(x)**3": lambda x: math.sqrt(x) ** 3,
    "log10(100*x)": lambda x: math.log10(100 * x),
    "abs(1-x)": lambda x: abs(1 - x),
    "exp(-x)*log(x)": lambda x: math.exp(-x) * math.log(x),
    "x*log(x)": lambda x: x * math.log(x),
}


@pytest.mark.parametrize("expr", list(CASES))
def test_formula_is_pythons_arithmetic(expr):
    want = np.array([CASES[expr](float(x)) for x in X])
    got = parse_function(expr)(X)
    assert got.shape == X.shape
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)


def test_precedence_by_hand():
    """The same truths as plain numbers worked by hand, at x = 3."""
    f = {e: float(parse_function(e)(np.array([3.0]))[0]) for e in ("1+2*x", "x-2-3", "24/x/2", "2**3**x",
                                                                    "-x**2", "2**-x", "2**x", "x^2")}
    assert f == {"1+2*x": 7.0, "x-2-3": -2.0, "24/x/2": 4.0, "2**3**x": 2.0**27, "-x**2": -9.0,
                 "2**-x": 0.125, "2**x": 8.0, "x^2": 9.0}


@pytest.mark.parametrize("expr,name,kind", [("y+1", "y", "name"), ("2*foo(x)", "foo", "function")])
def test_unknown_names_refused(expr, name, kind):
    with pytest.raises(InputError) as e:
        parse_function(expr)
    msg = str(e.value)
    assert "\n" not in msg
    assert msg.startswith(f"EXPR: unknown {kind} {name!r}; allowed x, numbers, + - * / ** ^, ( ), pi, e and sin,")


def test_not_finite_names_the_expression_and_the_x():
    """1/(x-1) is infinite at x = 1, the interval's last sample; sqrt(x) is undefined below 0."""
    for expr, x0, x1, where in (("1/(x-1)", 0.0, 1.0, "1"), ("sqrt(x)", -1.0, 1.0, "-1")):
        with pytest.raises(InputError) as e:
            check_interval(parse_function(expr), expr, x0, x1)
        msg = str(e.value)
        assert "\n" not in msg
        assert msg.startswith(f"EXPR = {expr!r} is not finite at x = {where} (division by zero, overflow or "
                              f"outside its domain); give an interval [X0, X1]")


def test_continuous_functions_pass_with_their_values():
    """A constant (no step at all), a line and a steep but continuous function are accepted, and the
    samples are f at np.linspace(X0, X1, samples)."""
    for expr, fn in (("3", lambda x: 3.0 + 0 * x), ("2*x-1", lambda x: 2 * x - 1),
                     ("arctan(50*(x-0.30037))", lambda x: np.arctan(50 * (x - 0.30037)))):
        xs, ys = check_interval(parse_function(expr), expr, 0.0, 1.0, 2001)
        np.testing.assert_array_equal(xs, np.linspace(0.0, 1.0, 2001))
        np.testing.assert_allclose(ys, fn(xs), rtol=1e-15, atol=0)


def test_constant_expression_is_refused_for_its_zero_output_range():
    """f = 3 is continuous: what is wrong with it for synthesis is f(X0) = f(X1)."""
    with pytest.raises(InputError) as e:
        FunctionTask("3", 0.0, 1.0, 30.0, 90.0, 60.0, 90.0, 100.0)
    assert str(e.value) == "EXPR = '3' has f(X0) = f(X1) = 3: the output range would be zero"


@pytest.mark.parametrize("c", [0.30037, 0.30013, 0.71191])
@pytest.mark.parametrize("offset", [0.0, 5.0, -40.0])
def test_jump_is_found_where_it_is(c, offset):
    """offset + sign(x - c) jumps by 2 at x = c (between two samples of [0, 1]): refused, naming c.
    (c = 0.30037 lies in the right half of its sample step, 0.30013 in the left one.)"""
    expr = f"{offset} + abs(x-{c})/(x-{c})"
    with pytest.raises(InputError) as e:
        check_interval(parse_function(expr), expr, 0.0, 1.0)
    _names_pole_or_jump(str(e.value), expr, c)


@pytest.mark.parametrize("c", [0.30037, 0.30013, 0.71191])
@pytest.mark.parametrize("offset", [0.0, 5.0, -40.0])
def test_finite_jump_is_found_where_it_is(c, offset):
    """offset + arctan(1/(x - c)) jumps by pi at x = c and is finite everywhere (pi/2 at c itself)."""
    expr = f"{offset} + arctan(1/(x-{c}))"
    assert np.isfinite(parse_function(expr)(np.array([c]))).all()
    with pytest.raises(InputError) as e:
        check_interval(parse_function(expr), expr, 0.0, 1.0)
    assert str(e.value) == (f"EXPR = {expr!r} has a pole or a jump near x = {c:.6g}; give an interval [X0, X1] "
                            f"where it is continuous")


@pytest.mark.parametrize("c", [0.30037, 0.30013])
def test_pole_between_samples_is_found_where_it_is(c):
    """1/(x - c) is finite at every sample of [0, 1] but has a pole at c."""
    expr = f"1/(x-{c})"
    with pytest.raises(InputError) as e:
        check_interval(parse_function(expr), expr, 0.0, 1.0)
    _names_pole_or_jump(str(e.value), expr, c)


def _names_pole_or_jump(msg: str, expr: str, c: float) -> None:
    """The refusal names the expression and c to six digits (the bisection may land on c itself,
    where the function is not finite, or only near it)."""
    assert "\n" not in msg
    assert msg in (f"EXPR = {expr!r} has a pole or a jump near x = {c:.6g}; give an interval [X0, X1] where it "
                   f"is continuous",
                   f"EXPR = {expr!r} is not finite at x = {c:.6g} (a pole); give an interval [X0, X1] where it "
                   f"is finite")


@pytest.mark.parametrize("expr, column", [("2*(x+1", 7), ("sin(x", 6), ("((x)", 5), ("1+sqrt(x*(2+x)", 15)])
def test_an_unclosed_parenthesis_is_named_where_it_is_missing(expr, column):
    """A parenthesis left open is reported at the end of the text, where the ')' is missing
    (column counted from 1), not where the parser last had a whole expression."""
    with pytest.raises(InputError) as e:
        parse_function(expr)
    assert str(e.value).startswith(f"EXPR = {expr!r} is not an expression of x: Expected ')' at column {column}; allowed x,")


@pytest.mark.parametrize("expr, column", [("sin(", 5), ("sin()", 5), ("*x", 1)])
def test_a_missing_operand_is_named_where_it_is_missing(expr, column):
    """A function's empty argument or a leading operator is named as a missing expression at its
    column, not as pyparsing's dump of the grammar."""
    with pytest.raises(InputError) as e:
        parse_function(expr)
    assert str(e.value).startswith(f"EXPR = {expr!r} is not an expression of x: Expected an expression at column "
                                   f"{column}; allowed x,")
