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
* The reactions stage as a check calls it (``cycle.react``, ``imported.react`` on a CSV written
  from tests/newton_euler.py), the 2013 program away from its defaults, the general solver's toggles
  between samples, a load off a coupler's axis (virtual work), a scene's own gas law, the summary
  of a slider-crank and of a toggle, imported splines over a full and a part turn.
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



def _origins_are_the_closed_form(hist, i: int, k: dict, t) -> None:
    """Each body's frame origin and its acceleration at sample ``i`` are the closed-form four-bar's
    (``k``: positions and accelerations in m, complex; the history in mm)."""
    origin = {"crank": 0j, "coupler": k["A"], "rocker": k["O4"]}
    acc = {"crank": 0j, "coupler": k["aA"], "rocker": 0j}
    for name in origin:
        body = hist.bodies[name]
        assert np.allclose(body.origin_mm[i], [origin[name].real * 1000, origin[name].imag * 1000], atol=1e-6)
        assert np.allclose(body.origin_acc_mm_s2[i], [acc[name].real * 1000, acc[name].imag * 1000],
                           atol=1e-6 * (1 + abs(acc[name]) * 1000)), (name, t)

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
            _origins_are_the_closed_form(hist, i, k, t)
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


# ---- the reactions stage as a check calls it (issue 39 §2: the dynamics package's surviving mutants) ----

def _newton_euler_csv(path, lengths, deg, reverse=("O4",)):
    """A reaction CSV written from tests/newton_euler.py's four-bar (not rigfem's writer): the pins'
    forces at ``deg`` and the torque; the joints in ``reverse`` given as the opposite pair's force."""
    pairs = {"O2": ("ground", "crank"), "A": ("crank", "coupler"), "B": ("coupler", "rocker"), "O4": ("ground", "rocker")}
    lines = [f"# joint {n}: force by {b if n in reverse else a} on {a if n in reverse else b}" for n, (a, b) in pairs.items()]
    lines.append("crank_deg," + ",".join(f"{n}_fx_N,{n}_fy_N" for n in pairs) + ",torque_Nm")
    for t in deg:
        F, T, _ = fourbar_newton_euler(*lengths, t)
        cells = [(-F[n] if n in reverse else F[n]) for n in pairs]
        lines.append(",".join(repr(float(v)) for v in (t, *(x for c in cells for x in (c.real, c.imag)), T)))
    path.write_text("\n".join(lines) + "\n")


def test_imported_reactions_are_the_newton_euler_ones_where_the_linkage_moves(tmp_path):
    """A check with ``reactions_csv`` (rigfem.dynamics.imported.react): a CSV of the Newton–Euler pin
    forces every 5° on the rig four-bar, O4's written as the rocker's force on the ground.  The history
    holds every force as the linkage's pair says (O4 turned round), at the closed-form joint positions, the
    CSV's torque; the evaluator answers at angles asked in any order with the motion there; the peaks
    refined on the spline are the Newton–Euler peaks, each with the force vector at its angle."""
    from rigfem.dynamics.history import DynamicsOptions
    from rigfem.dynamics.imported import react
    from rigfem.io.reactions_csv import read_csv
    from rigfem.linkage.state import linkage_state

    deg = np.arange(0.0, 360.0, 5.0)
    _newton_euler_csv(tmp_path / "ne.csv", FINAL_CM, deg)
    lk = four_bar(*FINAL_CM)
    options = DynamicsOptions(reactions_csv=tmp_path / "ne.csv")
    r = react(lk, linkage_state(lk, np.arange(0.0, 360.0, 1.0), 1.0), read_csv(tmp_path / "ne.csv"), options)
    h = r.history
    assert np.array_equal(h.crank_deg, deg) and h.full_turn
    assert h.meta["model"] == "imported from ne.csv" and h.meta["singular"] is None and h.meta["assumed"] == []
    assert {n: (j.body_a, j.body_b) for n, j in h.joints.items()} == {
        "O2": ("ground", "crank"), "A": ("crank", "coupler"), "B": ("coupler", "rocker"), "O4": ("ground", "rocker")}
    for i, t in enumerate(deg):
        F, T, pos = fourbar_newton_euler(*FINAL_CM, t)
        for n in F:
            assert np.allclose(h.joints[n].force_N[i], [F[n].real, F[n].imag], rtol=0, atol=1e-9), (n, t)
            assert np.allclose(h.joints[n].position_mm[i], [pos[n].real, pos[n].imag], atol=1e-6), (n, t)
        assert h.torque_Nm[i] == pytest.approx(T, abs=1e-9)
    asked = np.array([250.05, 3.3, 101.7])  # not increasing: answered in the order asked
    between = h.evaluator(asked)
    assert np.array_equal(between.crank_deg, asked)
    for i, t in enumerate(asked):
        F, T, pos = fourbar_newton_euler(*FINAL_CM, t)
        k = fourbar_motion(*FINAL_CM, t)
        for n in F:
            assert np.allclose(between.joints[n].position_mm[i], [pos[n].real, pos[n].imag], atol=1e-6), (n, t)
            assert np.allclose(between.joints[n].force_N[i], [F[n].real, F[n].imag], rtol=2e-3, atol=1.0), (n, t)
        assert between.torque_Nm[i] == pytest.approx(T, rel=2e-3, abs=0.2)
        for b, name in enumerate(("crank", "coupler", "rocker")):
            body = between.bodies[name]
            assert np.exp(1j * body.angle_rad[i]) == pytest.approx(k["e"][b], abs=1e-12), (name, t)
            assert (body.omega_rad_s[i], body.alpha_rad_s2[i]) == pytest.approx((k["w"][b], k["al"][b]), abs=1e-9)
        _origins_are_the_closed_form(between, i, k, t)
    for j in ("O2", "A", "B", "O4"):
        force, at = newton_euler_peak(fourbar_newton_euler, FINAL_CM, j)
        p = r.peaks[j]
        assert p["force_N"] == pytest.approx(force, rel=1e-3) and abs((p["crank_deg"] - at + 180) % 360 - 180) < 0.3, j
        F = fourbar_newton_euler(*FINAL_CM, p["crank_deg"])[0][j]
        assert (p["fx_N"], p["fy_N"]) == pytest.approx((F.real, F.imag), rel=2e-3, abs=1.0), j
    assert r.summary["peaks"] == {n: v for n, v in r.peaks.items() if n != "torque"}


@pytest.mark.parametrize("model", ["rigid-body", "original"])
def test_the_reactions_stage_of_a_check_is_newton_euler_at_the_scenes_speed_and_samples(model):
    """rigfem.dynamics.cycle.react, the stage a check runs: the history at the options' samples (40) and
    crank speed (1.3 Hz) of the mass model asked (the Newton–Euler rig model, or the 2013 study's program),
    its peaks and its summary stating them."""
    from rigfem.dynamics.cycle import react
    from rigfem.dynamics.history import DynamicsOptions
    from rigfem.linkage.state import linkage_state

    lk = four_bar(*FINAL_CM)
    truth = fourbar_newton_euler if model == "rigid-body" else (lambda *a: study_program(*a[:6]))
    r = react(lk, linkage_state(lk, np.arange(0.0, 360.0, 9.0), 1.3), DynamicsOptions(40, model, 1.3))
    h = r.history
    assert np.array_equal(h.crank_deg, np.arange(40) * 9.0) and h.meta["model"] == model and h.meta["speed_hz"] == 1.3
    for i, t in enumerate(h.crank_deg):
        F, T, _ = truth(*FINAL_CM, t, 1.3)
        for n, f in F.items():
            assert np.allclose(h.joints[n].force_N[i], [f.real, f.imag], rtol=0, atol=1e-9), (n, t)
        assert h.torque_Nm[i] == pytest.approx(T, abs=1e-9)
    for j in ("O2", "A", "B", "O4"):
        force, at = newton_euler_peak(truth, FINAL_CM, j, speed_hz=1.3)
        assert (r.peaks[j]["force_N"], r.peaks[j]["crank_deg"]) == pytest.approx((force, at), rel=1e-9, abs=1e-4), j
    grid = np.arange(0.0, 360.0, 0.25)
    assert r.peaks["torque"]["peak"] == pytest.approx(max(abs(truth(*FINAL_CM, t, 1.3)[1]) for t in grid), rel=1e-4)
    assert r.summary["peaks"] == {n: v for n, v in r.peaks.items() if n != "torque"}
    assert r.summary["samples"] == 40 and r.summary["speed_hz"] == 1.3 and r.singular is None


def test_the_2013_program_at_another_speed_and_rails_is_the_study_program():
    """original_reactions / original_program / program_reactions away from the study's defaults
    (1.7 Hz, rails of 650/950/1100 mm): the 2013 program written from geometry/RIG.md §3; the
    kinematics they return are the closed-form four-bar's (constant crank speed: α2 = 0) and the
    transmission angle the law of cosines'."""
    from rigfem.dynamics.original import program_reactions

    rails = (650.0, 950.0, 1100.0)
    deg = np.array([0.0, 77.0, 190.0, 301.0])
    r = original_reactions(*FINAL_CM, np.radians(deg), speed_hz=1.7, rails_mm=rails)
    k = r["kin"]
    for i, t in enumerate(deg):
        forces, torque, pos = study_program(*FINAL_CM, t, 1.7, rails_mm=rails)
        scale = max(abs(F) for F in forces.values())
        for key, name in (("R12", "O2"), ("R23", "A"), ("R34", "B"), ("R14", "O4")):
            assert np.allclose(r[key][i], [forces[name].real, forces[name].imag], rtol=0, atol=1e-9 * scale), (key, t)
        assert r["M2"][i] == pytest.approx(torque, abs=1e-9 * scale)
        m = fourbar_motion(*FINAL_CM, t, 1.7)
        for b, name in enumerate(("2", "3", "4")):
            assert np.exp(1j * k["theta" + name][i]) == pytest.approx(m["e"][b], abs=1e-12), (name, t)
            assert (k["omega" + name][i], k["alpha" + name][i]) == pytest.approx((m["w"][b], m["al"][b]), abs=1e-9)
        for name in ("A", "B"):
            assert k[name].shape == (deg.size, 2)
            assert k[name][i] == pytest.approx([pos[name].real / 1000, pos[name].imag / 1000], abs=1e-12), (name, t)
    assert np.array_equal(k["alpha2"], np.zeros(deg.size))
    assert np.allclose(r["mu_deg"], law_of_cosines_mu(*FINAL_CM, deg), atol=1e-9)
    again = program_reactions(fourbar_kinematics(*(x / 1000 for x in FINAL_CM), np.radians(deg), 2 * np.pi),
                              *FINAL_CM[:3])  # its own defaults: 1 Hz, the rig's masses and rails
    for i, t in enumerate(deg):
        forces, torque, _ = study_program(*FINAL_CM, t)
        assert np.allclose(again["R23"][i], [forces["A"].real, forces["A"].imag], atol=1e-9)
        assert again["M2"][i] == pytest.approx(torque, abs=1e-9)
    got = original_program(*STUDY, speed_hz=1.7, instants=720)
    rows = [study_program(*STUDY, t, 1.7) for t in np.linspace(0.0, 360.0, 720)]
    for j in ("O2", "A", "B", "O4"):
        assert got[j] == pytest.approx(max(abs(row[0][j]) for row in rows), rel=1e-12), j
    assert got["torque_Nm"] == pytest.approx(max(abs(row[1]) for row in rows), rel=1e-12)


def test_the_original_model_on_other_rails_is_the_study_program():
    """simulate(model="original") of a four-bar built on rails of 650/950/1100 mm: the 2013 program on
    those rails, at every sample; its driver is the motor's torque (N·m)."""
    rails = (650.0, 950.0, 1100.0)
    h = simulate(four_bar(*FINAL_CM, rails_mm=rails), samples=12, model="original")
    for i, t in enumerate(h.crank_deg):
        forces, torque, _ = study_program(*FINAL_CM, t, rails_mm=rails)
        for name, F in forces.items():
            assert np.allclose(h.joints[name].force_N[i], [F.real, F.imag], atol=1e-9), (name, t)
        assert h.torque_Nm[i] == pytest.approx(torque, abs=1e-9)
    s = summary(h)
    assert h.meta["driver_unit"] == "N·m" and s["torque_Nm"]["peak"] == pytest.approx(
        max(abs(study_program(*FINAL_CM, t, rails_mm=rails)[1]) for t in np.arange(0.0, 360.0, 0.25)), rel=1e-4)


def test_the_slider_cranks_summary_and_joints_say_what_the_linkage_is():
    """The rig slider-crank in closed form: three pins and the slide (a prismatic joint, named as the
    linkage names them), the Newton–Euler forces; no transmission angle (it is a four-bar's); the
    torque's peak at the angle Newton–Euler puts it; the summary passes the history's warnings on
    and names a slider's driver force as such."""
    h = simulate(slider_crank(300.0, 840.0, 0.0), samples=36)
    assert h.meta["solver"] == "closed form" and h.meta["driver_unit"] == "N·m"
    assert {n: (j.name, j.kind) for n, j in h.joints.items()} == {
        "O2": ("O2", "revolute"), "A": ("A", "revolute"), "B": ("B", "revolute"), "slide": ("slide", "prismatic")}
    for i, t in enumerate(h.crank_deg):
        forces, torque, _ = slider_crank_newton_euler(300.0, 840.0, t)
        for name, F in forces.items():
            assert np.allclose(h.joints[name].force_N[i], [F.real, F.imag], atol=1e-9), (name, t)
        assert h.torque_Nm[i] == pytest.approx(torque, abs=1e-9)
    h.meta["warnings"] = ["a warning of the solver"]
    s = summary(h)
    assert s["transmission_angle_deg"] is None and s["warnings"] == ["a warning of the solver"]
    grid = np.arange(0.0, 360.0, 0.25)
    torques = np.array([abs(slider_crank_newton_euler(300.0, 840.0, t)[1]) for t in grid])
    assert s["torque_Nm"]["peak"] == pytest.approx(torques.max(), rel=1e-4)
    top = grid[np.argmax(torques)]  # no offset: |T| is mirrored about the slide line, peaking at ±top
    assert min(abs((s["torque_Nm"]["crank_deg"] - x + 180) % 360 - 180) for x in (top, -top)) < 0.3
    h.meta.update(driver_unit="N", textbook=True)  # as a history driven by a slider, from a textbook scene
    s = summary(h)
    assert "torque_Nm" not in s and s["driver_force_N"]["peak"] == pytest.approx(torques.max(), rel=1e-4)
    assert s["textbook"] is True


def test_a_toggles_summary_states_the_law_of_cosines_ranges():
    """300/600/400/502 mm in closed form (rigid-body): the summary's singular ranges are the history's,
    which hold every crank angle where sin μ < sin 5° by the law of cosines; the mask flags exactly the
    samples the ranges hold."""
    lengths = (300.0, 600.0, 400.0, 502.0)
    h = simulate(four_bar(*lengths), samples=360)
    s = summary(h)
    assert s["singular"] == h.meta["singular"] and s["singular"]
    bad = np.sin(np.radians(law_of_cosines_mu(*lengths, h.crank_deg))) < np.sin(np.radians(5.0))
    inside = np.zeros(h.crank_deg.size, bool)
    for a, b in s["singular"]:
        inside |= (h.crank_deg >= a) & (h.crank_deg <= b)
    assert np.array_equal(inside, bad) and np.array_equal(h.singular_mask, bad)
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values()) and np.isfinite(h.torque_Nm).all()


def test_a_spline_through_a_smooth_turn_keeps_its_slope_round_the_turn_and_a_part_turn_finds_its_peaks():
    """Imported histories: through a full turn the spline is periodic (the Newton–Euler force is smooth
    round 360°: its slope at 0° from either side agrees); through half a turn (0–180° every 5°: a partial
    turn) the peaks refined on a not-a-knot spline are the Newton–Euler peaks inside it."""
    from rigfem.dynamics.history import spline_evaluator

    h = dataclasses.replace(simulate(four_bar(*FINAL_CM), samples=72), evaluator=None)
    ev = spline_evaluator(h)
    e = 1e-3
    f = ev(np.array([360.0 - 2 * e, 360.0 - e, 0.0, e])).joints["A"].force_N[:, 0]
    left, right = (f[1] - f[0]) / e, (f[3] - f[2]) / e
    truth = (fourbar_newton_euler(*FINAL_CM, e)[0]["A"].real - fourbar_newton_euler(*FINAL_CM, -e)[0]["A"].real) / (2 * e)
    assert left == pytest.approx(right, rel=1e-3, abs=1e-3) and right == pytest.approx(truth, rel=2e-2, abs=0.05)
    part = simulate(four_bar(*FINAL_CM), samples=72)
    keep = part.crank_deg <= 180.0
    half = dataclasses.replace(part, crank_deg=part.crank_deg[keep], evaluator=None, full_turn=False,
                               torque_Nm=part.torque_Nm[keep],
                               joints={n: dataclasses.replace(j, force_N=j.force_N[keep]) for n, j in part.joints.items()})
    pk = peaks(half)
    for j in ("O2", "A", "B", "O4"):
        grid = np.arange(0.0, 180.01, 0.25)
        vals = np.array([abs(fourbar_newton_euler(*FINAL_CM, t)[0][j]) for t in grid])
        i = int(np.argmax(vals))
        if 0 < i < grid.size - 1:  # a maximum inside the half turn
            assert pk[j]["force_N"] == pytest.approx(vals.max(), rel=2e-3), j
            assert abs(pk[j]["crank_deg"] - grid[i]) < 0.5, j
        else:  # at an end of the half turn: that sample
            assert pk[j]["force_N"] == pytest.approx(vals[i], rel=1e-9), j


def test_the_general_solver_reports_a_toggle_between_its_samples_where_the_law_of_cosines_puts_it():
    """300/600/400/699.5 mm: μ passes 176.3° with the crank at 180°, sin μ < sin 5° over about
    ±3.5° there (law of cosines).  Through the general solver at 8 samples (every 45° from 22.5°) no
    sample is in that range but the continuation points between them are: the toggle is reported
    inside the law's range; at every 0.5° the ranges and the flagged samples are the law's."""
    lengths = (300.0, 600.0, 400.0, 699.5)
    grid = np.arange(0.0, 360.0, 0.5)
    law = np.sin(np.radians(law_of_cosines_mu(*lengths, grid))) < np.sin(np.radians(5.0))
    lo, hi = grid[law].min(), grid[law].max()
    assert 170 < lo < 180 < hi < 190
    coarse = solve(four_bar(*lengths), np.arange(22.5, 360.0, 45.0), general=True)
    assert coarse.singular_mask is None and coarse.meta["singular"]
    assert all(lo - 0.5 <= a <= b <= hi + 0.5 for a, b in coarse.meta["singular"])
    fine = solve(four_bar(*lengths), grid, general=True)
    assert fine.meta["solver"] == "general" and np.array_equal(fine.singular_mask, law)
    assert fine.meta["singular"] == [[lo, hi]]
    assert peaks(fine)["A"]["singular"] and peaks(coarse)["A"]["singular"]


def test_a_load_on_the_coupler_is_balanced_by_the_torque_of_virtual_work():
    """A massless rig four-bar with a force F(θ) = (100 cos θ, 50) N at the coupler point 300 mm along
    and 100 mm off the coupler's axis from A: T·ω2 + F·v_P = 0, v_P = v_A + ω3 × r_AP (tests/newton_euler.py's
    closed-form motion).  The load is handed the crank angle, its point (mm) and the coordinates (x, y
    in m, φ) and their rates of each body."""
    from rigfem.linkage.model import Load

    seen = []

    def force(state):
        seen.append(state)
        return np.stack([100.0 * np.cos(state["theta_rad"]), np.full(len(state["theta_rad"]), 50.0)], -1)

    lk = four_bar(*FINAL_CM, masses=None)
    lk.loads.append(Load("coupler", (300.0, 100.0), force))
    h = simulate(lk, samples=12)
    st = seen[0]
    for i, t in enumerate(h.crank_deg):
        k = fourbar_motion(*FINAL_CM, t)
        w2, w3 = k["w"][0], k["w"][1]
        r = (0.3 + 0.1j) * k["e"][1]
        P, vP = k["A"] + r, 1j * w2 * k["A"] + 1j * w3 * r
        F = complex(100.0 * np.cos(np.radians(t)), 50.0)
        assert h.torque_Nm[i] == pytest.approx(-(F.real * vP.real + F.imag * vP.imag) / w2, abs=1e-9), t
        assert st["theta_rad"][i] == pytest.approx(np.radians(t), abs=1e-12)
        assert st["point_mm"][i] == pytest.approx([P.real * 1000, P.imag * 1000], abs=1e-6)
        x, y, phi = st["q"][i, 3:6]
        assert (x, y, np.exp(1j * phi)) == pytest.approx((k["A"].real, k["A"].imag, k["e"][1]), abs=1e-9)
        vA = 1j * w2 * k["A"]
        assert st["qd"][i, 3:6] == pytest.approx([vA.real, vA.imag, w3], abs=1e-9)


def test_a_scenes_own_gas_law_reaches_the_slider(tmp_path):
    """A compressor scene stating its own gas law (p = 3000 N, L = 1100 mm, c = 50 mm): the slider's load is
    F_x = −p ((L − c − b3 + b2)/(L − c − x) − 1) at piston distance x (geometry/MECHANISMS.md §5), not the
    default law's."""
    from importlib.resources import files

    from rigfem.dynamics.forces import loaded_linkage
    from rigfem.scene import load_scene

    text = files("rigfem").joinpath("scenes/mech5-compressor.toml").read_text()
    text = text.replace("p_N = 2000.0", "p_N = 3000.0").replace("L_mm = 1000.0", "L_mm = 1100.0").replace(
        "c_mm = 100.0", "c_mm = 50.0")
    (tmp_path / "gas.toml").write_text(text)
    lk = loaded_linkage(load_scene(tmp_path / "gas.toml"))
    x = np.array([200.0, 350.0, 480.0])
    f = lk.loads[0].force({"point_mm": np.stack([x, np.zeros(3)], -1)})
    assert lk.loads[0].body == "slider"
    assert np.allclose(f, np.stack([-3000.0 * ((1100 - 50 - 350 + 150) / (1100 - 50 - x) - 1), np.zeros(3)], -1), rtol=1e-12)


def test_the_2013_models_toggle_ranges_hold_every_flagged_sample():
    """The original model of 300/600/400/502 mm sampled every 1° from 0.05° (off its 0.1° scan grid):
    the flagged samples are exactly those with sin μ < sin 5° (law of cosines) and every one lies in a
    reported range; a toggle-free four-bar flags none (no mask)."""
    from rigfem.dynamics.cycle import cycle_history
    from rigfem.linkage.state import linkage_state

    lengths = (300.0, 600.0, 400.0, 502.0)
    lk = four_bar(*lengths)
    deg = np.arange(360) + 0.05
    h = cycle_history(lk, linkage_state(lk, deg, 1.0), deg, 1.0, "original")
    law = np.sin(np.radians(law_of_cosines_mu(*lengths, deg))) < np.sin(np.radians(5.0))
    assert np.array_equal(h.singular_mask, law) and "singular_fn" not in h.meta
    inside = np.zeros(deg.size, bool)
    for a, b in h.meta["singular"]:
        inside |= (deg >= a) & (deg <= b)
    assert np.array_equal(inside & law, law)
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values())
    free = simulate(four_bar(*FINAL_CM), samples=36, model="original")
    assert free.singular_mask is None and free.meta["singular"] is None


def test_a_change_point_four_bar_in_closed_form_flags_the_law_of_cosines_samples_and_keeps_numbers_finite():
    """300/600/400/500 mm (s + l = p + q: the bars fold flat with the crank at 0°, where the closed
    form's moment balance divides by zero).  Sampled every 1° in closed form: the flagged samples are
    exactly those with sin μ < sin 5° (law of cosines); every force and the torque stay finite (the
    change point's unbounded values are given as 0); away from the toggle the forces are Newton–Euler's.
    A toggle-free four-bar flags none (no mask) and neither history carries the builder's toggle test."""
    lengths = (300.0, 600.0, 400.0, 500.0)
    h = solve(four_bar(*lengths), np.arange(0.0, 360.0, 1.0), speed_hz=1.7)
    assert h.meta["solver"] == "closed form" and h.meta["speed_hz"] == 1.7 and "singular_fn" not in h.meta
    law = np.sin(np.radians(law_of_cosines_mu(*lengths, h.crank_deg))) < np.sin(np.radians(5.0))
    assert law[0] and np.array_equal(h.singular_mask, law)
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values()) and np.isfinite(h.torque_Nm).all()
    assert all(np.array_equal(j.force_N[0], [0.0, 0.0]) for j in h.joints.values()) and h.torque_Nm[0] == 0.0
    for t in (90.0, 180.0, 270.0):
        F, T, _ = fourbar_newton_euler(*lengths, t, 1.7)
        i = int(t)
        for n, f in F.items():
            assert np.allclose(h.joints[n].force_N[i], [f.real, f.imag], atol=1e-9), (n, t)
        assert h.torque_Nm[i] == pytest.approx(T, abs=1e-9)
    free = solve(four_bar(*FINAL_CM), np.arange(0.0, 360.0, 30.0), speed_hz=1.7)
    assert free.singular_mask is None and free.meta["singular"] is None and "singular_fn" not in free.meta
    between = free.evaluator(np.array([15.0]))  # re-solved at the history's own speed
    F, T, _ = fourbar_newton_euler(*FINAL_CM, 15.0, 1.7)
    assert between.torque_Nm[0] == pytest.approx(T, abs=1e-9) and between.meta["speed_hz"] == 1.7


@pytest.mark.parametrize("general", [False, True])
def test_a_slider_with_its_mass_off_the_slide_takes_the_moment_of_its_inertia_force(general):
    """A massless slider-crank (300/840 mm, no offset) whose 2 kg slider has its centre of mass 50 mm
    above the slide line: the slide holds the slider against the moment of its d'Alembert force about
    the sliding point, M = r_c × m a_B = −m · 0.05 m · a_B,x (a_B from tests/newton_euler.py's closed
    form), in closed form and through the general solver."""
    lk = slider_crank(300.0, 840.0, 0.0, masses=None, body_masses={"slider": {"mass_kg": 2.0, "com_local_mm": (0.0, 50.0)}})
    h = solve(lk, np.arange(0.0, 360.0, 30.0), general=general)
    assert h.meta["solver"] == ("general" if general else "closed form")
    for i, t in enumerate(h.crank_deg):
        th, w2 = np.radians(t), 2 * np.pi
        e2 = np.exp(1j * th)
        e3 = np.exp(1j * np.arcsin(-0.3 * e2.imag / 0.84))
        w3 = -(0.3 * w2 * e2.real) / (0.84 * e3.real)
        aA = -0.3 * w2**2 * e2
        a3 = -(aA.imag - w3**2 * 0.84 * e3.imag) / (0.84 * e3.real)
        aB = aA + 0.84 * (1j * a3 - w3**2) * e3
        assert abs(aB.imag) < 1e-9
        assert h.joints["slide"].moment_Nm[i] == pytest.approx(-2.0 * 0.05 * aB.real, abs=1e-9), t
