"""Issue 6, stability at the extremes — linkages.

Near-toggle configurations (mu -> 0 and 180 deg), the Grashof change point, bars from
10 mm to 10 m, very high speeds and lengths that look like metres.  Every case is either
checked against an independent reference (closed-form transmission angle, a scaling law,
a neighbouring configuration) or must raise a one-line InputError naming the field.
"""

import json

import numpy as np
import pytest

from rigfem.pipeline import Output, Request, run_check
from rigfem.cli import main
from rigfem.dynamics import peaks, simulate
from rigfem.linkage import MU_TOGGLE_DEG, ClosureError, four_bar, slider_crank
from rigfem.errors import InputError
from rigfem.report import finite
from rigfem.rig import fourbar_rules, transmission_angle_range

REF = (480.0, 840.0, 780.0, 1020.0)  # the final design (mm)


def _assert_unbounded(pk):
    """Every peak of a toggle is None + singular, and the dict passes the report's finite()."""
    assert pk and all(p["singular"] for p in pk.values())
    assert all(p["force_N"] is None for n, p in pk.items() if n != "torque")
    assert pk["torque"]["peak"] is None and pk["torque"]["value"] is None
    finite(pk)


def _mu_closed_form(b2, b3, b4, d, deg):
    """Transmission angle from the cosine rule on the diagonal O4-A (independent of the solver)."""
    f2 = b2**2 + d**2 - 2 * b2 * d * np.cos(np.radians(deg))
    return np.degrees(np.arccos(np.clip((b3**2 + b4**2 - f2) / (2 * b3 * b4), -1, 1)))


# ----------------------------------------------------------------------------- near toggle
@pytest.mark.parametrize("d", [161.0, 175.0])  # d - b2 -> |b3 - b4| = 60: mu_min -> 0
def test_mu_to_zero_is_flagged_and_never_given_a_number(d):
    lk = (100.0, 840.0, 780.0, d)
    h = simulate(four_bar(*lk), samples=360)
    mu_min, _ = transmission_angle_range(*lk)
    assert mu_min < MU_TOGGLE_DEG
    assert h.meta["mu_deg"]["min"] == pytest.approx(mu_min, abs=1e-7)      # sample at crank 0
    # the flagged samples are exactly those with mu (closed form) within 5 deg of 0/180
    mu = _mu_closed_form(*lk, h.crank_deg)
    expect = np.sin(np.radians(mu)) < np.sin(np.radians(MU_TOGGLE_DEG))
    assert np.array_equal(h.singular_mask, expect)
    assert h.meta["singular"][0][0] == 0.0
    _assert_unbounded(peaks(h))


def test_just_outside_the_toggle_band_is_finite_and_continuous():
    """mu_min = 5.7 deg: not flagged; the peak is finite and grows as mu_min shrinks."""
    pk = {d: peaks(simulate(four_bar(100.0, 840.0, 780.0, d), samples=360)) for d in (200.0, 220.0)}
    assert transmission_angle_range(100.0, 840.0, 780.0, 200.0)[0] > MU_TOGGLE_DEG
    for p in pk.values():
        assert not any(x["singular"] for x in p.values())
        assert all(np.isfinite(x["force_N"]) and x["force_N"] > 0 for n, x in p.items() if n != "torque")
    assert pk[200.0]["A"]["force_N"] > pk[220.0]["A"]["force_N"]


def test_mu_to_180_is_flagged():
    lk = (240.0, 840.0, 780.0, 1379.0)  # b2 + d = 1619, one mm short of b3 + b4
    h = simulate(four_bar(*lk), samples=360)
    assert transmission_angle_range(*lk)[1] > 180 - MU_TOGGLE_DEG
    assert h.meta["mu_deg"]["max"] == pytest.approx(transmission_angle_range(*lk)[1], abs=1e-7)
    assert any(a <= 180.0 <= b for a, b in h.meta["singular"])
    _assert_unbounded(peaks(h))


def test_slider_crank_rod_near_perpendicular_is_flagged():
    """b2/b3 > cos 5 deg: the rod passes within 5 deg of perpendicular to the slide (asin(b2/b3))."""
    h = simulate(slider_crank(300.0, 301.0), samples=360)
    assert np.degrees(np.arcsin(300 / 301)) > 90 - MU_TOGGLE_DEG
    assert h.meta["singular"] and any(a <= 90.0 <= b for a, b in h.meta["singular"])
    _assert_unbounded(peaks(h))
    ok = simulate(slider_crank(300.0, 320.0), samples=360)  # asin(300/320) = 69.6 deg
    assert ok.meta["singular"] is None and all(np.isfinite(p["force_N"])
                                               for n, p in peaks(ok).items() if n != "torque")


def test_mu_to_zero_through_cli_json_and_text(capsys):
    assert main(["reactions", "--four-bar", "100", "840", "780", "175", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["singular"] and all(p["force_N"] is None for p in res["peaks"].values())
    assert main(["reactions", "--four-bar", "100", "840", "780", "175"]) == 0
    out = capsys.readouterr().out
    assert "SINGULAR" in out and "e+" not in out and "inf" not in out.lower() and "nan" not in out.lower()


def test_mu_to_zero_through_check(tmp_path):
    """tests/test_check.py covers mu -> 180 deg; this is the mu -> 0 side."""
    scene = tmp_path / "toggle0.toml"
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 100.0\nb3 = 840.0\nb4 = 780.0\nd = 175.0\n')
    r = run_check(Request(scene, {"parts": ["plate_A"]}, True), Output(tmp_path / "o"))  # it breaks the ground-clearance and hole-grid rules
    assert r["verdict"] == "fail" and r["singular"][0][0] == 0.0
    assert r["parts"] and all(p["peak_mpa"] is None and "toggle" in p["notes"][0] for p in r["parts"])
    rep = json.loads((tmp_path / "o" / "report.json").read_text())
    finite(rep)
    assert all(p["force_N"] is None for p in rep["peaks"].values() if "force_N" in p)


# ----------------------------------------------------------------------------- Grashof change point
def test_grashof_change_point():
    """b2 + d = b3 + b4: the 'crank turns fully' rule fails (strict), mu reaches 180 deg at crank
    180 (flagged, no number); 1 mm longer cannot be assembled (error names the angle range);
    one hole pitch shorter is an ordinary, finite configuration."""
    lk = (240.0, 840.0, 780.0, 1380.0)
    rules = {r.name.split(" (")[0]: r for r in fourbar_rules(*lk)}
    assert not rules["crank turns fully"].ok
    assert transmission_angle_range(*lk)[1] == pytest.approx(180.0, abs=1e-6)
    h = simulate(four_bar(*lk), samples=360)
    assert any(a <= 180.0 <= b for a, b in h.meta["singular"])
    _assert_unbounded(peaks(h))
    with pytest.raises(ClosureError, match=r"cannot be assembled for crank angles 17\d\.\d-18\d\.\d deg"):
        four_bar(240.0, 840.0, 780.0, 1381.0)
    below = (240.0, 840.0, 780.0, 1320.0)
    assert {r.name.split(" (")[0]: r for r in fourbar_rules(*below)}["crank turns fully"].ok
    pk = peaks(simulate(four_bar(*below), samples=360))
    assert all(np.isfinite(p["force_N"]) for n, p in pk.items() if n != "torque")


# ----------------------------------------------------------------------------- bar lengths 10 mm .. 10 m
SHAPE = np.array([10.0, 17.5, 16.25, 21.25])  # the final design / 48: b2 = 10 mm (the smallest allowed)
K_MAX = 10000.0 / SHAPE[-1]  # d = 10 m (the largest allowed)


def _pointmass_fourbar(k, hz=1.0):
    """Massless bars, fixed point masses at the joints, lengths k * SHAPE."""
    b2, b3, b4, d = k * SHAPE
    masses = {"crank": {"point_masses": [("A", 1.0, (b2, 0.0))]},
              "coupler": {"point_masses": [("B", 2.0, (b3, 0.0)), ("mid", 0.3, (b3 / 2, 0.0))]},
              "rocker": {"point_masses": [("B", 0.5, (b4, 0.0))]}}
    return peaks(simulate(four_bar(b2, b3, b4, d, masses=None, body_masses=masses), samples=360, speed_hz=hz))


def test_reactions_scale_with_length_from_10_mm_to_10_m():
    """Same shape and masses, lengths x k: accelerations and forces x k, torque x k², angles unchanged."""
    small, mid, big = _pointmass_fourbar(1.0), _pointmass_fourbar(10.0), _pointmass_fourbar(K_MAX)
    for n in small:
        if n == "torque":
            for p, k in ((mid, 10.0), (big, K_MAX)):
                assert p[n]["peak"] == pytest.approx(k**2 * small[n]["peak"], rel=1e-8)
        else:
            for p, k in ((mid, 10.0), (big, K_MAX)):
                assert p[n]["force_N"] == pytest.approx(k * small[n]["force_N"], rel=1e-8)
                assert p[n]["crank_deg"] == pytest.approx(small[n]["crank_deg"], abs=1e-5)


@pytest.mark.parametrize("hz", [10.0, 100.0])
def test_reactions_scale_with_speed_squared_pointmasses(hz):
    lo, hi = _pointmass_fourbar(1.0, 1.0), _pointmass_fourbar(1.0, hz)
    for n in lo:
        key = "peak" if n == "torque" else "force_N"
        assert hi[n][key] / lo[n][key] == pytest.approx(hz**2, rel=1e-9)


@pytest.mark.parametrize("model", ["rigid-body", "original"])
def test_rig_reactions_scale_with_speed_squared(model):
    """Inertia-only rig (no gravity): 1 Hz vs 10 Hz and 100 Hz (the allowed maximum) = 100 and 1e4."""
    lk = four_bar(*REF)
    base = peaks(simulate(lk, samples=360, speed_hz=1.0, model=model))
    for hz in (10.0, 100.0):
        p = peaks(simulate(lk, samples=360, speed_hz=hz, model=model))
        for n in base:
            key = "peak" if n == "torque" else "force_N"
            assert p[n][key] / base[n][key] == pytest.approx(hz**2, rel=1e-9)


def test_speed_above_the_allowed_range_is_a_clear_error():
    for hz in (100.5, 1e6, float("inf"), float("nan")):
        with pytest.raises(InputError, match=r"speed_hz = .* within \[-100, 100\] Hz") as e:
            simulate(four_bar(*REF), speed_hz=hz)
        assert "\n" not in str(e.value)


@pytest.mark.parametrize("build, field", [
    (lambda: four_bar(0.48, 0.84, 0.78, 1.02), "b2"),
    (lambda: four_bar(480.0, 840.0, 780.0, 1.02), "d"),
    (lambda: slider_crank(0.3, 0.9), "b2"),
])
def test_lengths_in_metres_are_a_clear_error(build, field):
    with pytest.raises(InputError, match=rf"^{field} = [\d.]+ looks like metres: lengths are in mm "
                                         r"\(allowed 10 to 10000 mm\)$"):
        build()


@pytest.mark.parametrize("b2, msg", [
    (10000.5, r"b2 = 10000.5 mm is outside the allowed range \[10, 10000\] mm"),
    (0.0, r"b2 = 0.0 mm must be a positive length"),
    (float("nan"), r"b2 = nan mm must be a positive length"),
])
def test_lengths_outside_10mm_10m_are_a_clear_error(b2, msg):
    with pytest.raises(InputError, match=msg):
        four_bar(b2, 840.0, 780.0, 1020.0)


# ----------------------------------------------------------------------------- rail lengths

@pytest.mark.parametrize("rails, needle", [
    pytest.param((-700.0, 1000.0, 1000.0), r"rails_mm.*-700"),
    pytest.param((float("nan"), 1000.0, 1000.0), r"rails_mm.*nan"),
    pytest.param((0.7, 1.0, 1.0), r"rails_mm.*looks like metres"),
    pytest.param((700.0, 2000.0, 2000.0), r"b2 = 1200.*rails_mm.*700"),
    pytest.param((1200.0, 2000.0, 2000.0), r"b2 = 1200 mm does not fit.*allowed b2 <= 1120 mm"),
])
def test_bad_rail_lengths_are_a_clear_error(rails, needle):
    with pytest.raises(InputError, match=needle):
        simulate(four_bar(1200.0, 1900.0, 1800.0, 2400.0, rails_mm=rails), samples=72)


def test_valid_rails_give_finite_peaks():
    """The counterpart of the errors above: rails that reach each far joint (80 mm of a rail lies
    behind its pivot) solve normally."""
    pk = peaks(simulate(four_bar(1200.0, 1900.0, 1800.0, 2400.0, rails_mm=(1280.0, 2000.0, 2000.0)), samples=72))
    assert all(np.isfinite(p["force_N"]) and p["force_N"] > 0 for n, p in pk.items() if n != "torque")
