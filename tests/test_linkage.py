"""General planar solver: four-bar kinematics vs closed form, Newton–Euler balance of every
body, agreement with the 2013 equations where their quirks vanish, branch continuity, toggles."""

import os

import numpy as np
import pytest

from rigfem.dynamics import fourbar_kinematics, loaded_linkage, original_reactions, simulate, solve
from rigfem.linkage import ClosureError, crank_angles, four_bar, transmission_angle
from rigfem.rig import RigMasses

REF = (540.0, 840.0, 780.0, 1020.0)


def _wrap(a):
    return np.angle(np.exp(1j * a))


@pytest.mark.parametrize("branch,sgn", [("open", 1), ("crossed", -1)])
def test_fourbar_kinematics_closed_form_full_turn(branch, sgn):
    """Loop-closure (Freudenstein) positions, velocities, accelerations at 720 angles; the
    continuation must stay on the starting branch all the way round."""
    deg = crank_angles(720)
    h = solve(four_bar(*REF, branch=branch), deg, speed_hz=1.0, general=True)
    k = fourbar_kinematics(*(x / 1000 for x in REF), np.radians(deg), 2 * np.pi, sgn)
    c, r = h.bodies["coupler"], h.bodies["rocker"]
    assert np.max(np.abs(_wrap(c.angle_rad - k["theta3"]))) < 1e-10
    assert np.max(np.abs(_wrap(r.angle_rad - k["theta4"]))) < 1e-10
    assert np.allclose(c.omega_rad_s, k["omega3"], atol=1e-9)
    assert np.allclose(r.omega_rad_s, k["omega4"], atol=1e-9)
    assert np.allclose(c.alpha_rad_s2, k["alpha3"], atol=1e-8)
    assert np.allclose(r.alpha_rad_s2, k["alpha4"], atol=1e-8)
    assert np.allclose(h.joints["B"].position_mm, k["B"] * 1000, atol=1e-8)


def test_branch_continuity_across_full_turn():
    """Successive samples move by a bounded step and the turn closes on itself."""
    h = solve(four_bar(*REF), crank_angles(360), general=True)
    for b in h.bodies.values():
        ang = np.unwrap(np.r_[b.angle_rad, b.angle_rad[0]])
        assert np.max(np.abs(np.diff(ang))) < np.radians(3.0)
        assert abs(ang[-1] - ang[0]) < 1e-9 or b.name == "crank"
    assert "warnings" not in h.meta


def _newton_euler_residual(h, body_name, lk):
    """Independent check: sum of joint forces/moments on a body vs m a_G, I_G alpha."""
    body = next(b for b in lk.bodies if b.name == body_name)
    m, c_m, inertia = body.totals()
    bh = h.bodies[body_name]
    c = np.cos(bh.angle_rad)[:, None] * np.array([1.0, 0]) * c_m[0] + \
        np.sin(bh.angle_rad)[:, None] * np.array([0, 1.0]) * c_m[0]
    c[:, 0] -= np.sin(bh.angle_rad) * c_m[1]
    c[:, 1] += np.cos(bh.angle_rad) * c_m[1]
    w, al = bh.omega_rad_s[:, None], bh.alpha_rad_s2[:, None]
    a_g = bh.origin_acc_mm_s2 / 1000 + al * np.c_[-c[:, 1], c[:, 0]] - w**2 * c
    g = bh.origin_mm / 1000 + c
    F = np.zeros_like(a_g)
    M = np.zeros(a_g.shape[0])
    for j in h.joints.values():
        if body_name not in (j.body_a, j.body_b):
            continue
        f = j.force_N if j.body_b == body_name else -j.force_N
        rr = j.position_mm / 1000 - g
        F += f
        M += rr[:, 0] * f[:, 1] - rr[:, 1] * f[:, 0]
    if body_name == "crank":
        M += h.torque_Nm
    return np.max(np.abs(F - m * a_g)), np.max(np.abs(M - inertia * bh.alpha_rad_s2))


@pytest.mark.parametrize("body", ["crank", "coupler", "rocker"])
def test_rigid_body_reactions_satisfy_newton_euler(body):
    lk = four_bar(*REF)
    h = simulate(lk, samples=180)
    fres, mres = _newton_euler_residual(h, body, lk)
    assert fres < 1e-9 * 700 and mres < 1e-9 * 200


def test_rigid_body_equals_original_where_quirks_vanish():
    """No point masses and rails as long as the bars: the 2013 equations are exact rigid-body
    dynamics, so both models must agree (an independent hand-written equation set)."""
    cat = RigMasses(rail_kg_m=2.7, study_rail_kg_m=2.7, rail_behind_mm=0.0, carriage=0.0, plate=0.0,
                    coupling=0.0)
    b2, b3, b4, d = REF
    lk = four_bar(b2, b3, b4, d, rails_mm=(b2, b3, b4), catalogue=cat)
    h = simulate(lk, samples=90)
    r = original_reactions(b2, b3, b4, d, np.radians(h.crank_deg), 1.0, cat, (b2, b3, b4))
    for name, key in (("O2", "R12"), ("A", "R23"), ("B", "R34"), ("O4", "R14")):
        assert np.allclose(h.joints[name].force_N, r[key], rtol=1e-9, atol=1e-9)
    assert np.allclose(h.torque_Nm, r["M2"], atol=1e-9)


def test_gravity_adds_static_weight():
    """A massive vertical-plane crank-rocker at rest speed -> reactions carry the weight."""
    lk = four_bar(*REF, gravity_mm_s2=(0.0, -9810.0))
    h = simulate(lk, samples=36, speed_hz=1e-6)
    total_w = sum(b.totals()[0] for b in lk.bodies) * 9.81
    fy = h.joints["O2"].force_N[:, 1] + h.joints["O4"].force_N[:, 1]
    assert np.allclose(fy, total_w, rtol=1e-9)


def test_toggle_is_flagged_and_never_a_plain_peak():
    """Change-point four-bar (b2 + d = b3 + b4): mu reaches 180 deg at crank 180 deg."""
    from rigfem.dynamics import peaks

    h = simulate(four_bar(540, 840, 780, 1080), samples=360)
    assert h.meta["singular"] is not None
    lo, hi = h.meta["singular"][0]
    assert lo <= 180.0 <= hi
    p = peaks(h)
    assert all(p[j]["force_N"] is None and p[j]["singular"] for j in ("O2", "A", "B", "O4"))
    assert p["torque"]["peak"] is None
    assert np.all(np.isfinite(h.torque_Nm))


def test_near_toggle_flag_uses_transmission_angle():
    h = simulate(four_bar(540, 840, 780, 1079), samples=720)
    mu = transmission_angle(h.bodies)
    assert h.meta["singular"] is not None
    flagged = h.singular_mask
    near = np.sin(np.radians(mu)) < np.sin(np.radians(5.0))
    assert near.any() and np.array_equal(flagged, near)


def test_far_from_toggle_not_flagged():
    h = simulate(four_bar(*REF), samples=360)
    assert h.meta["singular"] is None and h.singular_mask is None


def test_cannot_close_names_crank_range():
    # d + b2 > b3 + b4 and d - b2 < b3 + b4: the loop breaks around 180 deg
    with pytest.raises(ClosureError, match=r"crank angles \d+\.\d-\d+\.\d deg"):
        four_bar(540, 840, 780, 1200)


# ----------------------------------------------------------------------------- any linkage
def _balance(h, lk):
    """Max force (N) and moment (N·m) imbalance over all bodies, recomputed from the history:
    joint forces at joint points, prismatic constraint moments, driver, loads, gravity."""
    from rigfem.linkage import CrankDriver

    g = np.asarray(lk.gravity_mm_s2) / 1000
    worst_f = worst_m = 0.0
    for body in lk.bodies:
        m, c_loc, inertia = body.totals()
        bh = h.bodies[body.name]
        ca, sa = np.cos(bh.angle_rad), np.sin(bh.angle_rad)
        c = np.stack([ca * c_loc[0] - sa * c_loc[1], sa * c_loc[0] + ca * c_loc[1]], -1)
        w, al = bh.omega_rad_s[:, None], bh.alpha_rad_s2[:, None]
        a_g = bh.origin_acc_mm_s2 / 1000 + al * np.c_[-c[:, 1], c[:, 0]] - w**2 * c
        G = bh.origin_mm / 1000 + c
        F = m * g + np.zeros_like(a_g)
        M = np.zeros(len(a_g))
        for j in h.joints.values():
            if body.name not in (j.body_a, j.body_b):
                continue
            sgn = 1.0 if j.body_b == body.name else -1.0
            f = sgn * j.force_N
            rr = j.position_mm / 1000 - G
            F += f
            M += rr[:, 0] * f[:, 1] - rr[:, 1] * f[:, 0]
            if j.moment_Nm is not None:
                M += sgn * j.moment_Nm
        for ld in lk.loads:
            if ld.body == body.name:
                loc = np.asarray(ld.local_mm) / 1000
                p = bh.origin_mm / 1000 + np.stack([ca * loc[0] - sa * loc[1], sa * loc[0] + ca * loc[1]], -1)
                f = ld.force({"point_mm": p * 1000})
                F += f
                M += (p - G)[:, 0] * f[:, 1] - (p - G)[:, 1] * f[:, 0]
        if isinstance(lk.driver, CrankDriver) and lk.driver.body == body.name:
            M += h.torque_Nm
        worst_f = max(worst_f, np.max(np.abs(F - m * a_g)))
        worst_m = max(worst_m, np.max(np.abs(M - inertia * bh.alpha_rad_s2)))
    return worst_f, worst_m


def _driven_slider_crank():
    """Slider-crank driven at the slider, s = 400 + 80 sin(theta) mm: the crank rocks."""
    from rigfem.linkage import SliderDriver

    lk = slider_crank(150, 350, masses="rig")
    lk.driver = SliderDriver("slide", 400.0, 80.0)
    ax = (400**2 + 150**2 - 350**2) / (2 * 400)
    ay = np.sqrt(150**2 - ax**2)
    lk.guess = {"crank": (0, 0, np.arctan2(ay, ax)), "rod": (ax, ay, np.arctan2(-ay, 400 - ax)),
                "slider": (400, 0, 0)}
    return lk


from rigfem.linkage import inverted_slider_crank, quick_return, slider_crank
from rigfem.scene import load_scene


@pytest.mark.parametrize("make", [
    lambda: four_bar(*REF, gravity_mm_s2=(0.0, -9810.0)),
    lambda: slider_crank(300, 900, 60),
    lambda: inverted_slider_crank(500, 200, 200),
    lambda: quick_return(150, 350, 800),
    lambda: loaded_linkage(load_scene("mech5-compressor")),
    _driven_slider_crank,
], ids=["fourbar-gravity", "slider-crank", "inverted", "quick-return", "compressor", "driven-slider"])
@pytest.mark.parametrize("general", [False, True], ids=["default", "general-solver"])
def test_every_body_in_newton_euler_balance(make, general):
    lk = make()
    h = solve(lk, crank_angles(72), speed_hz=1.5, general=general)
    scale = max(np.abs(j.force_N).max() for j in h.joints.values()) + 1.0
    f, m = _balance(h, lk)
    assert f < 1e-9 * scale and m < 1e-9 * scale


def test_driven_slider_kinematics_and_power():
    """Crank angle from the triangle O2-A-B (cos th = (x^2 + r^2 - l^2) / 2 r x); the actuator
    power F·v equals the rate of change of the kinetic energy of all bodies (spectral
    derivative over the periodic cycle)."""
    lk = _driven_slider_crank()
    deg = crank_angles(360)
    h = solve(lk, deg, speed_hz=1.0)
    x = 400 + 80 * np.sin(np.radians(deg))
    th = np.arccos((x**2 + 150**2 - 350**2) / (2 * 150 * x))
    assert np.allclose(h.bodies["crank"].angle_rad, th, atol=1e-10)
    assert h.meta["driver_unit"] == "N"
    v = 80e-3 * 2 * np.pi * np.cos(np.radians(deg))
    _, dke = _power_balance(h, lk)
    assert np.allclose(h.torque_Nm * v, dke, atol=1e-7 * np.abs(dke).max())


def _power_balance(h, lk):
    """(driver power input by torque·omega, dT/dt) with the kinetic energy T of all bodies
    differentiated spectrally over the periodic cycle (independent of the force solution)."""
    deg = h.crank_deg
    w = 2 * np.pi * h.meta["speed_hz"]
    k = np.fft.rfftfreq(deg.size, 1.0 / deg.size) * 1j * w
    ke = np.zeros(deg.size)
    for body in lk.bodies:
        m, c_loc, inertia = body.totals()
        bh = h.bodies[body.name]
        ca, sa = np.cos(bh.angle_rad), np.sin(bh.angle_rad)
        G = bh.origin_mm / 1000 + np.stack([ca * c_loc[0] - sa * c_loc[1], sa * c_loc[0] + ca * c_loc[1]], -1)
        vg = np.fft.irfft(np.fft.rfft(G, axis=0) * k[:, None], n=deg.size, axis=0)
        ke += 0.5 * m * np.sum(vg**2, 1) + 0.5 * inertia * bh.omega_rad_s**2
    dke = np.fft.irfft(np.fft.rfft(ke) * k, n=deg.size)
    return h.torque_Nm * w, dke


@pytest.mark.parametrize("make", [lambda: four_bar(*REF), lambda: quick_return(150, 350, 800),
                                  lambda: inverted_slider_crank(500, 200, 200)],
                         ids=["rig-fourbar", "quick-return", "inverted"])
@pytest.mark.parametrize("general", [False, True], ids=["default", "general-solver"])
def test_motor_power_equals_rate_of_kinetic_energy(make, general):
    lk = make()
    h = solve(lk, crank_angles(360), speed_hz=1.0, general=general)
    p_in, dke = _power_balance(h, lk)
    assert np.allclose(p_in, dke, atol=1e-7 * np.abs(dke).max())


def test_guess_at_another_angle_keeps_the_branch():
    """A linkage assembled at crank 130 deg and solved from 0 deg stays on its branch."""
    for branch, sgn in (("open", 1), ("crossed", -1)):
        lk = four_bar(*REF, branch=branch, start_deg=130.0)
        deg = crank_angles(36)
        h = solve(lk, deg, general=True)
        k = fourbar_kinematics(*(x / 1000 for x in REF), np.radians(deg), 2 * np.pi, sgn)
        assert np.max(np.abs(_wrap(h.bodies["rocker"].angle_rad - k["theta4"]))) < 1e-10


@pytest.mark.parametrize("offset", [590.0, 599.9])
def test_near_toggle_slider_crank_keeps_its_branch(offset):
    """b2 + offset just below b3: the two assembly branches nearly touch at crank 270 deg.
    The slider must stay on the +x branch, x = Ax + sqrt(b3^2 - (e - Ay)^2), all the way round."""
    h = solve(slider_crank(300, 900, offset), crank_angles(360), general=True)
    th = np.radians(h.crank_deg)
    x = 300 * np.cos(th) + np.sqrt(900**2 - (offset - 300 * np.sin(th)) ** 2)
    assert np.allclose(h.bodies["slider"].origin_mm[:, 0], x, atol=1e-8)
    assert "warnings" not in h.meta
    # rod within 5 deg of perpendicular to the slide only for the tighter case
    assert (h.meta["singular"] is not None) == (offset > 595.0)


def test_evaluator_far_from_the_solved_range_falls_back_to_continuation():
    """Solved on 0-90 deg only, then evaluated at 250 deg: the Taylor prediction is far off,
    so the solver continues through to the sample and must land on the same branch."""
    lk = four_bar(*REF)
    h = solve(lk, np.linspace(0.0, 90.0, 10), general=True)
    far = h.evaluator(np.array([250.0, 300.0]))
    k = fourbar_kinematics(*(x / 1000 for x in REF), np.radians([250.0, 300.0]), 2 * np.pi, 1)
    assert np.allclose(_wrap(far.bodies["rocker"].angle_rad - k["theta4"]), 0.0, atol=1e-10)
    assert np.allclose(far.bodies["coupler"].alpha_rad_s2, k["alpha3"], atol=1e-8)


@pytest.mark.parametrize("model", ["rigid-body", "original"])
def test_toggle_between_samples_is_still_flagged(model):
    """9 samples (40 deg apart) straddle the near-toggle at crank 180 deg (mu -> 179.9 deg)."""
    from rigfem.dynamics import peaks

    h = simulate(four_bar(540, 840, 780, 1079.99), samples=9, model=model)
    assert h.singular_mask is None                       # no sample is near the toggle ...
    lo, hi = h.meta["singular"][0]                       # ... but the range is reported
    assert lo < 180.0 < hi
    assert peaks(h)["B"]["force_N"] is None and peaks(h)["torque"]["peak"] is None


def test_joint_direction_convention():
    """Naming the ground as body_b flips the reported force (force BY body_a ON body_b)."""
    from rigfem.linkage import Revolute

    lk = four_bar(*REF)
    h = solve(lk, crank_angles(24))
    lk2 = four_bar(*REF)
    lk2.joints[3] = Revolute("O4", "rocker", "ground", (0.0, 0.0), (REF[3], 0.0))
    h2 = solve(lk2, crank_angles(24))
    assert np.allclose(h2.joints["O4"].force_N, -h.joints["O4"].force_N, atol=1e-9)
    assert np.allclose(h2.joints["O4"].position_mm, [REF[3], 0.0])
    assert np.allclose(h2.torque_Nm, h.torque_Nm, atol=1e-9)


def test_solve_keeps_its_general_solver_options_as_deprecated_keywords(monkeypatch):
    """``solve(..., tol_mm=, check_closure=)`` still runs, with a DeprecationWarning, and hands them
    to the general solver when it runs; a misspelt keyword is a TypeError, as before."""
    import rigfem.dynamics.solver as solver

    lk, deg = four_bar(*REF), crank_angles(72)
    got, general = [], solver.general_motion
    monkeypatch.setattr(solver, "general_motion", lambda *a, **k: got.append(k) or general(*a, **k))
    with pytest.warns(DeprecationWarning, match="tol_mm"):
        old = solve(lk, deg, 2.5, tol_mm=1e-7, check_closure=False, general=True)
    assert got == [{"tol_mm": 1e-7, "check_closure": False}]
    assert np.allclose(old.torque_Nm, solve(lk, deg, 2.5, general=True).torque_Nm, rtol=1e-9, atol=0)
    assert old.meta["speed_hz"] == 2.5  # the history says the speed it was solved at
    with pytest.warns(DeprecationWarning, match=r"^solve\(tol_mm=\.\.\., check_closure=\.\.\.\) is deprecated: no "
                      r"caller changes the general solver's tolerance or closure check; the argument goes in "
                      r"rigfem 0\.3$") as caught:
        solve(lk, deg, tol_mm=1e-7, check_closure=False, general=True)
    if "MUTANT_UNDER_TEST" not in os.environ:  # mutmut's trampoline adds a frame
        assert [w.filename for w in caught] == [__file__]  # the caller's line: a script sees it
    with pytest.warns(DeprecationWarning, match="check_closure"):
        closed = solve(lk, deg, 2.5, check_closure=False)  # the closed form applies: no general solver
    assert len(got) == 2 and closed.meta["solver"] == "closed form"
    assert np.allclose(closed.torque_Nm, solve(lk, deg, 2.5).torque_Nm, rtol=1e-12, atol=0)
    with pytest.raises(TypeError, match="tol"):
        solve(lk, deg, tol=1e-9)
