"""Closed-form dynamics of the rig four-bar and slider-crank (rigfem.dynamics.closed) against
the general planar solver: same reactions, torque, motion and peaks to round-off; the
general solver keeps toggles and other topologies."""

import numpy as np
import pytest

from rigfem.dynamics import compressor_gas_force, peaks, solve
from rigfem.linkage import Revolute, crank_angles, four_bar, quick_return, slider_crank


def _rng_fourbars(n: int, seed: int = 3):
    """Random Grashof crank-rockers (shortest link the crank) clear of the toggle band."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        b2 = rng.uniform(60, 400)
        b3, b4, d = rng.uniform(b2 + 50, 1500, 3)
        if b2 + max(b3, b4, d) < sum((b3, b4, d)) - max(b3, b4, d) - 1:
            try:
                lk = four_bar(b2, b3, b4, d, masses=None, branch=str(rng.choice(["open", "crossed"])),
                              body_masses={"crank": {"mass_kg": rng.uniform(0.5, 3), "com_local_mm": (b2 / 2, 5.0)},
                                           "coupler": {"mass_kg": rng.uniform(0.5, 3), "com_local_mm": (b3 / 3, -20.0),
                                                       "inertia_com_kg_mm2": 1e4},
                                           "rocker": {"mass_kg": 1.0, "com_local_mm": (b4 / 2, 0.0),
                                                      "point_masses": [("B", 0.7, (b4, 0.0))]}},
                              gravity_mm_s2=(0.0, -9810.0))
            except Exception:
                continue
            if solve(lk, crank_angles(8)).meta["solver"] == "closed form":
                out.append(lk)
    return out


CASES = {
    "rig-reference": lambda: four_bar(540, 840, 780, 1020),
    "rig-crossed-gravity": lambda: four_bar(540, 840, 780, 1020, branch="crossed", gravity_mm_s2=(0, -9810)),
    "rig-slider-offset": lambda: slider_crank(300, 840, 50),
    "compressor-custom-masses": lambda: slider_crank(
        100, 400, -20, masses=None, slider_force=compressor_gas_force(100, 400),
        body_masses={"slider": {"mass_kg": 2.0}, "rod": {"mass_kg": 1, "com_local_mm": (200, 3),
                                                         "inertia_com_kg_mm2": 1e4}}),
}


def _assert_same(a, b):
    scale = max(np.abs(j.force_N).max() for j in b.joints.values())
    for name, jb in b.joints.items():
        ja = a.joints[name]
        assert np.allclose(ja.force_N, jb.force_N, rtol=0, atol=1e-11 * scale), name
        assert np.allclose(ja.position_mm, jb.position_mm, rtol=0, atol=1e-9), name
        if jb.moment_Nm is not None:
            assert np.allclose(ja.moment_Nm, jb.moment_Nm, rtol=0, atol=1e-11 * scale), name
    assert np.allclose(a.torque_Nm, b.torque_Nm, rtol=0, atol=1e-11 * np.abs(b.torque_Nm).max())
    for name, bb in b.bodies.items():
        ba = a.bodies[name]
        assert np.allclose(np.angle(np.exp(1j * (ba.angle_rad - bb.angle_rad))), 0, atol=1e-12)
        for f in ("omega_rad_s", "alpha_rad_s2", "origin_mm", "origin_vel_mm_s", "origin_acc_mm_s2"):
            x, y = getattr(ba, f), getattr(bb, f)
            assert np.allclose(x, y, rtol=0, atol=1e-10 * max(1.0, np.abs(y).max())), (name, f)
        assert ba.joint_local_mm.keys() == bb.joint_local_mm.keys()


@pytest.mark.parametrize("speed_hz", [1.3, -0.7])
@pytest.mark.parametrize("case", list(CASES))
def test_closed_form_equals_general_solver(case, speed_hz):
    lk = CASES[case]()
    deg = crank_angles(360, 7.0)
    a, b = solve(lk, deg, speed_hz), solve(lk, deg, speed_hz, general=True)
    assert (a.meta["solver"], b.meta["solver"]) == ("closed form", "general")
    _assert_same(a, b)
    pa, pb = peaks(a), peaks(b)
    for k in pb:
        va, vb = (pa[k].get("force_N", pa[k].get("peak")), pb[k].get("force_N", pb[k].get("peak")))
        assert va == pytest.approx(vb, rel=1e-12), k
        assert pa[k]["crank_deg"] == pytest.approx(pb[k]["crank_deg"], abs=1e-5), k


def test_random_crank_rockers_agree():
    for lk in _rng_fourbars(12):
        deg = crank_angles(72)
        _assert_same(solve(lk, deg, 2.0), solve(lk, deg, 2.0, general=True))


def test_evaluator_is_closed_form_at_any_angle():
    lk = four_bar(540, 840, 780, 1020)
    h = solve(lk, crank_angles(36))
    at = np.array([3.3, 181.7, 359.9])
    _assert_same(h.evaluator(at), solve(lk, at, general=True))


def test_toggles_and_other_topologies_stay_with_the_general_solver():
    # slider-crank whose rod comes within 5 deg of perpendicular to the slide, a quick-return, and
    # a four-bar with a renamed joint
    lk = four_bar(540, 840, 780, 1020)
    lk.joints[3] = Revolute("O4", "rocker", "ground", (0.0, 0.0), (1020.0, 0.0))
    for lk in (slider_crank(300, 900, 599.9), quick_return(150, 350, 800), lk):
        assert solve(lk, crank_angles(36)).meta["solver"] == "general"
    assert solve(slider_crank(300, 900, 590.0), crank_angles(36)).meta["solver"] == "closed form"
    # a change-point four-bar (mu reaches 180 deg) follows its smooth branch through the change point
    # in closed form (the general solver may bounce there), its toggle flagged (tests/test_change_points.py)
    h = solve(four_bar(540, 840, 780, 1080), crank_angles(36))
    assert h.meta["solver"] == "closed form" and any(a <= 180.0 <= b for a, b in h.meta["singular"])


@pytest.mark.parametrize("general", [False, True])
def test_mirrored_equal_peaks_are_all_reported(general):
    """An offset-free slider-crank is symmetric: every reaction peaks equally at crank angles θ
    and 360° − θ.  Which one the floats crown is a knife edge, so both are listed, the smaller
    is the peak's angle whichever solver ran, and the study's load case takes both."""
    from rigfem.loads import part_cases
    from rigfem.settings import check_settings

    lk = slider_crank(540, 600)
    h = solve(lk, crank_angles(360), general=general)
    pk = peaks(h)
    for name in ("O2", "A", "B", "torque"):
        a, b = pk[name]["equal_peaks_deg"]
        assert a + b == pytest.approx(360.0, abs=1e-5) and pk[name]["crank_deg"] == a < 180.0
    assert "equal_peaks_deg" not in peaks(solve(four_bar(540, 840, 780, 1020), crank_angles(360)))["B"]
    cases = dict((c.name, c) for mode, c in part_cases(h, pk, check_settings({}, "slider-crank", [700.0, 1000.0]))
                 if mode == "original" and c.name == "plate_B")
    c = cases["plate_B"]
    assert c.coef.shape == (2, 2) and np.allclose(c.coef, np.diag(np.diag(c.coef)))
    assert sorted(c.rows) == pytest.approx(pk["B"]["equal_peaks_deg"])
    d0, d1 = (np.array(u.direction[:2]) for u in c.loads)
    assert not np.allclose(d0, d1)  # mirrored force directions, in the plate's frame
