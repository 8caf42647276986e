"""Linkage kinematics against independent truths (closed forms written out here, not the code's output).

Truths: the slider-crank's rod angle sin th3 = (e - b2 sin th2)/b3 and slider x = b2 cos th2 +
b3 cos th3; its dead centres x = sqrt((b3 ± b2)² - e²) at crank atan2(e, x) (stroke 2·b2 for
e = 0) and full rotation iff b2 + |e| < b3; the law of cosines |A - O4|² = b2² + d² - 2·b2·d·cos th
(four-bar closure range, inverted slider-crank dead points); loop closure |A - B| = b3,
|B - O4| = b4 to 1e-9; velocities by central differences of positions; the quick-return ram on
the line O4-A at the ram's height; a change-point four-bar's smooth motion (finite rates where
the closed form reads 0/0).
"""

import numpy as np
import pytest

from rigfem.errors import ClosureError, InputError
from rigfem.linkage.closed import closed_motion
from rigfem.linkage.kinematics import (
    fourbar_motion,
    fourbar_turn,
    inverted_slider_crank_turn,
    linkage_motion,
    linkage_turn,
    motion_from_history,
    slider_crank_motion,
    slider_crank_turn,
)
from rigfem.linkage.loops import fourbar_angles, fourbar_closes
from rigfem.linkage.mechanisms import four_bar, quick_return, slider_crank
from rigfem.linkage.model import Body


def _rod(b2, b3, e, deg):
    """Rod angle (rad) and slider x (mm) of a slider-crank from its loop closure."""
    th2 = np.radians(deg)
    th3 = np.arcsin((e - b2 * np.sin(th2)) / b3)
    return th3, b2 * np.cos(th2) + b3 * np.cos(th3)


def _bars_are_rigid(m, lengths):
    """Every bar joins named points, and each named pair stays its length apart."""
    for bar, names in m.bars.items():
        assert all(n in m.points for n in names), (bar, names)
    for (p, q), L in lengths.items():
        r = np.hypot(*(m.points[p]["position_mm"] - m.points[q]["position_mm"]).T)
        assert np.allclose(r, L, atol=1e-9 * L), (p, q)


def test_slider_crank_motion_matches_its_loop_closure():
    """Rod angle, slider, transmission angle (90 - rod), mechanical advantage b2·w/|v| with v by
    central differences, the bars and the definitions the CLI reports."""
    b2, b3, e, w = 100.0, 420.0, 35.0, 5.0
    deg = np.arange(3.0, 360.0, 17.0)
    m = slider_crank_motion(b2, b3, e, deg, w)
    th3, x = _rod(b2, b3, e, deg)
    assert np.allclose(np.radians(m.links["rod"]["angle_deg"]), th3, atol=1e-12)
    assert np.allclose(m.slider["position_mm"], x, atol=1e-9)
    assert np.allclose(m.points["B"]["position_mm"][:, 1], e)
    assert np.allclose(m.transmission_deg, 90.0 - np.degrees(th3), atol=1e-9)
    h = 1e-4
    v = (_rod(b2, b3, e, deg + h)[1] - _rod(b2, b3, e, deg - h)[1]) / np.radians(2 * h) * w
    assert np.allclose(m.slider["velocity_mm_s"], v, rtol=1e-6, atol=1e-6)
    assert np.allclose(m.mechanical_advantage, b2 * w / np.abs(v), rtol=1e-6)
    assert m.bars == {"crank": ["O2", "A"], "rod": ["A", "B"]}
    _bars_are_rigid(m, {("O2", "A"): b2, ("A", "B"): b3})
    assert m.meta["type"] == "slider-crank" and m.meta["lengths_mm"] == dict(b2=b2, b3=b3, offset=e)
    assert {"mechanical_advantage", "transmission_angle"} <= set(m.meta)


def test_fourbar_motion_closes_its_loop_and_keeps_its_bars():
    """|A - B| = b3, |B - O4| = b4, |P - A| = p for a coupler point; every bar joins named points."""
    b2, b3, b4, d = 100.0, 300.0, 250.0, 280.0
    deg = np.arange(0.0, 360.0, 15.0)
    for cp in (None, (80.0, 30.0)):
        m = fourbar_motion(b2, b3, b4, d, deg, 3.0, coupler_point=cp)
        lengths = {("O2", "A"): b2, ("A", "B"): b3, ("O4", "B"): b4, ("O2", "O4"): d}
        if cp:
            lengths[("A", "P")] = cp[0]
        _bars_are_rigid(m, lengths)
        assert m.bars["rocker"] == ["O4", "B"] and m.bars["crank"] == ["O2", "A"]
        assert m.meta["type"] == "four-bar" and m.meta["branch"] == "open"
        assert m.meta["lengths_mm"] == dict(b2=b2, b3=b3, b4=b4, d=d)


def test_fourbar_closure_error_names_the_law_of_cosines_range():
    """b2=200, b3=b4=100, d=250: closes while |A - O4| <= 200, i.e. cos th >= (b2²+d²-200²)/(2·b2·d)."""
    b2, b3, b4, d = 200.0, 100.0, 100.0, 250.0
    a = np.degrees(np.arccos((b2**2 + d**2 - 200.0**2) / (2 * b2 * d)))
    with pytest.raises(ClosureError) as e:
        fourbar_motion(b2, b3, b4, d, [180.0])
    msg = str(e.value)
    assert f"0.0 to {np.floor(a * 10) / 10:.1f} deg" in msg, msg
    assert f"{np.ceil((360 - a) * 10) / 10:.1f} to 359.9 deg" in msg, msg


def test_slider_crank_closure_error_range_starts_at_crank_zero():
    """b2=100, b3=50, e=0: the loop closes at crank 0 (rod along the slide), so the first range
    reported starts at 0.0 and ends at asin(1/2) = 30 deg."""
    with pytest.raises(ClosureError) as e:
        slider_crank_motion(100.0, 50.0, 0.0, [90.0])
    assert "crank angles 0.0 to 30.0 deg" in str(e.value), str(e.value)


def test_kinematics_length_limit_is_1e5_mm():
    """The kinematics accept lengths up to 1e5 mm, not above (``Lengths`` hi)."""
    with pytest.raises(InputError):
        fourbar_turn(100000.5, 100.0, 100.0, 100.0)
    with pytest.raises(InputError):
        slider_crank_turn(100000.5, 100.0)


def test_slider_crank_turn_dead_centres_and_stroke():
    """Dead centres sqrt((b3 ± b2)² - e²) at crank atan2(e, x) (inner + 180); stroke 2·b2 for e = 0."""
    for b2, b3, e in ((100.0, 400.0, 0.0), (100.0, 400.0, 60.0)):
        t = slider_crank_turn(b2, b3, e)
        xo, xi = np.sqrt((b3 + b2) ** 2 - e**2), np.sqrt((b3 - b2) ** 2 - e**2)
        out, inn = t["limits"]
        assert out["crank_deg"] == pytest.approx(np.degrees(np.arctan2(e, xo)) % 360, abs=1e-9)
        assert inn["crank_deg"] == pytest.approx(np.degrees(np.arctan2(e, xi)) + 180, abs=1e-9)
        assert out["slider_mm"] == pytest.approx(xo) and inn["slider_mm"] == pytest.approx(xi)
        assert t["stroke_mm"] == pytest.approx(xo - xi)
        if e == 0:
            assert t["stroke_mm"] == pytest.approx(2 * b2)
        assert t["crank_turns_fully"] is True


def test_slider_crank_turn_without_full_rotation():
    """b2 + |e| >= b3 (100 + 60 > 150): no full turn, no stroke, no limit positions; it closes
    where |e - b2 sin th| <= b3: all but the arc between asin((e - b3)/b2) and 180 deg - that."""
    b2, b3, e = 100.0, 150.0, 60.0
    t = slider_crank_turn(b2, b3, e)
    assert t["crank_turns_fully"] is False
    assert t["stroke_mm"] is None and t["limits"] == [] and t["time_ratio"] is None
    a = np.degrees(np.arcsin((e - b3) / b2)) % 360.0
    assert t["dead_points_deg"] == pytest.approx(sorted([a, (180 - a) % 360]))
    lo, hi = sorted([a, (180 - a) % 360])     # sin th < (e - b3)/b2 only between them
    assert t["crank_range_deg"] == pytest.approx([hi, lo + 360.0])


def test_inverted_slider_crank_dead_points_law_of_cosines():
    """The block reaches the slide line while |A - O4| >= arm: cos th <= (b2² + d² - arm²)/(2·b2·d)."""
    d, b2, arm = 300.0, 200.0, 150.0
    a = np.degrees(np.arccos((b2**2 + d**2 - arm**2) / (2 * b2 * d)))
    t = inverted_slider_crank_turn(d, b2, arm)
    assert t["crank_turns_fully"] is False and t["limits"] == [] and t["stroke_mm"] is None
    assert t["dead_points_deg"] == pytest.approx([a, 360 - a])
    assert t["crank_range_deg"] == pytest.approx([a, 360 - a])
    assert t["crank_ranges_deg"] == [t["crank_range_deg"]]
    # arm > b2 + d: |A - O4| never reaches the arm, no angle closes
    t = inverted_slider_crank_turn(100.0, 100.0, 220.0)
    assert t["crank_turns_fully"] is False and t["dead_points_deg"] == [] and t["crank_range_deg"] is None
    assert t["crank_ranges_deg"] == [] and t["limits"] == []
    # arm < d - b2: always reaches, the crank turns fully (no closed form)
    assert inverted_slider_crank_turn(300.0, 100.0, 150.0) is None


def test_fourbar_turn_non_grashof_has_no_time_ratio_and_a_change_point_repeats_after_two_turns():
    """A triple-rocker has no toggles on the crank's path, hence no time ratio; a change-point
    four-bar with one change point, followed on the smooth branch, swaps branches once a turn,
    so it repeats after two turns."""
    t = fourbar_turn(200.0, 100.0, 250.0, 300.0)
    assert t["crank_turns_fully"] is False and t["time_ratio"] is None
    c = fourbar_turn(200.0, 400.0, 700.0, 500.0)   # |d - b2| = |b3 - b4| = 300
    assert c["change_points_deg"] == [0.0] and c["crank_turns_fully"] is True
    assert c["turns_to_repeat"] == 2


def test_builder_linkages_use_their_closed_forms():
    """linkage_motion/linkage_turn of the builders' slider-crank with an offset: slider on y = e,
    x from the loop closure, transmission angle 90 - rod angle, stroke sqrt((b3+b2)²-e²) -
    sqrt((b3-b2)²-e²)."""
    b2, b3, e = 100.0, 420.0, 35.0
    lk = slider_crank(b2, b3, e)
    deg = np.arange(0.0, 360.0, 30.0)
    m = linkage_motion(lk, deg, 2 * np.pi)
    th3, x = _rod(b2, b3, e, deg)
    assert np.allclose(m.points["B"]["position_mm"], np.stack([x, np.full_like(x, e)], -1), atol=1e-9)
    assert np.allclose(m.transmission_deg, 90.0 - np.degrees(th3), atol=1e-9)
    t = linkage_turn(lk)
    assert t["stroke_mm"] == pytest.approx(np.sqrt((b3 + b2) ** 2 - e**2) - np.sqrt((b3 - b2) ** 2 - e**2))


def test_quick_return_ram_on_the_line_through_o4_and_a():
    """The ram's pin C lies on O4-A at height ram_height above O4: x = ram_height·b2 cos th /
    (b2 sin th + pivot_below); its velocity the central difference of that; constant speed."""
    b2, pb, rh = 100.0, 300.0, 500.0
    deg = np.arange(0.0, 360.0, 45.0)
    w = 2 * np.pi
    m = linkage_motion(quick_return(b2, pb, rh, masses=None), deg, w)

    def xc(dg):
        t = np.radians(dg)
        return rh * b2 * np.cos(t) / (b2 * np.sin(t) + pb)

    assert np.allclose(m.slider["position_mm"], xc(deg), atol=1e-7)
    h = 1e-4
    v = (xc(deg + h) - xc(deg - h)) / np.radians(2 * h) * w
    assert np.allclose(m.slider["velocity_mm_s"], v, rtol=1e-6, atol=1e-5)
    assert m.alpha_rad_s2 == 0.0
    assert np.all(m.links["crank"]["alpha_rad_s2"] == 0.0)


def test_general_solver_motion_keeps_the_four_bar_branch():
    """motion_from_history of a four-bar keeps its type, lengths and branch (the CLI reports the branch)."""
    from rigfem.dynamics import solve

    lk = four_bar(100.0, 300.0, 250.0, 280.0, masses=None)
    h = solve(lk, np.arange(0.0, 360.0, 90.0), general=True)
    m = motion_from_history(h)
    assert m.meta.get("branch") == "open" and m.meta.get("type") == "four-bar"
    assert m.alpha_rad_s2 == 0.0
    A, B = m.points["A"]["position_mm"], m.points["B"]["position_mm"]
    assert np.allclose(np.hypot(*(A - B).T), 300.0, atol=1e-9 * 300)


def test_change_point_fourbar_rates_are_finite_and_derivatives():
    """b2=200, b3=400, b4=700, d=500: |d - b2| = |b4 - b3|, flat at crank 0 where the formula reads
    0/0; the smooth motion's rates there are finite and are the central differences of the angles
    on either side (branch +1 after, -1 before)."""
    b2, b3, b4, d, w = 200.0, 400.0, 700.0, 500.0, 2.0
    k = fourbar_angles(b2, b3, b4, d, np.array([0.0]), w, 0.0, 1)
    for n in ("omega3", "omega4", "alpha3", "alpha4"):
        assert np.all(np.isfinite(k[n])), n
    h = 1e-5
    hi = fourbar_angles(b2, b3, b4, d, np.array([h]), w, 0.0, 1)
    lo = fourbar_angles(b2, b3, b4, d, np.array([-h]), w, 0.0, -1)
    for th, om in (("theta3", "omega3"), ("theta4", "omega4")):
        dth = np.angle(np.exp(1j * (hi[th] - lo[th])))
        assert np.allclose(k[om], dth / (2 * h) * w, rtol=1e-4), th
    for x in (hi, lo):   # the angles either side close the loop
        A = np.array([b2 * np.cos(h), b2 * np.sin(h)]) if x is hi else np.array([b2 * np.cos(h), -b2 * np.sin(h)])
        B = A + b3 * np.array([np.cos(x["theta3"][0]), np.sin(x["theta3"][0])])
        assert np.hypot(B[0] - d, B[1]) == pytest.approx(b4, rel=1e-9)


def test_kite_fourbar_with_the_crank_pin_on_o4_closes():
    """b2 = d, b3 = b4: at crank 0 the pin A sits on O4; the coupler and rocker still close the
    loop there (|A - B| = b3, |B - O4| = b4), the motion continuous from crank +0.01 deg."""
    b2, b3, b4, d = 100.0, 200.0, 200.0, 100.0
    th2 = np.radians([0.0, 0.01, 30.0])
    k = fourbar_angles(b2, b3, b4, d, th2, 1.0)
    A = b2 * np.stack([np.cos(th2), np.sin(th2)], -1)
    B = A + b3 * np.stack([np.cos(k["theta3"]), np.sin(k["theta3"])], -1)
    assert np.allclose(np.hypot(B[:, 0] - d, B[:, 1]), b4, rtol=1e-9)
    assert abs(np.angle(np.exp(1j * (k["theta3"][1] - k["theta3"][0])))) < 1e-3


def test_closed_motion_defaults_offset_zero_and_branch_open():
    """A builder linkage whose meta omits the slider-crank's offset (0) or the four-bar's branch
    (open) still gets the closed form: slider x = b2 cos + sqrt(b3² - b2² sin²); |A - B| = b3."""
    b2, b3 = 100.0, 420.0
    lk = slider_crank(b2, b3, 0.0, masses=None)
    del lk.meta["lengths_mm"]["offset"]
    th = np.radians(np.arange(0.0, 360.0, 30.0))
    st = closed_motion(lk, th, 2.0)
    assert st is not None
    _, x = _rod(b2, b3, 0.0, np.degrees(th))
    assert np.allclose(st.joints["B"][:, 0] * 1000, x, atol=1e-9)
    lk = four_bar(100.0, 300.0, 250.0, 280.0, masses=None)
    lk.meta.pop("branch", None)
    assert closed_motion(lk, th, 2.0) is not None


def test_body_history_keeps_the_centre_of_mass():
    """Body.history hands over the body's own centre of mass (local mm) unchanged."""
    b = Body("rail", 1.0, (75.0, 5.0), 10.0)
    n = 3
    z = np.zeros(n)
    bh = b.history(z, z, z, np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2)))
    assert np.allclose(bh.com_local_mm, [75.0, 5.0])


CLOSE = [0.0, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 9.99e-3, 1e-2, 2e-2]  #: rad from a change point


def test_rates_of_the_rhombus_near_its_change_points_are_the_parallelograms():
    """The rhombus 500/500/500/500 moves as a parallelogram (the rocker parallel to the crank): ω4 =
    ω2, α4 = α2, ω3 = α3 = 0 exactly, on both sides of its change points at crank 0 and 180°, where the
    closed form reads 0/0 and, a little off them, loses its digits."""
    t = np.array([c + s * x for c in (0.0, np.pi) for s in (-1, 1) for x in CLOSE]) % (2 * np.pi)
    k = fourbar_angles(500.0, 500.0, 500.0, 500.0, t, 7.0, 3.0)
    np.testing.assert_allclose(k["omega4"], 7.0, rtol=1e-10)
    np.testing.assert_allclose(k["alpha4"], 3.0, rtol=1e-7)
    np.testing.assert_allclose(k["omega3"], 0.0, atol=7e-10)
    np.testing.assert_allclose(k["alpha3"], 0.0, atol=3e-7)


@pytest.mark.parametrize("lengths, change", [((200.0, 400.0, 700.0, 500.0), 0.0),
                                             ((200.0, 300.0, 400.0, 500.0), np.pi)])
def test_rates_near_a_change_point_continue_the_branch_the_motion_is_on(lengths, change):
    """Near a change point the rates are those of the smooth curve the motion is on at that side:
    its values well off the point (1.5e-2 to 6e-2 rad: the closed form there, outside the
    interpolation's 0.01 rad, keeps its digits), the branch on the near side and the other one
    beyond (continuation through the change point), fitted by a polynomial of degree 7 and read at
    the point.  On the change point itself, the motion is
    on the curve it leaves on."""
    far = np.linspace(1.5e-2, 6e-2, 6)
    for side in (-1, 1):
        close = np.array(CLOSE if side > 0 else CLOSE[1:])  # on the point itself: the curve it leaves on
        t = (change + side * close) % (2 * np.pi)
        got = fourbar_angles(*lengths, t, 2.0, 0.5)
        # the branch the motion follows on this side (+1 from crank 0 on) and, past the point, its other sign
        near = fourbar_angles(*lengths, change + side * far, 2.0, 0.5)
        beyond = fourbar_angles(*lengths, change - side * far, 2.0, 0.5,
                                branch=-1 if change == 0.0 else 1)
        x = np.r_[side * far, -side * far]
        for key in ("omega3", "omega4", "alpha3", "alpha4"):
            fit = np.polynomial.Polynomial.fit(x, np.r_[near[key], beyond[key]], 7)
            want = fit(side * close)
            np.testing.assert_allclose(got[key], want, rtol=1e-6, atol=1e-7 * np.abs(want).max(),
                                       err_msg=f"{key} side {side}")


@pytest.mark.parametrize("exact, off", [
    ((1.0, 3.0, 2.0, 2.0), (1.0000000000000004, 3.000000000000003, 2.000000000000003, 2.0)),
    ((500.0, 500.0, 500.0, 500.0), (500.0, 500.0, 500.0, 500.00000000000006))])
def test_a_change_point_four_bar_off_by_rounding_turns_as_the_exact_one(exact, off):
    """Lengths a rounding error off Grashof's equality (e.g. recovered by a synthesis) make the same
    change-point four-bar: the crank turns fully, its dead points are the change points (not a pair
    1e-6° either side of one, bounding a crank range) and it repeats after as many turns."""
    want, got = fourbar_turn(*exact), fourbar_turn(*off)
    assert got["change_points_deg"] == want["change_points_deg"] and want["crank_turns_fully"]
    for key in ("crank_turns_fully", "dead_points_deg", "crank_range_deg", "turns_to_repeat"):
        assert got[key] == want[key], key


@pytest.mark.parametrize("lengths", [(200.0, 400.0, 700.0000006, 500.0), (500.0, 500.0, 500.0, 500.0000001),
                                     (1000.0, 10.0, 10.0, 1000.0), (200.0, 400.0, 700.0, 500.0)])
def test_the_crank_range_of_a_four_bar_near_a_change_point_is_where_its_loop_closes(lengths):
    """Near Grashof's equality (within change_points_deg's tolerance, beyond rounding's) the crank
    turns fully exactly when the loop closes at every crank angle, and its range ends where it stops
    closing (the law of cosines, sampled every 0.01° here)."""
    r = fourbar_turn(*lengths)
    grid = np.linspace(0.0, 360.0, 36001)
    closes = fourbar_closes(*lengths, grid)
    assert r["crank_turns_fully"] == closes.all()
    if not closes.all():
        lo, hi = r["crank_range_deg"]
        inside = ((grid - lo) % 360.0 <= (hi - lo)) | np.isclose((grid - lo) % 360.0, hi - lo, rtol=0, atol=1e-9)
        assert np.array_equal(inside, closes)


def test_rates_of_a_crank_that_swings_through_its_change_point_within_a_few_steps():
    """1000/10/10/1000 mm swings ±1.15° through its change point at 0: the interpolation's nodes
    there must stay inside that range, so its rates are finite and on the smooth curve — the
    central difference of the rocker angle across the point (the branch it leaves on ahead, the
    other behind) — and at ±0.005 rad they are the rocker angle's derivative (central differences)."""
    L = (1000.0, 10.0, 10.0, 1000.0)
    h = 1e-5
    ahead = fourbar_angles(*L, np.array([h]), 1.0)["theta4"]
    behind = fourbar_angles(*L, np.array([-h]), 1.0, branch=-1)["theta4"]
    np.testing.assert_allclose(fourbar_angles(*L, np.array([0.0, 1e-9]), 1.0, 0.0)["omega4"],
                               np.angle(np.exp(1j * (ahead - behind)))[0] / (2 * h), rtol=1e-5)
    h = 1e-7
    for t in (0.005, -0.005):
        th4 = fourbar_angles(*L, np.array([t - h, t + h]), 1.0, 0.0)["theta4"]
        np.testing.assert_allclose(fourbar_angles(*L, np.array([t]), 1.0, 0.0)["omega4"],
                                   (th4[1] - th4[0]) / (2 * h), rtol=1e-6)


@pytest.mark.parametrize("lengths", [(300.0, 100.0, 250.0, 300.0), (400.0, 150.0, 300.0, 350.0)])
def test_the_folded_toggle_of_a_coupler_shorter_than_its_crank(lengths):
    """Folded, a coupler shorter than the crank lies back along it: B on the crank's own line at
    b2 − b3 from O2, and on the rocker's circle — the law of cosines gives the crank angle (one of
    ±θ, the branch's), and the rocker angle is B's direction from O4."""
    b2, b3, b4, d = lengths
    (fold,) = [t for t in fourbar_turn(*lengths)["toggles"] if t["kind"] == "folded"]
    r = b2 - b3
    th = np.radians(fold["crank_deg"])
    assert np.cos(th) == pytest.approx((r * r + d * d - b4 * b4) / (2 * r * d), abs=1e-12)
    B = r * np.array([np.cos(th), np.sin(th)])
    assert fold["rocker_deg"] == pytest.approx(np.degrees(np.arctan2(B[1], B[0] - d)) % 360.0, abs=1e-9)


def test_the_dead_points_of_a_change_point_four_bar_are_its_change_points():
    """The kite 300/700/700/300 lies flat at crank 0 (d − b2 = b3 − b4 = 0) and the rhombus at 0 and
    180°: the law of cosines' cos θ = ±1 exactly there, so those are its dead points, to the bit."""
    assert fourbar_turn(300.0, 700.0, 700.0, 300.0)["dead_points_deg"] == [0.0]
    assert sorted(fourbar_turn(500.0, 500.0, 500.0, 500.0)["dead_points_deg"]) == [0.0, 180.0]
    assert fourbar_turn(200.0, 400.0, 700.0, 500.0)["dead_points_deg"] == [0.0]
