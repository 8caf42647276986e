"""Every load case of a check, entry by entry, against the study's load case (geometry/RIG.md §4)
and the Newton–Euler solution of tests/newton_euler.py (issue 39: the loads package's mutants).

Cycle mode: each rail is a free body loaded through the screws of its two couplings by the pin
force less the inertia of the point masses its coupling carries (geometry/RIG.md §3: plate + carriage at A
on the crank and at B on the coupler, a coupling at A on the coupler and at B on the rocker), the
motor torque as a couple on the crank's pivot screws (±T/120 mm across the rail), and its own
inertia (the pivot's acceleration, α and ω² of the bar, about the pivot at x = 80 mm); the plate
carries its pin force, the post its pin force through its two top screws.  The bearing weights
of each hole must rebuild those forces at every crank angle.
"""

import dataclasses

import numpy as np
import pytest
from newton_euler import CARRIAGE, COUPLING, PLATE, RAILS_MM, fourbar_motion, fourbar_newton_euler, newton_euler_peak

from rigfem.dynamics import peaks, simulate
from rigfem.errors import ComputeError, InputError
from rigfem.linkage import four_bar, slider_crank
from rigfem.loads import part_cases
from rigfem.settings import check_settings

FINAL_CM = (480.0, 840.0, 780.0, 1020.0)
N_DIR = 8
PITCH, FIRST, PIVOT_X, SPACING = 60.0, 20.0, 80.0, 120.0  # rail holes, the pivot joint's x, a coupling's screws
RAIL = "rail_size25"
NOTES = {  # the committed report's statements of the load cases (results/final-cm/report.json)
    "crank_rail": "1.4 × peak A reaction 420.1 N at crank 16.67°, split over hole_09 and hole_11 at the far end "
                  "(study's worst case); held by the screws of the pivot coupling",
    "plate_A": "1.4 × peak A pin reaction 420.1 N at crank 16.67° on the bearing seat; held by its two screws",
    "post_B": "250 N longitudinal + 250 N transverse at each screw hole (study); base resting on the rail "
              "(normal displacement only), bottom screws bolted",
}


def hole(x_mm: float) -> str:
    return f"hole_{int(round((x_mm - FIRST) / PITCH)):02d}"


@pytest.fixture  # per test (not per module): mutation testing credits a load case to every test that builds it
def cases():
    h = simulate(four_bar(*FINAL_CM), samples=36)
    s = check_settings({"bearing_directions": N_DIR}, "four-bar", list(RAILS_MM))
    return h, {(m, c.name): c for m, c in part_cases(h, peaks(h), s)}


def hole_forces(case) -> dict[str, np.ndarray]:
    """Each bearing hole's force (n_rows, 2) rebuilt from its unit loads and weights."""
    out = {}
    for j, ld in enumerate(case.loads):
        if ld.kind == "bearing":
            out[ld.group] = out.get(ld.group, 0) + np.outer(case.coef[:, j], ld.direction[:2])
    return out


def expected_rail_screws(name: str, t: float) -> dict[str, complex]:
    """Newton–Euler screw forces (N, in the rail's frame) of a cycle-mode rail at crank angle t."""
    F, T, _ = fourbar_newton_euler(*FINAL_CM, t)
    k = fourbar_motion(*FINAL_CM, t)
    (e2, e3, e4), b2, b3, b4 = k["e"], *FINAL_CM[:3]
    aA, aB = k["aA"], k["lengths"][2] * (1j * k["al"][2] - k["w"][2] ** 2) * e4
    joints = {  # rail -> [(joint x along the rail, coupling force N (global), torque N·mm)], rail direction
        "crank_rail": ([(PIVOT_X, F["O2"], T * 1000), (PIVOT_X + b2, -F["A"] - (PLATE + CARRIAGE) * aA, 0.0)], e2),
        "coupler_rail": ([(PIVOT_X, F["A"] - COUPLING * aA, 0.0), (PIVOT_X + b3, -F["B"] - (PLATE + CARRIAGE) * aB, 0.0)], e3),
        "rocker_rail": ([(PIVOT_X, F["O4"], 0.0), (PIVOT_X + b4, F["B"] - COUPLING * aB, 0.0)], e4),
    }[name]
    out = {}
    for x, f, torque in joints[0]:
        local = f * np.conj(joints[1])
        out[hole(x - SPACING / 2)] = local / 2 - 1j * torque / SPACING
        out[hole(x + SPACING / 2)] = local / 2 + 1j * torque / SPACING
    return out


@pytest.mark.parametrize("name, mass", [("crank_rail", 0.7 * 3.1), ("coupler_rail", 3.1), ("rocker_rail", 3.1)])
def test_cycle_rail_case_is_its_newton_euler_free_body(cases, name, mass):
    h, cs = cases
    c = cs[("cycle", name)]
    assert (c.part, c.params, c.supports, c.mass_kg) == (RAIL, {"length": 700.0 if name == "crank_rail" else 1000.0},
                                                         [("free", ())], pytest.approx(mass))
    assert np.array_equal(c.rows, h.crank_deg)
    got = hole_forces(c)
    first = expected_rail_screws(name, 0.0)
    assert c.refine == tuple(first) and list(got) == list(first)
    inertia = [ld for ld in c.loads if ld.kind == "inertia"]
    assert [(ld.component, ld.direction, ld.group) for ld in inertia] == [
        (k, (PIVOT_X, 0.0, 0.0), None) for k in ("a0x", "a0y", "alpha", "omega2")]
    bar = {"crank_rail": 0, "coupler_rail": 1, "rocker_rail": 2}[name]
    for i, t in enumerate(c.rows):
        for g, f in expected_rail_screws(name, t).items():
            assert np.allclose(got[g][i], [f.real, f.imag], atol=1e-9 * max(1.0, abs(f))), (name, t, g)
        k = fourbar_motion(*FINAL_CM, t)
        a0 = (k["aA"] if name == "coupler_rail" else 0j) * np.conj(k["e"][bar]) * 1000  # mm/s², rail frame
        assert np.allclose(c.coef[i, -4:], [a0.real, a0.imag, k["al"][bar], k["w"][bar] ** 2], rtol=1e-9, atol=1e-6), t
    assert f"({mass:.3f} kg)" in c.notes[0] and ", ".join(first) in c.notes[0]


def test_cycle_fitting_cases_carry_their_pin_force(cases):
    h, cs = cases
    plate, post = cs[("cycle", "plate_B")], cs[("cycle", "post_B")]
    assert (plate.part, plate.params, plate.supports, plate.refine) == (
        "PF_4b_006", {}, [("bolt", ("screw_1", "screw_2"))], ("bore", "screw_1", "screw_2"))
    assert (post.part, post.params, post.refine) == ("PF_4b_003_v2", {}, ("screw_1", "screw_2", "screw_3", "screw_4", "fillets"))
    assert post.supports == [("slide", ("base",)), ("bolt", ("screw_1", "screw_2"))]
    assert plate.notes == ["B pin force on the bearing seat at every crank angle; held by its two screws"]
    assert post.notes == ["B pin force through the top screws; base resting on the rail (normal displacement only), "
                          "bottom screws bolted"]
    on_plate, on_post = hole_forces(plate), hole_forces(post)
    assert list(on_post) == ["screw_3", "screw_4"]
    for i, t in enumerate(h.crank_deg):
        F, _, _ = fourbar_newton_euler(*FINAL_CM, t)
        k = fourbar_motion(*FINAL_CM, t)
        at_plate = -F["B"] * np.conj(k["e"][1])  # the rocker's pin on the coupler, in the coupler rail's frame
        assert np.allclose(on_plate["bore"][i], [at_plate.real, at_plate.imag], atol=1e-9 * abs(at_plate))
        along = F["B"] * np.conj(k["e"][2])  # on the rocker, in its frame; the post's x is the rail's −y
        half = np.array([-along.imag, along.real]) / 2
        for g in ("screw_3", "screw_4"):
            assert np.allclose(on_post[g][i], half, atol=1e-9 * abs(along)), (t, g)


def test_original_cases_say_what_the_study_did(cases):
    _, cs = cases
    crank, plate, post = cs[("original", "crank_rail")], cs[("original", "plate_A")], cs[("original", "post_B")]
    peak, deg = newton_euler_peak(fourbar_newton_euler, FINAL_CM, "A")
    assert (crank.part, crank.params, crank.mass_kg) == (RAIL, {"length": 700.0}, None)
    assert crank.refine == ("hole_00", "hole_02", "hole_09", "hole_11")
    assert np.allclose(crank.rows, [deg], atol=1e-4) and np.allclose(plate.rows, [deg], atol=1e-4)
    assert (plate.part, plate.params, plate.refine) == ("PF_4b_006", {}, ("bore", "screw_1", "screw_2"))
    F, _, _ = fourbar_newton_euler(*FINAL_CM, deg)
    d = -F["A"] * np.conj(fourbar_motion(*FINAL_CM, deg)["e"][0]) / abs(F["A"])
    assert [ld.direction for ld in plate.loads] == [pytest.approx((d.real, d.imag, 0.0), abs=1e-7)]
    assert [ld.direction for ld in crank.loads] == [pytest.approx((d.real, d.imag, 0.0), abs=1e-7)] * 2
    assert (post.part, post.params, list(post.rows), post.refine) == (
        "PF_4b_003_v2", {}, [0.0], ("screw_1", "screw_2", "screw_3", "screw_4", "fillets"))
    assert [ld.direction for ld in post.loads] == [pytest.approx((2**-0.5, 2**-0.5, 0.0))] * 4
    for c in (crank, plate, post):
        assert c.notes == [NOTES[c.name]], c.name
        assert {ld.kind for ld in c.loads} == {"bearing"}, c.name
    assert abs(peak - 420.06304793087634) < 1e-6  # the committed report's peak A reaction


def test_a_history_without_evaluator_loads_the_nearest_sample():
    """An imported history (no solver to refine on): the study's case takes the sample nearest the
    refined peak, its force and direction there (Newton–Euler at that sample), 1.4 × the peak."""
    h = simulate(four_bar(*FINAL_CM), samples=72)
    bare = dataclasses.replace(h, evaluator=None)
    pk = peaks(h)
    s = check_settings({"modes": ["original"], "parts": ["crank_rail", "plate_A", "rocker_rail"]}, "four-bar",
                       list(RAILS_MM))
    got = {c.name: c for _, c in part_cases(bare, pk, s)}
    for name, joint, bar in (("crank_rail", "A", 0), ("plate_A", "A", 0), ("rocker_rail", "B", 2)):
        near = h.crank_deg[np.argmin(np.abs((h.crank_deg - pk[joint]["crank_deg"] + 180) % 360 - 180))]
        F, _, _ = fourbar_newton_euler(*FINAL_CM, near)
        d = (F[joint] if name == "rocker_rail" else -F[joint]) * np.conj(fourbar_motion(*FINAL_CM, near)["e"][bar])
        c = got[name]
        assert list(c.rows) == [near], name
        assert np.allclose(c.loads[0].direction, [d.real / abs(d), d.imag / abs(d), 0.0], atol=1e-12), name
    assert np.allclose(got["plate_A"].coef, 1.4 * pk["A"]["force_N"], rtol=1e-12)
    c = part_cases(bare, {**pk, "A": {**pk["A"], "crank_deg": 2.6}}, s)[0][1]
    assert list(c.rows) == [5.0]  # 2.4° from 5°, 2.6° from 0°
    nowhere = dataclasses.replace(bare, joints={n: dataclasses.replace(j, position_mm=None) for n, j in bare.joints.items()})
    with pytest.raises(ComputeError, match="no joint positions"):  # a bug: every check's history has them
        part_cases(nowhere, pk, s)
    near_zero = dataclasses.replace(h, evaluator=None, crank_deg=(h.crank_deg + 355.0) % 360.0)  # wraps round 360°
    c = part_cases(near_zero, {**pk, "A": {**pk["A"], "crank_deg": 1.0}}, s)[0][1]
    assert list(c.rows) == [0.0]


def test_mirrored_peaks_are_all_loaded_and_a_toggle_is_refused():
    """The symmetric slider-crank has two equal peaks at B (mirror angles): both are load rows."""
    h = simulate(slider_crank(300.0, 840.0, 0.0), samples=72)
    s = check_settings({"modes": ["original"], "parts": ["rod_rail"]}, "slider-crank", [700.0, 1000.0])
    (_, rod), = part_cases(h, peaks(h), s)
    assert len(rod.rows) == 2 and rod.rows[0] + rod.rows[1] == pytest.approx(360.0)
    assert rod.coef.shape == (2, 4) and np.count_nonzero(rod.coef) == 4
    assert f"at crank {rod.rows[0]:.2f}° and {rod.rows[1]:.2f}° (equal peaks: the worst is checked), split" in rod.notes[0]
    pk = peaks(h)
    for bad in ({**pk["B"], "singular": True}, {**pk["B"], "force_N": None}):
        with pytest.raises(InputError, match="toggle"):
            part_cases(h, {**pk, "B": bad}, s)
    s4 = check_settings({"modes": ["original"], "parts": ["crank_rail"]}, "four-bar", list(RAILS_MM))
    c = part_cases(simulate(four_bar(*FINAL_CM), samples=36), peaks(simulate(four_bar(*FINAL_CM), samples=36)), s4)
    assert "equal peaks" not in c[0][1].notes[0]


def test_a_tiny_load_keeps_its_direction_and_no_load_gets_none():
    """Turning very slowly the peak A reaction is 1e-3 N: the load case still points along it; a
    massless linkage's parts get zero weights (reported 'not loaded', never passed)."""
    from rigfem.loads import direction_weights

    slow = simulate(four_bar(*FINAL_CM), samples=36, speed_hz=0.002)
    s = check_settings({"modes": ["original", "cycle"], "parts": ["plate_A"]}, "four-bar", list(RAILS_MM))
    cs = dict(((m, c.name), c) for m, c in part_cases(slow, peaks(slow), s))
    plate = cs[("original", "plate_A")]
    t = plate.rows[0]
    F, _, _ = fourbar_newton_euler(*FINAL_CM, t, 0.002)
    d = -F["A"] * np.conj(fourbar_motion(*FINAL_CM, t, 0.002)["e"][0])
    assert abs(F["A"]) < 1e-2 and np.allclose(plate.loads[0].direction, [d.real / abs(d), d.imag / abs(d), 0.0], atol=1e-9)
    assert all(ld.direction[2] == 0.0 for ld in cs[("cycle", "plate_A")].loads)
    still = simulate(four_bar(*FINAL_CM, masses=None), samples=36)
    (_, c), = part_cases(still, peaks(still), check_settings({"modes": ["original"], "parts": ["plate_A"]},
                                                            "four-bar", list(RAILS_MM)))
    assert {ld.direction for ld in c.loads} == {(1.0, 0.0, 0.0)} and not np.any(c.coef)  # every angle ties
    assert direction_weights(np.array([[3.0, 4.0]])).shape == (1, 12)  # the documented default: 12 directions
    w = direction_weights(np.array([[1.0, -1e-20]]), 8)  # an angle that rounds to 2π lands on direction 0
    assert np.allclose(w[0], np.eye(8)[0])
