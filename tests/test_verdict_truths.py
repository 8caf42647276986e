"""The verdict's rules against the numbers the README and geometry/RIG.md state, written here
(not read from rigfem): σu/2 = 375 MPa for the rig steel, the undecided band, a free body's 5 %
imbalance tolerance, the Goodman line with Se' = Sut/2 (issue 39: the mutation tests'
survivors in rigfem/verdict/)."""

import numpy as np
import pytest

from rigfem.errors import ComputeError, InputError
from rigfem.material import Material
from rigfem.verdict import goodman, half_ultimate, marin_endurance, overall
from rigfem.verdict.criterion import allowable_stress


def test_a_free_body_out_of_balance_by_more_than_five_percent_is_undecided():
    """README: above 5 % of the applied load (force) or of load × lever (moment) the part is undecided."""
    assert half_ultimate(30.0, 750.0, imbalance=(0.049, 0.049)).verdict == "pass"
    for imb in ((0.051, 0.0), (0.0, 0.051), (0.3, 0.2)):
        v = half_ultimate(30.0, 750.0, imbalance=imb)
        assert v.verdict == "undecided" and "tolerance 5 %" in v.reason, imb
    assert half_ultimate(400.0, 750.0, imbalance=(0.3, 0.0)).verdict == "fail"  # failing stays failing


def _refused(call, message: str) -> None:
    """``call`` raises InputError with exactly ``message`` (README: one line naming the field, the value,
    the allowed range and its unit)."""
    with pytest.raises(InputError) as e:
        call()
    assert str(e.value) == message


def _invariant(call, match: str) -> None:
    """``call`` raises ComputeError: inside the layers a value the edge validated (σu by Material, the
    limit factor by the scene schema) or the FE produced (a peak, a history) is an invariant, its
    breach a bug, not bad input."""
    with pytest.raises(ComputeError, match=match):
        call()


def test_the_allowable_is_half_the_ultimate_strength():
    """geometry/RIG.md §5: σu/2 = 375 MPa for the rig steel; a limit factor in (0, 1], σu > 0."""
    assert allowable_stress(750.0) == 375.0
    assert allowable_stress(750.0, 0.4) == 300.0 and allowable_stress(750.0, 1.0) == 750.0
    assert allowable_stress(0.5, 0.5) == 0.25  # any positive strength
    assert half_ultimate(290.0, 750.0, factor=0.4).limit_mpa == 300.0
    for bad in ((0.0, 0.5), (750.0, 0.0), (750.0, 1.5)):
        _invariant(lambda: allowable_stress(*bad), "not a limit")


def test_the_band_decides_at_the_limit():
    """A peak passes only when its whole band lies below σu/2, fails when the whole band reaches it;
    a peak exactly at the limit fails (the criterion is peak < σu/2)."""
    assert half_ultimate(375.0, 750.0).verdict == "fail"
    assert half_ultimate(374.0, 750.0).verdict == "pass"            # no band unless given
    assert half_ultimate(374.0, 750.0, 1.0).verdict == "undecided"  # 374 · 1.01 > 375
    assert half_ultimate(375 / 1.01 + 0.01, 750.0, 1.0).verdict == "undecided"  # band top just above
    assert half_ultimate(375 / 1.01 - 0.01, 750.0, 1.0).verdict == "pass"
    assert half_ultimate(375 / 0.99 - 0.01, 750.0, 1.0).verdict == "undecided"  # band bottom just below
    assert half_ultimate(375 / 0.99 + 0.01, 750.0, 1.0).verdict == "fail"
    assert half_ultimate(400.0, 750.0, 1.0).verdict == "fail"
    v = half_ultimate(300.0, 750.0, 2.0)
    assert v.as_dict() == {"peak_mpa": 300.0, "limit_mpa": 375.0, "utilisation_pct": 80.0, "error_pct": 2.0,
                           "verdict": "pass", "reason": ""}
    _invariant(lambda: half_ultimate(-1.0, 750.0), "not a stress")
    _invariant(lambda: half_ultimate(1.0, 750.0, -2.0), "not a stress")
    _invariant(lambda: half_ultimate(float("nan"), 750.0), "not a stress")
    assert half_ultimate(0.0, 750.0, 0.0).verdict == "pass"


def test_imbalance_at_the_tolerance_passes_and_its_reason_names_both_figures():
    assert half_ultimate(30.0, 750.0, imbalance=(0.05, 0.05)).verdict == "pass"
    v = half_ultimate(30.0, 750.0, imbalance=(0.06, 0.02))
    assert v.reason == "free body out of balance: force 6.0 %, moment 2.0 % (tolerance 5 %)"
    assert (v.peak_mpa, v.error_pct) == (30.0, 0.0)


@pytest.mark.parametrize("verdicts, expected", [
    (["pass"], "pass"), (["pass", "pass"], "pass"), (["pass", "fail"], "fail"), (["undecided", "fail"], "fail"),
    (["pass", "undecided"], "undecided"), (["not loaded", "pass"], "undecided"), (["fail", "not loaded"], "fail")])
def test_overall_verdict(verdicts, expected):
    assert overall([{"verdict": v} for v in verdicts]) == expected


def test_marin_factors_are_shigleys():
    """Shigley 10th ed.: ka = a·Sut^b (Table 6-2, machined 4.51, −0.265); kb = (d/7.62)^−0.107 for
    2.79 ≤ d ≤ 51 mm, 1.51 d^−0.157 for 51 < d ≤ 254 mm, 1 in axial loading (eq. 6-20); kc 0.85
    axial (eq. 6-26); ke 0.814 at 99 % (Table 6-5); Se' = 0.5 Sut up to 1400 MPa, 700 MPa above (eq. 6-8);
    Se = ka kb kc kd ke Se'."""
    m = marin_endurance(750.0, size_mm=100.0, loading="axial", reliability=0.99, temperature_factor=0.9)
    ka = 4.51 * 750.0 ** -0.265
    assert (m["ka"], m["kb"], m["kc"], m["kd"], m["ke"], m["se_prime_mpa"]) == pytest.approx((ka, 1.0, 0.85, 0.9, 0.814, 375.0))
    assert m["se_mpa"] == pytest.approx(ka * 0.85 * 0.9 * 0.814 * 375.0, rel=1e-12)
    assert marin_endurance(750.0, size_mm=100.0, loading="bending")["kb"] == pytest.approx(1.51 * 100.0 ** -0.157)
    assert marin_endurance(750.0, size_mm=51.0, loading="bending")["kb"] == pytest.approx((51 / 7.62) ** -0.107, rel=1e-12)
    assert marin_endurance(750.0, size_mm=51.5, loading="bending")["kb"] == pytest.approx(1.51 * 51.5 ** -0.157, rel=1e-12)
    assert marin_endurance(750.0)["kb"] == pytest.approx((19.0 / 7.62) ** -0.107, rel=1e-12)  # the rail: d_e = 19 mm
    for su, se in ((1400.0, 700.0), (1400.5, 700.0), (1500.0, 700.0), (0.5, 0.25)):
        assert marin_endurance(su)["se_prime_mpa"] == se, su
    for d in (2.79, 254.0):
        assert marin_endurance(750.0, size_mm=d)["kb"] > 0
    assert marin_endurance(750.0, temperature_factor=1.0)["kd"] == 1.0
    _refused(lambda: marin_endurance(750.0, size_mm=2.5), "fatigue size_mm = 2.5 mm is outside the allowed range [2.79, 254] mm")
    _refused(lambda: marin_endurance(750.0, size_mm=260.0), "fatigue size_mm = 260.0 mm is outside the allowed range [2.79, 254] mm")
    with pytest.raises(InputError, match="sigma_u"):  # σu is validated where a material is made
        Material("x", 210e3, 0.3, 0.0, 7.85e-9)
    _refused(lambda: marin_endurance(750.0, temperature_factor=0.0),
             "fatigue temperature_factor = 0.0 is outside the allowed range (0, 1]")
    _refused(lambda: marin_endurance(750.0, temperature_factor=1.2),
             "fatigue temperature_factor = 1.2 is outside the allowed range (0, 1]")
    _refused(lambda: marin_endurance(750.0, reliability=0.8),
             "fatigue reliability 0.8 is not one of 0.5, 0.9, 0.95, 0.99, 0.999, 0.9999")


def test_goodman_picks_the_worst_point_and_passes_at_exactly_one():
    se = marin_endurance(750.0)["se_mpa"]
    hist = np.zeros((2, 2, 6))
    hist[:, 0, 0] = (0.1 * se, -0.1 * se)
    hist[:, 1, 0] = (se, -se)  # fully reversed at the endurance limit: n = 1 exactly
    g = goodman(hist, 750.0)   # two crank angles are enough
    assert g["point"] == 1 and g["safety_factor"] == 1.0 and g["verdict"] == "pass"
    hist[:, 1, 0] *= 1.001
    assert goodman(hist, 750.0)["verdict"] == "fail"
    still = goodman(np.zeros((3, 1, 6)), 750.0)  # no stress: no demand
    assert still["safety_factor"] == 1e9 and still["verdict"] == "pass"
    _invariant(lambda: goodman(np.zeros((1, 1, 6)), 750.0), r"shape \(angles >= 2, points >= 1, 6\): \(1, 1, 6\)")
    _invariant(lambda: goodman(np.zeros((4, 0, 6)), 750.0), r"shape \(angles >= 2, points >= 1, 6\): \(4, 0, 6\)")
    _invariant(lambda: goodman(np.zeros((4, 1, 5)), 750.0), r"shape \(angles >= 2, points >= 1, 6\): \(4, 1, 5\)")
