"""Synthesis (rigfem/linkage/synthesis.py) against truths computed here, not against its own output:
the motion design closes its loop through the three positions (circle intersection in this file),
Grashof's class and the transmission angle's closed form, invariance under the unit, origin and a
common rotation of the angles, Freudenstein's equation at the precision points, the output scale
of the function, and each documented validation rule at its boundary with its exact message."""

import math

import numpy as np
import pytest

from rigfem.errors import InfeasibleError, InputError
from rigfem.linkage import chebyshev_points, fourbar_motion
from rigfem.linkage.synthesis import (
    FunctionTask,
    Positions,
    check_three_position,
    crank_in_order,
    optimise_three_position,
    synthesize_function,
    three_position,
)

# elliptical-trainer foot points (cm) and free choices (deg) of a defect-free crank-rocker design
TRAINER = np.array([[0.0, 0.0], [-15.12, -9.0], [-29.128, -4.0]])
ALPHA, BETA, GAMMA = [4.875, 7.810], [218.395, -227.639], [7.473, 1.961]


def _z(p):
    return complex(p[0], p[1])


def _loop_points(r, side):
    """The coupler point at the design's three crank angles by loop closure: A on the crank's
    circle about O2, B where the coupler's circle about A meets the rocker's about O4 (on ``side``
    of the line A→O4), the coupler point fixed to A→B."""
    L = r["lengths"]
    O2, th1 = _z(r["O2"]), math.radians(r["ground_angle_deg"])
    O4 = O2 + L["d"] * complex(math.cos(th1), math.sin(th1))
    cd, ca = r["coupler_point"]["distance"], math.radians(r["coupler_point"]["angle_deg"])
    out = []
    for c in r["crank_deg"]:
        A = O2 + L["b2"] * complex(math.cos(th1 + math.radians(c)), math.sin(th1 + math.radians(c)))
        v = O4 - A
        e = abs(v)
        x = (L["b3"] ** 2 - L["b4"] ** 2 + e * e) / (2 * e)
        h = math.sqrt(max(L["b3"] ** 2 - x * x, 0.0))
        B = A + (x + side * 1j * h) * v / e
        P = A + cd * (B - A) / abs(B - A) * complex(math.cos(ca), math.sin(ca))
        out.append([P.real, P.imag])
    return np.array(out)


def _side(r):
    """Which side of A1→O4 the design's B1 lies on (+1 left, -1 right)."""
    L = r["lengths"]
    th1 = math.radians(r["ground_angle_deg"])
    O4 = _z(r["O2"]) + L["d"] * complex(math.cos(th1), math.sin(th1))
    A1, B1 = _z(r["A1"]), _z(r["B1"])
    return 1.0 if ((O4 - A1).conjugate() * (B1 - A1)).imag > 0 else -1.0


def _mu(b2, b3, b4, d):
    """Transmission angle extremes (deg), the crank along the ground line (diagonal d ∓ b2)."""
    return [math.degrees(math.acos((b3 * b3 + b4 * b4 - f * f) / (2 * b3 * b4))) for f in (d - b2, d + b2)]


# --- motion synthesis: three_position and check_three_position -------------------------------------------


@pytest.mark.parametrize("scale,origin", [(1.0, (30.0, -12.0)), (1.0, (9e4, 9e4)), (900.0, (9e4, 9e4))])
def test_motion_design_closes_its_loop_through_the_positions(scale, origin):
    """Any unit and origin of the positions: the pins, the lengths and the coupler point returned
    make one four-bar whose coupler point passes the three positions (loop closure here), and the
    check finds no defect: a design in km is the design in cm (unit and origin are arbitrary)."""
    P = TRAINER * scale + np.array(origin)
    r = three_position(P, ALPHA, BETA, GAMMA)
    L = r["lengths"]
    O2, O4, A1, B1 = (_z(r[k]) for k in ("O2", "O4", "A1", "B1"))
    tol = 1e-12 * (np.abs(P).max() + 1)
    assert abs(A1 - O2) == pytest.approx(L["b2"], abs=tol) and abs(B1 - A1) == pytest.approx(L["b3"], abs=tol)
    assert abs(B1 - O4) == pytest.approx(L["b4"], abs=tol) and abs(O4 - O2) == pytest.approx(L["d"], abs=tol)
    assert math.degrees(np.angle(O4 - O2)) == pytest.approx(r["ground_angle_deg"], abs=1e-9)
    assert r["coupler_point"]["distance"] == pytest.approx(abs(_z(P[0]) - A1), abs=tol)
    assert np.allclose(_loop_points(r, _side(r)), P, rtol=0, atol=1e-9 * (np.abs(P).max() + 1))
    chk = check_three_position(r)
    assert chk["defects"] == [] and chk["branch"] in ("open", "crossed")
    assert chk["position_error"] < 1e-9 * (np.abs(P).max() + 1)


def test_crank_rocker_class_and_transmission_angle_closed_form():
    r = three_position(TRAINER, ALPHA, BETA, GAMMA)
    L = r["lengths"]
    b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
    s, *pq, l_ = sorted([b2, b3, b4, d])
    assert s + l_ < sum(pq) and s == b2            # Grashof, shortest link the crank: a crank-rocker
    chk = check_three_position(r)
    assert chk["grashof"] == "crank-rocker"
    lo, hi = _mu(b2, b3, b4, d)
    assert chk["transmission_deg"] == pytest.approx(dict(min=lo, max=hi), abs=1e-9)


def test_positions_on_two_branches_are_a_branch_defect():
    """The loop closure here puts position 1 on one side of A→O4 and position 3 only on the other
    (no change point between, a crank-rocker): the check reports a branch defect, its kind first."""
    r = three_position(TRAINER, [-2.0, 47.0], [156.0, -51.0], [13.0, -32.0])
    s = _side(r)
    near = np.linalg.norm(_loop_points(r, s) - TRAINER, axis=1) < 1e-9
    far = np.linalg.norm(_loop_points(r, -s) - TRAINER, axis=1) < 1e-9
    assert near.tolist() == [True, True, False] and far.tolist() == [False, False, True]
    assert check_three_position(r)["defects"] == [
        "branch defect: not all three positions lie on the assembly branch of the first"]


def test_first_position_off_the_linkage():
    """Position 1 moved 1 cm off the coupler point's path at the first crank angle (by loop closure
    here on both sides): the linkage is not at position 1 on either branch."""
    r = three_position(TRAINER, ALPHA, BETA, GAMMA)
    r["points"] = (TRAINER + [[1.0, 0.0], [0.0, 0.0], [0.0, 0.0]]).tolist()
    for s in (1.0, -1.0):
        assert np.linalg.norm(_loop_points(r, s)[0] - r["points"][0]) > 0.5
    assert check_three_position(r) == dict(branch=None,
                                           defects=["the linkage cannot be assembled at the first position"])


def test_a_crank_of_no_length_refused():
    """Positions 1e-10 off a rigid rotation about C carrying each into the next (coupler rotations
    α): the crank's dyad (Cramer's rule here) is W ≈ 1e-10 of the positions' spread, a crank of
    no length (for an exact rotation W = 0, Z = P1 − C solves it), though the other links are not."""
    C, R = 3.0 + 1.0j, 2.0 - 0.5j
    al, be, ga = [-19.0, -1.0], [-32.0, 100.0], [-44.0, -1.0]
    z = [C + R * np.exp(1j * math.radians(a)) for a in [0.0, *al]]
    z[2] += 1e-10
    dl = [z[1] - z[0], z[2] - z[0]]
    e = [[np.exp(1j * math.radians(t[k])) - 1 for k in (0, 1)] for t in (be, al)]
    W = (dl[0] * e[1][1] - dl[1] * e[1][0]) / (e[0][0] * e[1][1] - e[0][1] * e[1][0])
    assert abs(W) < 2e-10 * max(map(abs, dl))
    with pytest.raises(InfeasibleError) as err:
        three_position([[v.real, v.imag] for v in z], al, be, ga)
    assert str(err.value) == "the chosen rotations give a zero-length link; change --alpha/--beta/--gamma"


@pytest.mark.parametrize("pts", [[[0, 0], [0.5, 0.5], [0.5, 0.5]], [[0, 0], [0, 0], [0.3, 0.1]],
                                 [[1e3, 2e3], [1e3 + 5e-7, 2e3], [0, 0]]])
def test_coincident_positions_refused_at_any_span(pts):
    with pytest.raises(InputError) as e:
        Positions(pts)
    assert str(e.value) == "--points: the three positions must be distinct"


def test_distinct_small_positions_accepted():
    assert Positions([[0, 0], [1e-3, 0], [0, 1e-3]]).xy.shape == (3, 2)


def _in_order_by_walking(c, step=0.25):
    """Walk the crank from c0 (inclusive) in steps of 0.25 deg one way, then the other, noting which
    of the later angles it meets first (all angles multiples of 0.25 deg here)."""
    for sgn in (1, -1):
        seen = []
        for k in range(0, 1441):
            a = (c[0] + sgn * k * step) % 360
            hits = [j for j in (1, 2) if abs((c[j] - a + 180) % 360 - 180) < 1e-9]
            if len(hits) == 2:
                break                                   # both at once: not in order
            seen += hits
            if len(seen) == 2:
                break
        if seen == [1, 2]:
            return True
    return False


@pytest.mark.parametrize("c", [[0, 90, 180], [0, 270, 180], [10, 0, 0], [0, 10, 10], [350, 340, 330], [5, 100, 50],
                               [200, 10, 20], [359.75, 0.25, 0.5], [0, 0, 90], [120, 120, 120], [30, 300, 350]])
def test_crank_in_order(c):
    """As walking the crank finds, and the same for a common rotation of the three angles and for
    the mirrored angles (the datum and the turning sense are arbitrary)."""
    want = _in_order_by_walking(c)
    assert crank_in_order(c) == want
    for shift in (0.0, 37.5, 180.0, 333.25):
        assert crank_in_order([(x + shift) % 360 for x in c]) == want
        assert crank_in_order([(shift - x) % 360 for x in c]) == want


# --- the optimiser ------------------------------------------------------------------------------------------


@pytest.fixture
def de_calls(monkeypatch):
    """scipy's differential evolution, run as is, its bounds, evaluations and result recorded."""
    import scipy.optimize

    real, calls = scipy.optimize.differential_evolution, []

    def wrapped(func, bounds, **kw):
        rec = dict(bounds=list(bounds), evals=[])

        def f(v):
            y = func(v)
            rec["evals"].append((np.array(v, float), float(y)))
            return y

        rec["result"] = real(f, bounds, **kw)
        calls.append(rec)
        return rec["result"]

    monkeypatch.setattr(scipy.optimize, "differential_evolution", wrapped)
    return calls


@pytest.mark.parametrize("alpha,maxiter", [(ALPHA, 2), (None, 1)])
def test_optimiser_maximises_the_smallest_transmission_angle(de_calls, alpha, maxiter):
    """The design returned is defect-free, its crank turning fully (Grashof, the crank or the ground
    shortest), through the three positions (loop closure here); the value the search minimises is
    −min(μ_min, 180 − μ_max) of each feasible design (closed form here), and the design returned is
    the best the search met.  The rotation ranges searched are symmetric about 0 (turning either
    way is searched alike)."""
    P = TRAINER + [5.0, 2.0]
    r = optimise_three_position(P, alpha, seed=0, maxiter=maxiter)
    assert len(r["beta_deg"]) == 2 and len(r["gamma_deg"]) == 2 and len(r["alpha_deg"]) == 2
    if alpha is not None:
        assert r["alpha_deg"] == alpha
    assert np.allclose(_loop_points(r, _side(r)), P, rtol=0, atol=1e-9)
    chk = check_three_position(r)
    L = r["lengths"]
    s, *pq, l_ = sorted(L.values())
    assert chk["defects"] == [] and s + l_ < sum(pq) and s in (L["b2"], L["d"])    # the crank turns fully
    (rec,) = de_calls
    assert len(rec["bounds"]) == (4 if alpha is not None else 6)
    assert all(lo == -hi for lo, hi in rec["bounds"])
    free = np.r_[r["beta_deg"], r["gamma_deg"], [] if alpha is not None else r["alpha_deg"]]
    assert np.array_equal(free, rec["result"].x)
    assert all(lo <= v <= hi for v, (lo, hi) in zip(free, rec["bounds"]))
    feasible = 0
    for v, y in rec["evals"]:
        if y < 0:
            d = three_position(P, alpha if alpha is not None else v[4:6], v[0:2], v[2:4])["lengths"]
            lo, hi = _mu(d["b2"], d["b3"], d["b4"], d["d"])
            assert y == pytest.approx(-min(lo, 180 - hi), abs=1e-9)
            feasible += 1
    assert feasible > 5
    lo, hi = _mu(L["b2"], L["b3"], L["b4"], L["d"])
    assert -min(lo, 180 - hi) == pytest.approx(min(y for _, y in rec["evals"]), abs=1e-9)


# --- function generation: FunctionTask and synthesize_function ----------------------------------------------

TASK = dict(expr="x*log(x)", x0=1.0, x1=3.0, in_start=20.0, in_range=90.0, out_start=80.0, out_range=90.0, d=2.0)


@pytest.mark.parametrize("key,name", [("x0", "--x X0"), ("x1", "--x X1"), ("in_start", "--input START"),
                                      ("in_range", "--input RANGE"), ("out_start", "--output START"),
                                      ("out_range", "--output RANGE"), ("d", "--ground")])
@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_input_named_as_the_cli_option(key, name, bad):
    with pytest.raises(InputError) as e:
        FunctionTask(**{**TASK, key: bad})
    assert str(e.value) == f"{name} = {bad!r} must be a finite number"


def test_x_range_boundary():
    with pytest.raises(InputError) as e:
        FunctionTask(**{**TASK, "x0": 2.0, "x1": 2.0})
    assert str(e.value) == "--x X0 X1 = 2 2: X1 must be greater than X0"
    assert FunctionTask(**{**TASK, "x0": 2.0, "x1": 2.0 + 1e-9}).y1 > 0


@pytest.mark.parametrize("d", [0.0, -1.0])
def test_ground_boundary_refused(d):
    with pytest.raises(InputError) as e:
        FunctionTask(**{**TASK, "d": d})
    assert str(e.value) == f"--ground = {d:g} must be a positive length"


def test_any_positive_ground_scales_the_linkage():
    """Freudenstein's K's are ratios to d: any positive ground, below 1 too, gives the same
    linkage scaled by d."""
    ref = synthesize_function(**{**TASK, "d": 1.0})["lengths"]
    for d in (1e-3, 0.5, 1.0, 7.0):
        assert FunctionTask(**{**TASK, "d": d}).d == d
        r = synthesize_function(**{**TASK, "d": d})
        assert r["ground"] == d
        assert [r["lengths"][k] for k in "abcd"] == pytest.approx([d * ref[k] for k in "abcd"], rel=1e-9)


def test_freudenstein_equation_at_the_precision_points():
    """K1 = d/a, K2 = d/c, K3 = (a² − b² + c² + d²)/(2ac) of the signed lengths (a link offset 180°
    points the other way) satisfy K1 cos θ4 − K2 cos θ2 + K3 = cos(θ2 − θ4) at each precision point."""
    r = synthesize_function(**TASK)
    L, K = r["lengths"], r["freudenstein"]
    a = -L["a"] if r["input_offset_deg"] == 180 else L["a"]
    c = -L["c"] if r["output_offset_deg"] == 180 else L["c"]
    b, d = L["b"], L["d"]
    assert set(K) == {"K1", "K2", "K3"}
    assert K["K1"] == pytest.approx(d / a, rel=1e-12) and K["K2"] == pytest.approx(d / c, rel=1e-12)
    assert K["K3"] == pytest.approx((a * a - b * b + c * c + d * d) / (2 * a * c), rel=1e-9)
    xp = 2 - np.cos(np.array([1, 3, 5]) * np.pi / 6)                   # Chebyshev spacing on [1, 3]
    t2 = np.radians(20 + (xp - 1) / 2 * 90)
    t4 = np.radians(80 + xp * np.log(xp) / (3 * math.log(3)) * 90)
    assert np.allclose(K["K1"] * np.cos(t4) - K["K2"] * np.cos(t2) + K["K3"], np.cos(t2 - t4), rtol=0, atol=1e-12)


def test_samples_of_the_generated_function():
    r = synthesize_function(**TASK, samples=11)
    g = r["generated"]
    assert np.array_equal(g["x"], np.linspace(1.0, 3.0, 11))
    assert np.allclose(g["y_ideal"], g["x"] * np.log(g["x"]), rtol=0, atol=1e-15)


@pytest.mark.parametrize("shift", [5.0, -40.0])
def test_structural_error_percent_of_the_output_range(shift):
    """Adding a constant to f changes neither the linkage nor its error; the percentage is of the
    output range |f(x1) − f(x0)| = 3 ln 3, whatever f(x0) is."""
    r0 = synthesize_function(**TASK)
    r = synthesize_function(**{**TASK, "expr": f"x*log(x) + ({shift})"})
    assert r["lengths"] == pytest.approx(r0["lengths"], rel=1e-9)
    e = r["structural_error"]
    assert e["max_abs"] == pytest.approx(np.max(np.abs(r["generated"]["error"])), rel=1e-12)
    assert e["max_abs"] == pytest.approx(r0["structural_error"]["max_abs"], rel=1e-6)
    assert e["percent_of_range"] == pytest.approx(100 * e["max_abs"] / (3 * math.log(3)), rel=1e-12)


def _known(a, b, c, d, x0, x1, branch):
    """y = the rocker angle of a known four-bar at crank x (both maps the identity), through its three
    Chebyshev precision points exactly (a quadratic)."""
    xs = chebyshev_points(x0, x1, 3)
    coeffs = np.polyfit(xs, fourbar_motion(a, b, c, d, xs, branch=branch).links["rocker"]["angle_deg"], 2)
    ya, yb = np.polyval(coeffs, [x0, x1])
    return "({!r})*x**2 + ({!r})*x + ({!r})".format(*map(float, coeffs)), x0, x1, x0, x1 - x0, ya, yb - ya, d


def test_crank_longer_than_the_limit_refused():
    """A four-bar with crank 1000.5 × ground (coupler 999.2, rocker 0.5 × ground): Freudenstein gives
    it back (K1 = d/a < 1/1000), longer than MAX_LINK_RATIO allows, though its coupler is not."""
    with pytest.raises(InfeasibleError) as e:
        synthesize_function(*_known(1000.5, 999.2, 0.5, 1.0, 0.0, 30.0, "open"))
    assert "needs links longer than 1000 × --ground (allowed ≤ 1000 ×)" in str(e.value)


@pytest.mark.parametrize("branch", ["open", "crossed"])
def test_change_point_four_bar(branch):
    """A change-point four-bar, |d − a| = |b − c| (1, 3, 2, 2): every link in line at crank 0 deg.  Over
    20..100 deg the crank does not pass it: the linkage comes back, on its branch, with no defect;
    over −30..30 deg it does: a branch defect naming 0 deg."""
    r = synthesize_function(*_known(1.0, 3.0, 2.0, 2.0, 20.0, 100.0, branch))
    assert [r["lengths"][k] for k in "abcd"] == pytest.approx([1.0, 3.0, 2.0, 2.0], rel=1e-9)
    assert r["branch"] == branch and r["defects"] == []
    r = synthesize_function(*_known(1.0, 3.0, 2.0, 2.0, -30.0, 30.0, branch))
    assert r["branch"] == branch
    assert ("branch defect: the crank passes the change point at 0 deg in the input range (every link in line): "
            "there the linkage may leave on either branch") in r["defects"]
