"""The 2013 program reproduced: calibration case of geometry/RIG.md §3 to better than 1e-4 relative."""

import numpy as np
import pytest

from rigfem.dynamics import fourbar_kinematics, original_program, peaks, simulate
from rigfem.linkage import four_bar

#: geometry/RIG.md §3, the study's printed figures for b2=540 b3=840 b4=780 d=1020 mm at 1 Hz
CALIBRATION = {"O2": 641.9099, "A": 578.8140, "B": 379.4016, "O4": 366.4701,
               "torque_Nm": 199.7707, "mu_max_deg": 148.6930, "mu_min_deg": 34.2160}


@pytest.mark.parametrize("key", sorted(CALIBRATION))
def test_original_program_matches_calibration(key):
    got = original_program(540, 840, 780, 1020, speed_hz=1.0)
    assert got[key] == pytest.approx(CALIBRATION[key], rel=1e-4)


def test_original_model_through_simulate_matches_calibration():
    h = simulate(four_bar(540, 840, 780, 1020), samples=360, model="original")
    p = peaks(h)
    for j in ("O2", "A", "B", "O4"):
        assert p[j]["force_N"] == pytest.approx(CALIBRATION[j], rel=1e-4)
    assert p["torque"]["peak"] == pytest.approx(CALIBRATION["torque_Nm"], rel=1e-4)
    assert h.meta["mu_deg"]["min"] == pytest.approx(CALIBRATION["mu_min_deg"], rel=1e-4)
    assert h.meta["mu_deg"]["max"] == pytest.approx(CALIBRATION["mu_max_deg"], rel=1e-4)
    assert h.meta["singular"] is None


def test_transmission_angle_extremes_closed_form():
    """geometry/RIG.md §2: cos mu_min/max from the crank aligned with the ground line."""
    b2, b3, b4, d = 540, 840, 780, 1020
    mu_min = np.degrees(np.arccos((b3**2 + b4**2 - (d - b2) ** 2) / (2 * b3 * b4)))
    mu_max = np.degrees(np.arccos((b3**2 + b4**2 - (d + b2) ** 2) / (2 * b3 * b4)))
    k = fourbar_kinematics(b2, b3, b4, d, np.radians(np.arange(0, 360, 0.01)), 1.0)
    mu = np.degrees(k["mu"])
    assert mu.min() == pytest.approx(mu_min, abs=1e-6)
    assert mu.max() == pytest.approx(mu_max, abs=1e-6)
