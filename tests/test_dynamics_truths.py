"""The dynamics against truths written without rigfem (issue 39: the dynamics package's mutants).

* The ``original`` model is the 2013 study's program: tests/newton_euler.py ``study_program``
  writes it from geometry/RIG.md §3's description (quirks included) and reproduces the study's printed
  calibration figures; rigfem's original history equals it at every crank angle, and its bodies
  move as the closed-form four-bar of tests/newton_euler.py.
* The reactions summary (``rigfem reactions --json``) states the Newton–Euler peaks, the
  transmission angle of geometry/RIG.md §2's law of cosines and the rig rules' values.
* A history known only by its samples (an imported CSV: a cubic spline between them) finds the
  Newton–Euler peaks.
* The compressor's gas force (geometry/MECHANISMS.md §5) on a massless slider-crank is balanced
  by the motor torque of virtual work: T·ω = −F·v.
* A toggle (transmission angle below 5°) is reported where the law of cosines puts it.
"""

import dataclasses

import numpy as np
import pytest
from newton_euler import (
    fourbar_motion,
    fourbar_newton_euler,
    newton_euler_peak,
    slider_crank_newton_euler,
    study_program,
)

from rigfem.dynamics import (
    compressor_gas_force,
    fourbar_kinematics,
    original_program,
    original_reactions,
    peaks,
    simulate,
    solve,
    summary,
)
from rigfem.linkage import four_bar, slider_crank

CALIBRATION = {"O2": 641.9099, "A": 578.8140, "B": 379.4016, "O4": 366.4701, "torque": 199.7707}  # geometry/RIG.md §3
STUDY = (540.0, 840.0, 780.0, 1020.0)
FINAL_CM = (480.0, 840.0, 780.0, 1020.0)


def test_the_study_program_written_from_rig_md_prints_the_studys_figures():
    rows = [study_program(*STUDY, t) for t in np.linspace(0.0, 360.0, 5000)]  # the study's 5000 instants
    for j in ("O2", "A", "B", "O4"):
        assert max(abs(r[0][j]) for r in rows) == pytest.approx(CALIBRATION[j], rel=1e-4), j
    assert max(abs(r[1]) for r in rows) == pytest.approx(CALIBRATION["torque"], rel=1e-4)


@pytest.mark.parametrize("lengths, speed_hz", [(STUDY, 1.0), (FINAL_CM, 1.7)])
def test_the_original_model_is_the_study_program_at_every_angle(lengths, speed_hz):
    h = simulate(four_bar(*lengths), samples=24, speed_hz=speed_hz, model="original")
    assert h.meta["model"] == "original" and h.meta["singular"] is None and h.meta["speed_hz"] == speed_hz
    scale = max(abs(F) for F in study_program(*lengths, 0.0, speed_hz)[0].values())
    extra = np.array([3.3, 101.7, 250.05])
    between = h.evaluator(extra)
    assert h.full_turn and not between.full_turn
    for hist, angles in ((h, h.crank_deg), (between, extra)):
        assert np.array_equal(hist.crank_deg, angles)
        assert {n: (j.name, j.body_a, j.body_b) for n, j in hist.joints.items()} == {
            "O2": ("O2", "ground", "crank"), "A": ("A", "crank", "coupler"), "B": ("B", "coupler", "rocker"),
            "O4": ("O4", "ground", "rocker")}
        assert {n: b.name for n, b in hist.bodies.items()} == {"crank": "crank", "coupler": "coupler", "rocker": "rocker"}
        for i, t in enumerate(angles):
            forces, torque, pos = study_program(*lengths, t, speed_hz)
            for name, F in forces.items():
                assert np.allclose(hist.joints[name].force_N[i], [F.real, F.imag], rtol=0, atol=1e-9 * scale), (name, t)
                assert np.allclose(hist.joints[name].position_mm[i], [pos[name].real, pos[name].imag], atol=1e-6)
            assert hist.torque_Nm[i] == pytest.approx(torque, abs=1e-9 * scale)
            k = fourbar_motion(*lengths, t, speed_hz)
            for b, name in enumerate(("crank", "coupler", "rocker")):
                body = hist.bodies[name]
                assert np.exp(1j * body.angle_rad[i]) == pytest.approx(k["e"][b], abs=1e-12), (name, t)
                assert body.omega_rad_s[i] == pytest.approx(k["w"][b], abs=1e-9), (name, t)
                assert body.alpha_rad_s2[i] == pytest.approx(k["al"][b], abs=1e-9 * (1 + abs(k["al"][b]))), (name, t)
            origin = {"crank": 0j, "coupler": k["A"], "rocker": k["O4"]}
            acc = {"crank": 0j, "coupler": k["aA"], "rocker": 0j}
            for name in origin:
                body = hist.bodies[name]
                assert np.allclose(body.origin_mm[i], [origin[name].real * 1000, origin[name].imag * 1000], atol=1e-6)
                assert np.allclose(body.origin_acc_mm_s2[i], [acc[name].real * 1000, acc[name].imag * 1000],
                                   atol=1e-6 * (1 + abs(acc[name]) * 1000)), (name, t)
    rig = simulate(four_bar(*lengths), samples=8, speed_hz=speed_hz)
    for name in ("crank", "coupler", "rocker"):  # the bodies' mass data are the linkage's
        a, b = h.bodies[name], rig.bodies[name]
        assert (a.mass_kg, a.inertia_com_kg_mm2) == (b.mass_kg, b.inertia_com_kg_mm2)
        assert [(n, m, list(x)) for n, m, x in a.point_masses] == [(n, m, list(x)) for n, m, x in b.point_masses]
        assert np.array_equal(a.com_local_mm, b.com_local_mm) and a.joint_local_mm.keys() == b.joint_local_mm.keys()


@pytest.mark.parametrize("branch", [1, -1])
def test_original_reactions_of_the_program_itself(branch):
    th = np.radians([0.0, 77.0, 190.0])
    r = original_reactions(*STUDY, th, branch=branch)  # at the study's 1 Hz unless told
    assert np.allclose(r["kin"]["omega2"], 2 * np.pi)
    for i, t in enumerate(np.degrees(th)):
        forces, torque, _ = study_program(*STUDY, t, branch=branch)
        for key, name in (("R12", "O2"), ("R23", "A"), ("R34", "B"), ("R14", "O4")):
            assert np.allclose(r[key][i], [forces[name].real, forces[name].imag], atol=1e-9)
        assert r["M2"][i] == pytest.approx(torque, abs=1e-9)
    with pytest.raises(ValueError, match="cannot close"):
        fourbar_kinematics(300.0, 400.0, 200.0, 1100.0, np.radians([0.0, 90.0]), 2 * np.pi)


def test_the_study_program_prints_its_figures_from_5000_instants_at_1_hz():
    """original_program samples exactly like the study (5000 instants, both ends, 1 Hz, no refinement)."""
    got = original_program(*STUDY)
    rows = [study_program(*STUDY, t) for t in np.degrees(np.linspace(0.0, 2 * np.pi, 5000))]
    for j in ("O2", "A", "B", "O4"):
        assert got[j] == pytest.approx(max(abs(r[0][j]) for r in rows), rel=1e-12), j
    assert got["torque_Nm"] == pytest.approx(max(abs(r[1]) for r in rows), rel=1e-12)
    mu = law_of_cosines_mu(*STUDY, np.degrees(np.linspace(0.0, 2 * np.pi, 5000)))
    assert (got["mu_min_deg"], got["mu_max_deg"]) == pytest.approx((mu.min(), mu.max()), rel=1e-9)


def test_the_general_solver_is_newton_euler_too():
    """The rig slider-crank through the general planar solver at its default 1 Hz: every pin force
    and the torque are the Newton–Euler ones; the point-mass slider's guide takes no moment."""
    lk = slider_crank(300.0, 840.0, 0.0)
    deg = np.arange(0.0, 360.0, 30.0)
    h = solve(lk, deg, general=True)
    assert (h.meta["solver"], h.meta["driver_unit"], h.meta["speed_hz"]) == ("general", "N·m", 1.0)
    assert 0 < h.meta["rcond_min"] <= 1 and h.meta["singular"] is None and h.singular_mask is None
    assert {n: (j.name, j.kind) for n, j in h.joints.items()} == {
        "O2": ("O2", "revolute"), "A": ("A", "revolute"), "B": ("B", "revolute"), "slide": ("slide", "prismatic")}
    for i, t in enumerate(deg):
        forces, torque, _ = slider_crank_newton_euler(300.0, 840.0, t)
        for name, F in forces.items():
            assert np.allclose(h.joints[name].force_N[i], [F.real, F.imag], atol=1e-9), (name, t)
        assert h.torque_Nm[i] == pytest.approx(torque, abs=1e-9)
    assert np.allclose(h.joints["slide"].moment_Nm, 0.0, atol=1e-9)
    assert all(j.moment_Nm is None for n, j in h.joints.items() if n != "slide")


def test_the_rigid_body_history_moves_as_the_closed_form_four_bar():
    h = simulate(four_bar(*FINAL_CM), samples=12, speed_hz=-0.9)
    for i, t in enumerate(h.crank_deg):
        k = fourbar_motion(*FINAL_CM, t, -0.9)
        for b, name in enumerate(("crank", "coupler", "rocker")):
            body = h.bodies[name]
            assert np.exp(1j * body.angle_rad[i]) == pytest.approx(k["e"][b], abs=1e-12)
            assert (body.omega_rad_s[i], body.alpha_rad_s2[i]) == pytest.approx((k["w"][b], k["al"][b]), abs=1e-9)


def law_of_cosines_mu(b2, b3, b4, d, deg):
    """Transmission angle (deg) of a four-bar at crank angles ``deg`` (geometry/RIG.md §2's triangle)."""
    diag = np.abs(d - b2 * np.exp(1j * np.radians(deg)))
    return np.degrees(np.arccos((b3**2 + b4**2 - diag**2) / (2 * b3 * b4)))


def test_the_reactions_summary_states_independent_figures():
    h = simulate(four_bar(*FINAL_CM), samples=36)
    s = summary(h)
    assert (s["linkage"], s["model"], s["speed_hz"], s["samples"], s["textbook"]) == ("four-bar", "rigid-body", 1.0, 36, False)
    assert s["lengths_mm"] == dict(zip(("b2", "b3", "b4", "d"), FINAL_CM)) and s["singular"] is None
    for j in ("O2", "A", "B", "O4"):
        force, deg = newton_euler_peak(fourbar_newton_euler, FINAL_CM, j)
        p = s["peaks"][j]
        F = fourbar_newton_euler(*FINAL_CM, p["crank_deg"])[0][j]  # the force at the angle it reports
        assert (p["force_N"], p["crank_deg"]) == pytest.approx((force, deg), rel=1e-9, abs=1e-4), j
        assert (p["fx_N"], p["fy_N"], p["singular"]) == pytest.approx((F.real, F.imag, False), abs=1e-9), j
    grid = np.arange(0.0, 360.0, 0.25)
    torques = [fourbar_newton_euler(*FINAL_CM, t)[1] for t in grid]
    assert s["torque_Nm"]["peak"] == pytest.approx(max(map(abs, torques)), rel=1e-4)
    assert s["torque_Nm"]["singular"] is False
    mu = law_of_cosines_mu(*FINAL_CM, np.array([0.0, 180.0]))
    assert s["transmission_angle_deg"] == pytest.approx({"min": mu[0], "max": mu[1]}, rel=1e-9)
    b2, b3, b4, d = FINAL_CM
    rules = {r["name"].split(" (")[0]: (r["value"], r["limit"], r["ok"], r["relation"], r["unit"]) for r in s["rules"]}
    assert rules == {  # geometry/RIG.md §2
        "loop can close": (d, b2 + b3 + b4, True, "<", "mm"),
        "crank turns fully": (b2 + d, b3 + b4, True, "<", "mm"),
        "crank guide clears the rocker pivot": (d, 660.0, True, ">=", "mm"),
        "transmission angle min": (pytest.approx(mu[0]), 35.0, True, ">", "deg"),
        "transmission angle max": (pytest.approx(mu[1]), 145.0, True, "<", "deg"),
        "on the hole grid": (0.0, 0.0, True, "==", "mm")}


def test_a_history_known_by_its_samples_finds_the_newton_euler_peaks():
    """Without the solver to refine on (an imported CSV), a periodic cubic spline through 72
    samples (every 5°) finds each peak to 1e-3 and its angle to 0.2°."""
    h = dataclasses.replace(simulate(four_bar(*FINAL_CM), samples=72), evaluator=None)
    pk = peaks(h)
    for j in ("O2", "A", "B", "O4"):
        force, deg = newton_euler_peak(fourbar_newton_euler, FINAL_CM, j)
        assert pk[j]["force_N"] == pytest.approx(force, rel=1e-3), j
        assert abs((pk[j]["crank_deg"] - deg + 180) % 360 - 180) < 0.2, j
        assert abs(pk[j]["force_N"] - force) < abs(np.abs(h.joints[j].force_N[:, 0] + 1j * h.joints[j].force_N[:, 1]).max()
                                                   - force) + 1e-9  # refined beats the best sample
    s = h.crank_deg.copy()
    shifted = dataclasses.replace(h, crank_deg=(s + 2.5) % 360.0)  # samples off the grid, wrapping round 360°
    assert peaks(shifted)["A"]["force_N"] == pytest.approx(pk["A"]["force_N"], rel=1e-12)


@pytest.mark.parametrize("offset", [0.0, -20.0])
def test_the_gas_force_is_balanced_by_the_torque_of_virtual_work(offset):
    """Massless compressor (geometry/MECHANISMS.md §5's force law, crank 150, rod 350 mm): T·ω + F·v_B = 0,
    so T = −F_x dx_B/dθ with x_B(θ) = b2 cos θ + √(b3² − (b2 sin θ − e)²) and
    F_x = −2000 N · ((L − c − b3 + b2)/(L − c − x_B) − 1), L = 1000, c = 100 mm."""
    b2, b3 = 150.0, 350.0
    lk = slider_crank(b2, b3, offset, masses=None, slider_force=compressor_gas_force(b2, b3))
    h = simulate(lk, samples=36, speed_hz=20.0)
    th = np.radians(h.crank_deg)
    root = np.sqrt(b3**2 - (b2 * np.sin(th) - offset) ** 2)
    x = b2 * np.cos(th) + root
    dx = -b2 * np.sin(th) - (b2 * np.sin(th) - offset) * b2 * np.cos(th) / root  # mm per rad
    fx = -2000.0 * ((1000.0 - 100.0 - b3 + b2) / (1000.0 - 100.0 - x) - 1.0)
    assert np.allclose(h.joints["B"].position_mm[:, 0], x, atol=1e-9)
    assert np.allclose(h.torque_Nm, -fx * dx / 1000.0, rtol=1e-9, atol=1e-9 * np.abs(fx * dx).max() / 1000)


@pytest.mark.parametrize("model", ["original", "rigid-body"])
def test_a_toggle_is_reported_where_the_transmission_angle_falls_below_five_degrees(model):
    """300/600/400/502 mm: μ = 3.3° with the crank on the ground line; sin μ < sin 5° from −4.72°
    to +4.72° (law of cosines).  The 2013 model scans a 0.1° grid: its ranges are the law's to 0.1°;
    every model refuses numbers for the peaks."""
    lengths = (300.0, 600.0, 400.0, 502.0)
    h = simulate(four_bar(*lengths), samples=72, model=model)
    grid = np.arange(0.0, 360.0, 0.01)
    bad = np.sin(np.radians(law_of_cosines_mu(*lengths, grid))) < np.sin(np.radians(5.0))
    edge = grid[bad & (grid < 180)].max()
    pk = peaks(h)
    assert all(pk[j]["force_N"] is None and pk[j]["singular"] for j in ("O2", "A", "B", "O4"))
    assert h.meta["singular"] and h.meta["singular"][0][0] == 0.0
    if model == "original":
        assert h.meta["singular"] == [[0.0, pytest.approx(edge, abs=0.1)], [pytest.approx(360 - edge, abs=0.1),
                                                                        pytest.approx(359.9)]]
