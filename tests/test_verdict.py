"""Verdict and fatigue check against hand calculations (Shigley 10th ed. examples)."""

import numpy as np
import pytest

from rigfem.errors import ComputeError, InputError
from rigfem.tensors import von_mises
from rigfem.verdict import goodman, half_ultimate, marin_endurance


def test_half_ultimate_pass_fail_undecided():
    assert half_ultimate(300.0, 750.0).verdict == "pass"
    assert half_ultimate(400.0, 750.0).verdict == "fail"
    v = half_ultimate(360.0, 750.0, error_pct=5.0)  # 342..378 straddles 375
    assert v.verdict == "undecided"
    assert v.limit_mpa == 375.0 and v.utilisation_pct == pytest.approx(96.0)


def test_half_ultimate_refuses_what_no_valid_input_gives():
    """σu and the factor are validated where they are read (material, schema); a NaN or negative
    peak is a broken invariant of the FE: could not compute, never a verdict."""
    with pytest.raises(ComputeError, match="peak von Mises"):
        half_ultimate(float("nan"), 750.0)
    with pytest.raises(ComputeError, match="sigma_u"):
        half_ultimate(100.0, 0.0)


def test_von_mises_uniaxial_and_shear():
    assert von_mises([100, 0, 0, 0, 0, 0]) == pytest.approx(100.0)
    assert von_mises([0, 0, 0, 50, 0, 0]) == pytest.approx(50 * np.sqrt(3))
    assert von_mises([70, 70, 70, 0, 0, 0]) == pytest.approx(0.0)  # hydrostatic


def test_marin_shigley_worked_values():
    # Shigley 10th ed. §6-9 worked examples: Sut = 520 MPa machined gives ka = 0.860; a 32 mm
    # shaft in bending gives kb = (32/7.62)^-0.107 = 0.858; Se = 0.860*0.858*0.5*520 = 192 MPa.
    m = marin_endurance(520.0, surface="machined", size_mm=32.0, loading="bending", reliability=0.5)
    assert m["ka"] == pytest.approx(0.860, abs=2e-3)
    assert m["kb"] == pytest.approx(0.858, abs=2e-3)
    assert m["se_mpa"] == pytest.approx(192.0, rel=5e-3)


def test_goodman_fully_reversed_and_static():
    se = marin_endurance(750.0)["se_mpa"]
    t = np.linspace(0, 2 * np.pi, 73)
    # fully reversed uniaxial amplitude A: n = Se / A
    a = 0.5 * se
    hist = np.zeros((t.size, 1, 6))
    hist[:, 0, 0] = a * np.sin(t)
    g = goodman(hist, 750.0)
    assert g["mean_mpa"] == pytest.approx(0.0, abs=1e-9)
    assert g["alternating_mpa"] == pytest.approx(a, rel=1e-12)
    assert g["safety_factor"] == pytest.approx(2.0, rel=1e-12) and g["verdict"] == "pass"
    # pulsating 0..S: σa = σm = S/2, n = 1/(S/2/Se + S/2/Su); picks the worse of two points
    s = 600.0
    hist2 = np.zeros((t.size, 2, 6))
    hist2[:, 0, 0] = 0.5 * s * (1 + np.sin(t))
    hist2[:, 1, 0] = 10.0
    g2 = goodman(hist2, 750.0)
    assert g2["point"] == 0
    assert g2["safety_factor"] == pytest.approx(1 / (s / 2 / se + s / 2 / 750.0), rel=1e-12)
    assert g2["verdict"] == "fail"


def test_goodman_bad_history():
    with pytest.raises(ComputeError, match="shape"):
        goodman(np.zeros((5, 6)), 750.0)
    with pytest.raises(InputError, match="surface"):
        goodman(np.zeros((5, 1, 6)), 750.0, surface="polished-by-hand")
