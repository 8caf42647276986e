"""Freudenstein function generation: the generated output (closed-form kinematics, independent of
the synthesis equations) passes through the precision points; safe expressions; the CLI."""

import json

import numpy as np
import pytest

from rigfem.cli import main
from rigfem.linkage import chebyshev_points, fourbar_motion, parse_function, synthesize_function
from rigfem.errors import InputError
from said import said

WORKED = dict(expr="x*log(x)", x0=1.0, x1=3.0, in_start=20.0, in_range=90.0, out_start=80.0, out_range=90.0, d=2.0)


def test_worked_example_hits_the_ideal_at_the_precision_points():
    r = synthesize_function(**WORKED)
    assert r["defects"] == [] and r["branch"] in ("open", "crossed")
    L = r["lengths"]
    xp = np.array([p["x"] for p in r["precision_points"]])
    assert np.allclose(xp, 2 - np.cos(np.array([1, 3, 5]) * np.pi / 6))          # Chebyshev spacing on [1, 3]
    # generated output by the kinematics module, mapped back to y: must equal x ln x at each point
    th2 = 20 + (xp - 1) / 2 * 90 + r["input_offset_deg"]
    m = fourbar_motion(L["a"], L["b"], L["c"], L["d"], th2, branch=r["branch"])
    psi = m.links["rocker"]["angle_deg"] - r["output_offset_deg"]
    psi = (psi - 80 + 180) % 360 - 180 + 80
    y1 = 3 * np.log(3)
    y_gen = (psi - 80) / 90 * y1
    assert np.allclose(y_gen, xp * np.log(xp), rtol=0, atol=1e-9)
    # structural error: zero at the precision points, largest over the range as reported
    g = r["generated"]
    assert np.max(np.abs(g["error"])) == pytest.approx(r["structural_error"]["max_abs"])
    assert 0 < r["structural_error"]["percent_of_range"] < 2
    assert r["structural_error"]["percent_of_range"] == pytest.approx(100 * r["structural_error"]["max_abs"] / y1)


def test_freudenstein_recovers_a_known_linkage():
    """Precision points taken from a known four-bar's own motion give that four-bar back."""
    a, b, c, d = 1.5, 4.0, 3.5, 4.2
    # x is the crank angle and y the rocker angle itself (both maps the identity)
    xs = chebyshev_points(30.0, 110.0, 3)
    mm = fourbar_motion(a, b, c, d, xs)
    coeffs = np.polyfit(xs, mm.links["rocker"]["angle_deg"], 2)      # y(x) through the three points exactly
    expr = "({!r})*x**2 + ({!r})*x + ({!r})".format(*map(float, coeffs))
    y30, y110 = np.polyval(coeffs, [30.0, 110.0])
    r = synthesize_function(expr, 30.0, 110.0, 30.0, 80.0, y30, y110 - y30, d)
    assert r["lengths"]["a"] == pytest.approx(a, rel=1e-9) and r["lengths"]["c"] == pytest.approx(c, rel=1e-9)
    assert r["lengths"]["b"] == pytest.approx(b, rel=1e-9) and r["branch"] == "open"


@pytest.mark.parametrize("expr", ["__import__('os').system('true')", "x.real", "open('f')", "[x]", "lambda: 1",
                                  "x if x else 1", "np.log(x)"])
def test_only_whitelisted_expressions(expr):
    with pytest.raises(InputError, match="EXPR"):
        parse_function(expr)


def test_parse_function_values():
    f = parse_function("sqrt(x)**3 - 2*exp(-x) + sin(pi*x)/e")
    x = np.linspace(0.5, 2, 5)
    assert np.allclose(f(x), np.sqrt(x) ** 3 - 2 * np.exp(-x) + np.sin(np.pi * x) / np.e)
    assert parse_function("2")(np.zeros(3)).shape == (3,)


def test_cli_json_and_plot(capsys, tmp_path):
    png = tmp_path / "s.png"
    rc = main(["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "90", "--output", "80", "90",
               "--ground", "2", "--points", "3", "--json", "--plot", str(png)])
    out, err = capsys.readouterr()
    r = json.loads(out)
    assert rc == 0 and said(err) == [f"rigfem: wrote {png}"] and set(r["lengths"]) == {"a", "b", "c", "d"}
    assert png.stat().st_size > 10_000
    assert r["structural_error"]["max_abs"] > 0 and r["defects"] == []


@pytest.mark.parametrize("argv,needle", [
    (["log(x)", "--x", "-1", "3"], "not finite"),
    (["x", "--x", "3", "1"], "X1 must be greater"),
    (["x*log(x)", "--x", "1", "3", "--points", "4"], "--points"),
    (["cos(2*pi*x)", "--x", "0", "1"], "output range would be zero"),
    (["x**2", "--x", "1", "1.000001"], "--x X0 X1 = 1 1.000001: over this range"),   # f is linear there
    (["x*log(x)", "--x", "1e6", "1.000001e6"], "allowed ≤ 1000 ×"),
    (["x", "--x", "1", "2"], "--x X0 X1 = 1 2"),
])
def test_cli_bad_input(capsys, argv, needle):
    base = {"--input": ["20", "90"], "--output": ["80", "90"], "--ground": ["2"]}
    extra = [t for k, v in base.items() for t in [k, *v]]
    rc = main(["synthesize", "function", *argv, *extra])
    _, err = capsys.readouterr()
    assert rc == 2 and needle in err


TRAINER = np.array([[0.0, 0.0], [-15.12, -9.0], [-29.128, -4.0]])       # elliptical-trainer foot points (cm)


def _kinematics_points(r, branch):
    """The coupler point at the three crank angles, by the closed-form kinematics, in the global frame."""
    L = r["lengths"]
    m = fourbar_motion(L["b2"], L["b3"], L["b4"], L["d"], r["crank_deg"], branch=branch,
                       coupler_point=(r["coupler_point"]["distance"], r["coupler_point"]["angle_deg"]))
    t = np.radians(r["ground_angle_deg"])
    R = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    return np.array(r["O2"]) + m.points["P"]["position_mm"] @ R.T


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_three_position_analytic_and_optimised():
    from rigfem.linkage import check_three_position, optimise_three_position, three_position

    r = optimise_three_position(TRAINER, maxiter=40)
    chk = check_three_position(r)
    assert chk["defects"] == [] and chk["grashof"] == "crank-rocker"
    assert np.allclose(_kinematics_points(r, chk["branch"]), TRAINER, atol=1e-9)
    assert chk["transmission_deg"]["min"] > 45 and chk["transmission_deg"]["max"] < 135
    # the analytic solution with the optimiser's free choices is the same linkage
    r2 = three_position(TRAINER, r["alpha_deg"], r["beta_deg"], r["gamma_deg"])
    assert r2["lengths"] == pytest.approx(r["lengths"], rel=1e-12)
    # a choice whose positions lie on two branches is flagged, not hidden
    bad = check_three_position(three_position(TRAINER * 10, [-20, -40], [90, 180], [30, 60]))
    assert any("branch defect" in d for d in bad["defects"])


def test_cli_motion(capsys):
    rc = main(["synthesize", "motion", "--points", "0,0", "-15.12,-9", "-29.128,-4", "--alpha", "4.875", "7.810",
               "--beta", "218.395", "-227.639", "--gamma", "7.473", "1.961", "--json"])
    out, err = capsys.readouterr()
    r = json.loads(out)
    assert rc == 0 and r["optimised"] is False and r["position_error"] < 1e-9 and r["defects"] == []
    rc = main(["synthesize", "motion", "--points", "0,0", "1,1", "1,1", "--alpha", "1", "2", "--beta", "3", "4",
               "--gamma", "5", "6"])
    _, err = capsys.readouterr()
    assert rc == 2 and "distinct" in err
