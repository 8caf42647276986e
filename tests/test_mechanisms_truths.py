"""The catalogue's builders and the general solver against independent truths (mutation stop 49).

Truths used, none of them the code's earlier output:

* loop closure in closed form: the four-bar's pin B as an intersection of two circles (and its
  rates from the differentiated loop equation), the quick-return's ram x_C = h·A_x/(A_y + p)
  with the block on the crank pin and aligned with the slot, the slider-crank's reach
  |e − b2 sin θ| <= b3 and the four-bar's |b3 − b4| <= |A − O4| <= b3 + b4; a slot-driven
  quick-return's crank from the law of cosines s² = b2² + p² + 2 b2 p sin θ and its derivatives;
* a four-bar with b2 + d = b3 + b4 folds flat at crank 180° (a change point): the smooth motion
  passes it and ends a turn on the other assembly branch;
* a builder's guess is the assembly at its start angle (constraint residual 0), and the
  constraint Jacobian is the derivative of the residual (central differences);
* the catalogue's masses (geometry/RIG.md §3): a rail is a uniform bar m = λL, I = mL²/12, plates,
  carriages and couplings particles at their joints, labelled by the joint (loads/cases.py matches
  a particle to its coupling by that label);
* a dimensionless number (the scaled Jacobian's reciprocal condition) does not change when the
  linkage is drawn 10 times larger; a quadratic is reproduced exactly by a second-order Taylor
  step and by a quintic Hermite interpolant;
* the value types' boundaries: the value just inside the allowed range accepted, just outside refused.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigfem.errors import InputError
from rigfem.linkage import four_bar, inverted_slider_crank, quick_return, slider_crank
from rigfem.linkage.constraints import Constraints
from rigfem.linkage.dims import Drive, Lengths
from rigfem.linkage.general import _newton, _predict, conditioning, general_motion, rates
from rigfem.linkage.mechanisms import build
from rigfem.linkage.model import ClosureError, Linkage
from rigfem.rig.catalogue import RIG_MASSES
from rigfem.rig.rules import rules_for
from rigfem.scene import Scene


def _q_of(lk: Linkage, model: Constraints) -> np.ndarray:
    """The guess as the solver's coordinates (m, rad), one sample."""
    q = np.zeros(model.m)
    for n, (x, y, p) in lk.guess.items():
        i = 3 * model.index[n]
        q[i:i + 3] = x / 1000, y / 1000, p
    return q[None]


def _fourbar_B(b2, b3, b4, d, th):
    """Both intersections of circle(A, b3) and circle(O4, b4) (mm), A = b2 e^{iθ}, O4 = (d, 0)."""
    A = b2 * np.exp(1j * th)
    O4 = d + 0j
    f = np.abs(O4 - A)
    a = (b3**2 - b4**2 + f**2) / (2 * f)
    h = np.sqrt(b3**2 - a**2)
    e = (O4 - A) / f
    return A + a * e + 1j * h * e, A + a * e - 1j * h * e


# ---------------------------------------------------------------- value types
def test_a_kinematics_length_range_is_open_at_zero():
    """Lengths with lo = 0: (0, hi] mm — 0 refused, the smallest positive length accepted."""
    with pytest.raises(InputError):
        Lengths({"b2": 0.0}, lo=0)
    Lengths({"b2": 1e-300}, lo=0)
    Lengths({"b2": 1e5}, lo=0, hi=1e5)


def test_drive_bounds_are_the_documented_ones():
    """Drive: omega in ±1e4 rad/s, alpha in ±1e7 rad/s² (both ends, just inside and just outside)."""
    for a in (-1e7, 1e7):
        assert Drive(1.0, a).alpha == a
        with pytest.raises(InputError):
            Drive(1.0, a * (1 + 1e-9))
    for w in (-1e4, 1e4):
        assert Drive(w).omega == w
        with pytest.raises(InputError):
            Drive(w * (1 + 1e-9))


def test_four_bar_refuses_an_unknown_mass_model():
    """masses is "rig" or None (dims.Options): anything else is an InputError, not a massless linkage."""
    with pytest.raises(InputError):
        four_bar(100.0, 300.0, 250.0, 300.0, masses="bogus")


# ---------------------------------------------------------------- builders: assembly and closed forms
GUESS_CASES = [
    ("four-bar open 37", lambda: four_bar(100.0, 300.0, 250.0, 300.0, masses=None, start_deg=37.0)),
    ("four-bar crossed 200", lambda: four_bar(100.0, 300.0, 250.0, 300.0, masses=None, branch="crossed", start_deg=200.0)),
    ("slider-crank offset", lambda: slider_crank(150.0, 350.0, -40.0, masses=None, start_deg=30.0)),
    ("slider-crank offset 0", lambda: slider_crank(150.0, 350.0, 25.0)),
    ("inverted 30", lambda: inverted_slider_crank(300.0, 100.0, 50.0, masses=None, start_deg=30.0)),
    ("inverted 0", lambda: inverted_slider_crank(300.0, 100.0, 50.0)),
    ("quick-return 0", lambda: quick_return(100.0, 250.0, 500.0)),
    ("quick-return 130", lambda: quick_return(100.0, 250.0, 500.0, masses=None, start_deg=130.0)),
]


@pytest.mark.parametrize("name,make", GUESS_CASES, ids=[c[0] for c in GUESS_CASES])
def test_the_builders_guess_is_the_assembly_and_the_jacobian_its_derivative(name, make):
    """A builder's guess is its initial assembly at start_deg: every constraint (mm, rad) holds to
    1e-9; the Jacobian (asked without a frame) is the residual's derivative (central differences)."""
    lk = make()
    model = Constraints(lk)
    q = _q_of(lk, model)
    th = np.array([lk.guess["crank"][2]])
    res = model.residual(q, th)
    assert np.max(np.abs(res)) < 1e-12, res
    J = model.jacobian(q)
    eps = 1e-7
    num = np.empty_like(J[0])
    for k in range(model.m):
        dq = np.zeros_like(q)
        dq[0, k] = eps
        num[:, k] = (model.residual(q + dq, th)[0] - model.residual(q - dq, th)[0]) / (2 * eps)
    assert np.allclose(J[0], num, atol=1e-7)
    assert np.array_equal(J, model.jacobian(q, model.frame(q)))


def test_four_bar_motion_is_the_two_circle_intersection_with_its_rates():
    """Crank-rocker 100/300/250/300 mm at 1 Hz over a quarter-step full turn: B = O4 + b4 e^{iθ4} is
    one intersection of circle(A, b3) and circle(O4, b4), the same one throughout; ω and α of the
    coupler and rocker solve the once and twice differentiated loop b2e^{iθ2} + b3e^{iθ3} − b4e^{iθ4} = d;
    a Grashof crank returns to its start: no warning."""
    b2, b3, b4, d = 100.0, 300.0, 250.0, 300.0
    deg = np.array([0.0, 90.0, 180.0, 270.0])
    st = general_motion(four_bar(b2, b3, b4, d, masses=None), deg, speed_hz=1.0)
    assert st.general.warnings == []
    th = np.radians(deg)
    h = st.histories
    B = d + b4 * np.exp(1j * h["rocker"].angle_rad)
    Bp, Bm = _fourbar_B(b2, b3, b4, d, th)
    assert np.allclose(B, Bp, atol=1e-9) or np.allclose(B, Bm, atol=1e-9)
    w2 = 2 * np.pi
    e2, e3, e4 = (np.exp(1j * a) for a in (th, h["coupler"].angle_rad, h["rocker"].angle_rad))
    for i in range(deg.size):
        M = np.array([[(1j * b3 * e3[i]).real, (-1j * b4 * e4[i]).real], [(1j * b3 * e3[i]).imag, (-1j * b4 * e4[i]).imag]])
        rhs = -1j * b2 * w2 * e2[i]
        w3, w4 = np.linalg.solve(M, [rhs.real, rhs.imag])
        rhs2 = b2 * w2**2 * e2[i] + b3 * w3**2 * e3[i] - b4 * w4**2 * e4[i]
        a3, a4 = np.linalg.solve(M, [rhs2.real, rhs2.imag])
        assert h["coupler"].omega_rad_s[i] == pytest.approx(w3, abs=1e-9)
        assert h["rocker"].omega_rad_s[i] == pytest.approx(w4, abs=1e-9)
        assert h["coupler"].alpha_rad_s2[i] == pytest.approx(a3, abs=1e-7)
        assert h["rocker"].alpha_rad_s2[i] == pytest.approx(a4, abs=1e-7)


def test_a_four_bar_that_cannot_turn_is_built_where_it_first_closes_and_solved_over_its_range():
    """100/50/60/100 mm closes only where 10 <= |A − O4| = 200 sin(θ/2) <= 110 mm, from θ = 5.73°:
    whole_turn False and start 0° builds it at the first 0.1° grid angle that closes; solved over
    10-60° (not a full turn) it stays assembled there (B on a circle intersection)."""
    b2, b3, b4, d = 100.0, 50.0, 60.0, 100.0
    grid = np.round(np.arange(0.0, 360.05, 0.1), 10)
    f = np.hypot(b2 * np.cos(np.radians(grid)) - d, b2 * np.sin(np.radians(grid)))
    first = grid[(f >= abs(b3 - b4)) & (f <= b3 + b4)][0]
    assert first == pytest.approx(5.8)
    with pytest.raises(ClosureError):
        four_bar(b2, b3, b4, d, masses=None)
    lk = four_bar(b2, b3, b4, d, masses=None, whole_turn=False)
    assert lk.guess["crank"][2] == pytest.approx(np.radians(first), abs=1e-12)
    deg = np.linspace(10.0, 60.0, 6)
    st = general_motion(lk, deg)
    B = d + b4 * np.exp(1j * st.histories["rocker"].angle_rad)
    Bp, Bm = _fourbar_B(b2, b3, b4, d, np.radians(deg))
    assert np.allclose(B, Bp, atol=1e-9) or np.allclose(B, Bm, atol=1e-9)


def test_a_slider_crank_that_misses_its_line_by_a_narrow_range_is_refused():
    """Crank 100, rod 150 mm, offset 50.01 mm: at θ = 270° |e − b2 sin θ| = 150.01 > b3, so it is
    refused though the rod misses its line only within ±0.8° of 270°; with whole_turn False and
    start 270° it is built at the first 0.1° grid angle where |e − b2 sin θ| <= b3."""
    b2, b3, e = 100.0, 150.0, 50.01
    th = np.radians(270.0)
    assert abs(e - b2 * np.sin(th)) > b3
    with pytest.raises(ClosureError):
        slider_crank(b2, b3, e, masses=None)
    lk = slider_crank(b2, b3, e, masses=None, whole_turn=False, start_deg=270.0)
    grid = np.round(np.arange(0.0, 360.05, 0.1), 10)
    ok = np.abs(e - b2 * np.sin(np.radians(grid))) <= b3
    assert lk.guess["crank"][2] == pytest.approx(np.radians(grid[ok][0]), abs=1e-12)


def test_quick_return_ram_follows_the_slot_closed_form():
    """Quick-return b2 100, O4 250 below, ram line 500 above O4: the block sits on the crank pin
    with the slot's angle φ = atan2(A_y + p, A_x), and the ram's pin C at x = h·A_x/(A_y + p)."""
    b2, p, hgt = 100.0, 250.0, 500.0
    deg = np.arange(0.0, 360.0, 30.0)
    st = general_motion(quick_return(b2, p, hgt, masses=None), deg)
    th = np.radians(deg)
    Ax, Ay = b2 * np.cos(th), b2 * np.sin(th)
    h = st.histories
    assert np.allclose(h["block"].origin_mm, np.stack([Ax, Ay], 1), atol=1e-9)
    phi = np.arctan2(Ay + p, Ax)
    assert np.allclose(np.angle(np.exp(1j * (h["block"].angle_rad - phi))), 0.0, atol=1e-12)
    assert np.allclose(np.angle(np.exp(1j * (h["rocker"].angle_rad - phi))), 0.0, atol=1e-12)
    assert np.allclose(h["ram"].origin_mm[:, 0], hgt * Ax / (Ay + p), atol=1e-9)
    assert np.allclose(h["ram"].origin_mm[:, 1], hgt - p, atol=1e-9)


def test_quick_return_joints_are_the_documented_ones():
    """quick_return's joints are O2, A, slot, O4, slot_C, C, ram_slide (its docstring; reactions are
    reported by these names)."""
    assert [j.name for j in quick_return(100.0, 250.0, 500.0).joints] == ["O2", "A", "slot", "O4", "slot_C", "C",
                                                                            "ram_slide"]


# ---------------------------------------------------------------- catalogue masses
def _rail(L):
    m = RIG_MASSES.rail_kg_m * L / 1000
    return m, m * L**2 / 12


def test_rig_masses_of_the_inverted_slider_crank_and_the_quick_return():
    """geometry/RIG.md §3 (the builders' assumptions): the inverted slider-crank's link 4 is a rail
    of λL4 centred at the arm's foot (arm, 0) plus a plate at O4; its block a carriage + coupling.  The
    quick-return's rocker a rail from O4 (centre L/2 − behind) plus a plate at O4; each block a carriage
    + coupling at its joint; every particle labelled by a joint of its body."""
    c = RIG_MASSES
    L2, L4 = 700.0, 1000.0
    arm = 50.0
    lk = inverted_slider_crank(300.0, 100.0, arm, rails_mm=(L2, L4))
    b = {x.name: x for x in lk.bodies}
    m4, I4 = _rail(L4)
    m, com, inertia = b["rocker"].totals()
    cx = m4 * arm / (m4 + c.plate)
    assert m == pytest.approx(m4 + c.plate, rel=1e-12)
    assert com * 1000 == pytest.approx([cx, 0.0], abs=1e-9)
    assert inertia * 1e6 == pytest.approx(I4 + m4 * (arm - cx) ** 2 + c.plate * cx**2, rel=1e-12)
    assert b["block"].totals()[0] == pytest.approx(c.carriage + c.coupling, rel=1e-12)

    qr = quick_return(100.0, 250.0, 500.0, rails_mm=(L2, L4))
    b = {x.name: x for x in qr.bodies}
    mr, Ir = _rail(L4)
    xr = L4 / 2 - c.rail_behind_mm
    m, com, inertia = b["rocker"].totals()
    cx = mr * xr / (mr + c.plate)
    assert m == pytest.approx(mr + c.plate, rel=1e-12)
    assert com * 1000 == pytest.approx([cx, 0.0], abs=1e-9)
    assert inertia * 1e6 == pytest.approx(Ir + mr * (xr - cx) ** 2 + c.plate * cx**2, rel=1e-12)
    for n in ("block", "ram_block"):
        assert b[n].totals()[0] == pytest.approx(c.carriage + c.coupling, rel=1e-12)
    assert b["ram"].totals()[0] == pytest.approx(c.carriage + c.plate, rel=1e-12)
    for mech in (lk, qr, four_bar(100.0, 300.0, 250.0, 300.0), slider_crank(150.0, 350.0)):
        joints_of = {x.name: set() for x in mech.bodies}
        for j in mech.joints:
            for bn in (j.body_a, j.body_b):
                if bn in joints_of:
                    joints_of[bn].add(j.name)
        for x in mech.bodies:
            for lab, _, _ in x.point_masses:
                assert lab in joints_of[x.name], (x.name, lab)


def test_the_gas_force_acts_at_the_slider_pin():
    """A massless slider-crank under a horizontal gas force: the slider's forces (rod at pin B, gas,
    slide) have no moment about B, so the slide joint carries no moment."""
    from rigfem.dynamics import simulate
    from rigfem.dynamics.forces import compressor_gas_force

    h = simulate(slider_crank(150.0, 350.0, masses=None, slider_force=compressor_gas_force(150.0, 350.0)),
                 samples=12, speed_hz=5.0)
    assert np.abs(h.joints["slide"].force_N).max() > 1.0
    assert np.allclose(h.joints["slide"].moment_Nm, 0.0, atol=1e-9)


# ---------------------------------------------------------------- scenes
def test_a_textbook_scene_keeps_its_textbook_mark():
    """build() records the scene's textbook flag: a textbook linkage has no rig rules (rig/rules.py)."""
    params = dict(b2=100.0, b3=300.0, b4=250.0, d=300.0)
    text = build(Scene("t", "four-bar", params, 1.0, textbook=True))
    rig = build(Scene("r", "four-bar", params, 1.0, textbook=False))
    assert text.meta["textbook"] is True
    assert rules_for(text.meta) == [] and rules_for(rig.meta) != []


# ---------------------------------------------------------------- solver parts
def test_the_scaled_condition_number_does_not_depend_on_the_drawing_scale():
    """rcond of the length-scaled Jacobian is dimensionless: the same four-bar drawn 10× larger has
    the same value at every angle; where it is not finite it is reported as 0 (a toggle)."""
    deg = np.arange(0.0, 360.0, 45.0)
    out = []
    for s in (1.0, 10.0):
        st = general_motion(four_bar(100.0 * s, 300.0 * s, 250.0 * s, 300.0 * s, masses=None), deg)
        out.append(st.general.rcond)
    assert np.allclose(out[0], out[1], rtol=1e-9)
    assert np.all((out[0] > 0) & (out[0] < 1))
    lk = four_bar(100.0, 300.0, 250.0, 300.0, masses=None)
    model = Constraints(lk)
    q = _q_of(lk, model)
    J = model.jacobian(q)
    assert conditioning(model, J, np.full_like(J, np.nan))[0] == 0.0
    assert conditioning(model, J, np.full_like(J, np.inf))[0] == 0.0


def _folded():
    """100/300/200/200 mm four-bar with every body on the x axis (angles exactly 0): b2 + b3 =
    d + b4, a change point, where the constraint Jacobian is exactly singular."""
    lk = four_bar(100.0, 300.0, 200.0, 200.0, masses=None, start_deg=90.0)
    model = Constraints(lk)
    q = np.zeros((1, model.m))
    for n, (x, y) in {"crank": (0.0, 0.0), "coupler": (0.1, 0.0), "rocker": (0.2, 0.0)}.items():
        q[0, 3 * model.index[n]:3 * model.index[n] + 2] = x, y
    return lk, model, q


def test_an_exactly_singular_sample_does_not_spoil_the_others():
    """rates() on [a regular pose, an exactly singular pose]: no error, and the regular sample's
    rates are those of the differentiated loop (as in the four-bar test above)."""
    lk, model, qs = _folded()
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.inv(model.jacobian(qs))
    st = general_motion(lk, np.array([90.0]))
    h = st.histories
    q = qs.copy()
    for n, hb in h.items():
        i = 3 * model.index[n]
        q[0, i:i + 3] = *(hb.origin_mm[0] / 1000), hb.angle_rad[0]
    q = np.vstack([q, qs])
    qd, qdd, J, Jinv = rates(model, q, np.array([np.pi / 2, 0.0]), 1.0)
    assert np.all(np.isfinite(qd[0])) and np.all(np.isfinite(qdd[0]))
    b2, b3, b4 = 100.0, 300.0, 200.0
    e2, e3, e4 = 1j, np.exp(1j * h["coupler"].angle_rad[0]), np.exp(1j * h["rocker"].angle_rad[0])
    M = np.array([[(1j * b3 * e3).real, (-1j * b4 * e4).real], [(1j * b3 * e3).imag, (-1j * b4 * e4).imag]])
    rhs = -1j * b2 * e2
    w3, w4 = np.linalg.solve(M, [rhs.real, rhs.imag])
    assert qd[0, 3 * model.index["coupler"] + 2] == pytest.approx(w3, abs=1e-12)
    assert qd[0, 3 * model.index["rocker"] + 2] == pytest.approx(w4, abs=1e-12)


def test_newton_stops_unconverged_on_an_exactly_singular_jacobian():
    """Newton from the folded pose at a crank angle it does not satisfy: the Jacobian is exactly
    singular, so no step is taken and the sample is reported unconverged."""
    _, model, q = _folded()
    qn, ok = _newton(model, q, np.array([0.1]), 1e-12)
    assert not ok[0]
    assert np.array_equal(qn, q)


def test_the_predictor_reproduces_a_quadratic():
    """_predict: a quadratic q(θ) given by its values and derivatives at nodes 0, 1, 2 is reproduced
    exactly inside (quintic Hermite) and outside (second-order Taylor from the nearer node)."""
    a, b, c = np.array([1.0, -2.0]), np.array([0.5, 3.0]), np.array([-0.25, 0.75])
    nodes = np.array([0.0, 1.0, 2.0])
    qc = a + b * nodes[:, None] + c * nodes[:, None] ** 2
    qdc = b + 2 * c * nodes[:, None]
    qddc = np.broadcast_to(2 * c, qc.shape).copy()
    theta = np.array([-0.7, 0.3, 1.5, 2.6, 3.9])
    pred, _, _ = _predict(nodes, qc, qdc, qddc, theta)
    assert np.allclose(pred, a + b * theta[:, None] + c * theta[:, None] ** 2, atol=1e-12)


def test_newton_stops_unconverged_on_an_undefined_pose():
    """Newton from a NaN pose: its step is not finite, so it stops and reports the sample
    unconverged (it returns (q, mask), it does not raise)."""
    _, model, q = _folded()
    qn, ok = _newton(model, np.full_like(q, np.nan), np.array([0.1]), 1e-12)
    assert not ok[0] and qn.shape == q.shape


# ---------------------------------------------------------------- a driven slider on a turning slot
def _slot_driven(axis=(1.0, 0.0)):
    """The quick-return (b2 100, O4 250 below, ram 500) driven by the block's distance s from O4 along
    the slot, s = 312.25 + 20 sin φ mm (a SliderDriver on the slot, whose rocker turns)."""
    import dataclasses

    from rigfem.linkage.model import SliderDriver

    b2, p = 100.0, 250.0
    th0 = np.radians(30.0)
    mean = np.sqrt(b2**2 + p**2 + 2 * b2 * p * np.sin(th0))
    qr = quick_return(b2, p, 500.0, masses=None, start_deg=30.0)
    joints = [dataclasses.replace(j, axis_a=axis) if j.name == "slot" else j for j in qr.joints]
    return Linkage(qr.bodies, joints, SliderDriver("slot", mean, 20.0), qr.guess, meta=qr.meta), b2, p, mean


@pytest.mark.parametrize("axis", [(1.0, 0.0), (2.0, 0.0)])
def test_a_slot_driven_quick_return_follows_the_law_of_cosines(axis):
    """s = |A − O4| = √(b2² + p² + 2 b2 p sin θ): the crank angle from s, its rate θ' = s'/f'(θ) and
    acceleration θ'' = (s'' − f''θ'²)/f' (f' = b2 p cos θ / f); the slot's axis is a direction (its
    length does not matter)."""
    lk, b2, p, mean = _slot_driven(axis)
    deg = np.arange(0.0, 360.0, 45.0)
    st = general_motion(lk, deg, speed_hz=1.0)
    w = 2 * np.pi
    ph = np.radians(deg)
    s, s1, s2 = mean + 20 * np.sin(ph), 20 * w * np.cos(ph), -20 * w**2 * np.sin(ph)
    th = np.arcsin((s**2 - b2**2 - p**2) / (2 * b2 * p))
    f = lambda t: np.sqrt(b2**2 + p**2 + 2 * b2 * p * np.sin(t))  # noqa: E731
    f1 = lambda t: b2 * p * np.cos(t) / f(t)  # noqa: E731
    f2 = (f1(th + 1e-6) - f1(th - 1e-6)) / 2e-6
    t1 = s1 / f1(th)
    t2 = (s2 - f2 * t1**2) / f1(th)
    c = st.histories["crank"]
    assert np.allclose(c.angle_rad, th, atol=1e-9)
    assert np.allclose(c.omega_rad_s, t1, atol=1e-9)
    assert np.allclose(c.alpha_rad_s2, t2, rtol=1e-6, atol=1e-6)


def test_a_slider_driver_must_name_a_prismatic_joint():
    """SliderDriver on an unknown joint or on a revolute: ComputeError naming it (the layout check)."""
    from rigfem.errors import ComputeError
    from rigfem.linkage.model import SliderDriver

    qr = quick_return(100.0, 250.0, 500.0, masses=None)
    for name in ("nowhere", "A"):
        with pytest.raises(ComputeError, match="prismatic"):
            Constraints(Linkage(qr.bodies, qr.joints, SliderDriver(name, 300.0, 10.0), qr.guess))


@pytest.mark.parametrize("start", [0.0, 175.0])
def test_a_four_bar_folding_flat_passes_the_fold_and_ends_on_the_other_branch(start):
    """540/840/780/1080 mm: b2 + d = b3 + b4, so at crank 180° all four pins lie on the ground line,
    where the open and crossed assemblies meet; the smooth motion through that one change point
    swaps them, so a turn (from 0°, or from 175° where they differ by only 2ψ ≈ 0.08 rad) does not
    return to its start.  Both are reported."""
    b2, b3, b4, d = 540.0, 840.0, 780.0, 1080.0
    assert b2 + d == b3 + b4
    deg = start + 10.0 * np.arange(36)
    st = general_motion(four_bar(b2, b3, b4, d, masses=None, start_deg=start), deg)
    w = st.general.warnings
    assert "the linkage passes a toggle near crank angle 180.00 deg" in w
    assert any("does not return to its starting configuration" in x for x in w)
