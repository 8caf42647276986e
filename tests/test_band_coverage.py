"""The error band is an estimate whose coverage is measured (issue 22 §4): it covers closed-form truths,
P1 reports say linear tetrahedra under-predict bending, the calibration is the committed record's, and
on 31 geometries the calibration never saw it covers the closed form at every level (issue 39 §1)."""

import json
import math
from pathlib import Path

import pytest
from fe_shapes import box, quarter_ring

from rigfem.fe import BAND_FACTOR, FixedComponents, Gravity, Pressure, Symmetry, build_model, solve
from rigfem.material import get_material
from rigfem.verification.band_coverage import (
    CALIBRATION_GEOMETRY,
    HELD_OUT,
    LEVELS,
    PRESETS,
    calibrate,
    closed_form_case,
    coverage,
    held_out,
    inside,
    lower_bound,
    preset_mesh,
    required_factor,
)

RECORD = Path(__file__).resolve().parents[1] / "results" / "convergence" / "band_coverage.json"
STEEL = get_material("rig_steel")


def covers(peak, truth: float, u: float = 0.0) -> bool:
    return abs(truth - peak.value) <= peak.value * peak.error_pct / 100 + u * truth


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("nx, nz", [(34, 2), (50, 2)])  # the standard (6 mm) and fine (4 mm) sizes
def test_band_covers_the_bending_stress_of_a_beam(order, nx, nz):
    """Simply supported beam (half of a 400 mm span) under its own weight: mid-span σ = 3ρgL²/H.
    P1 reads it 40-45 % low here; the raw ZZ estimate (main's band) missed it, the calibrated band covers."""
    L, B, H, g = 200.0, 5.0, 10.0, 1e7
    model = build_model(box(L, B, H, nx, 1, nz), STEEL, order)
    peak = solve(model, [Symmetry("xmin"), Symmetry("ymin"), FixedComponents("xmax", "z")],
                 [Gravity((0, 0, -g))]).peak()
    assert covers(peak, 3 * STEEL.density * g * L**2 / H, (H / (2 * L)) ** 2)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("size", [4.0, 2.0])
def test_band_covers_the_lame_bore_stress(order, size):
    a, b, p = 10.0, 20.0, 100.0
    st = p * (a**2 + b**2) / (b**2 - a**2)
    model = build_model(quarter_ring(a, b, 5.0, size=size), STEEL, order)
    peak = solve(model, [Symmetry("xsym"), Symmetry("ysym"), Symmetry("zsym")], [Pressure("inner", p)]).peak()
    assert covers(peak, math.sqrt(st**2 + p**2 + st * p))


def test_peak_error_pct_is_the_calibrated_zz_estimate_in_percent():
    model = build_model(box(100.0, 10.0, 10.0, 6, 1, 1), STEEL, 1)
    pk = solve(model, [FixedComponents("xmin", "xyz")], [Gravity((0, 0, -1e7))]).peak()
    assert pk.zz_error > 0 and pk.error_pct == pytest.approx(100 * BAND_FACTOR[1] * pk.zz_error, rel=1e-12)


def test_required_factor_and_calibration():
    case = {"peak_mpa": 80.0, "truth_mpa": 100.0, "truth_u": 0.01, "zz_error": 0.1, "order": 1,
            "set": "calibration", "preset": "x", "case": "c", "source": "closed form"}
    assert required_factor(case) == pytest.approx((20.0 - 1.0) / 8.0)
    assert not inside(case, 2.35) and inside(case, 2.4)
    assert calibrate([case]) == {1: 2.4}
    assert calibrate([{**case, "truth_mpa": 80.5}]) == {1: 1.0}  # never narrower than the raw estimate
    with pytest.raises(ValueError, match="zero estimate"):
        calibrate([{**case, "zz_error": 0.0}])
    cov = coverage([{**case, "set": "measurement", "inside_raw": False, "inside": True, "required_factor": 2.4}],
                   ["x"])["x"]
    assert (cov["coverage_raw_pct"], cov["coverage_pct"], cov["misses_raw"]) == (0.0, 100.0, ["c (x)"])


def test_committed_record_sets_the_factors_and_every_preset_covers_95_percent():
    """BAND_FACTOR is the committed coverage record's calibration; re-run the study when either changes."""
    rec = json.loads(RECORD.read_text())
    assert {int(k): v for k, v in rec["calibration"].items()} == BAND_FACTOR
    for preset in PRESETS:
        assert rec["coverage"][preset]["n"] >= 6 and rec["coverage"][preset]["coverage_pct"] >= 95.0
    assert rec["coverage"]["P1@standard"]["coverage_raw_pct"] < 95.0  # why P1 has its own factor


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_p1_reports_say_linear_tetrahedra_under_predict_bending(tmp_path):
    from rigfem.pipeline import Output, Request, run_check

    fast = {"parts": ["plate_A"], "modes": ["original"], "fidelity": "draft", "samples": 36, "frames": 0}
    r1 = run_check(Request("final-cm", {**fast, "order": 1}), Output(tmp_path / "p1"))
    r2 = run_check(Request("final-cm", fast), Output(tmp_path / "p2"))
    assert all(any("under-predict bending" in n for n in p["notes"]) for p in r1["parts"])
    assert not any("under-predict bending" in n for p in r2["parts"] for n in p["notes"])
    assert "under-predict bending" in (tmp_path / "p1" / "report.md").read_text().replace("\\", "")  # Markdown escapes "-"


@pytest.mark.heavy
def test_closed_form_coverage_of_the_presets_is_at_least_95_percent():
    for preset in ("draft", "standard", "P1@standard"):
        order, size, local = preset_mesh(preset)
        cases = [closed_form_case(cf, order, size, local) for cf in ("lame", "hole", "beam")]
        assert all(inside(c, BAND_FACTOR[order]) for c in cases), preset


# ----------------------------------------------------------------------------- held out (issue 39 §1)
def test_lower_bound_is_clopper_pearsons():
    """All n covered: the one-sided 95 % bound is 0.05^(1/n) (closed form); none: 0."""
    for n in (12, 29, 31):
        assert lower_bound(n, n) == pytest.approx(0.05 ** (1 / n), rel=1e-9)
    assert lower_bound(12, 12) < 0.8 < 0.9 < lower_bound(29, 29)  # why a level needs 29 cases
    assert lower_bound(0, 31) == 0.0
    assert lower_bound(30, 31) < lower_bound(31, 31)


def test_held_out_geometries_are_not_calibrated_and_enough_for_a_90_percent_bound():
    assert len(HELD_OUT) >= 29
    assert not [g for fam, g in HELD_OUT if g == CALIBRATION_GEOMETRY[fam]]
    assert len({(fam, tuple(sorted(g.items()))) for fam, g in HELD_OUT}) == len(HELD_OUT)


def test_committed_held_out_coverage_is_at_least_90_percent_at_every_level():
    """The committed record scores every level a check can stop at on the held-out cases: n, hits,
    the lower bound, every case's truth a closed form."""
    ho = json.loads(RECORD.read_text())["held_out"]
    assert set(ho["levels"]) == set(LEVELS)
    for level, g in ho["levels"].items():
        assert g["n"] == len(HELD_OUT) and g["hits"] == g["n"], (level, g["misses"])
        assert g["lower_bound_pct"] >= 90.0 and g["worst_error_over_band"] <= 1.0
    assert {c["source"] for c in ho["cases"]} == {"closed form"}


@pytest.mark.parametrize("i", [0, 14, 25])  # a Lamé tube, a plate with a hole, a beam
def test_held_out_cases_reproduce_the_record_and_are_covered(i):
    """Re-solved here at the coarse level (the band is widest relative to the error there), each case
    equals the record (same mesh) and its calibrated band covers the closed form."""
    fam, g = HELD_OUT[i]
    rec = next(c for c in json.loads(RECORD.read_text())["held_out"]["cases"]
               if c["level"] == "coarse" and c["case"] == fam and c["geometry"] == g)
    order, size, local = preset_mesh("coarse")
    c = closed_form_case(fam, order, size, local, g)
    assert (c["peak_mpa"], c["zz_error"]) == pytest.approx((rec["peak_mpa"], rec["zz_error"]), rel=1e-6)
    assert inside(c, BAND_FACTOR[order])


@pytest.mark.heavy
def test_every_held_out_case_is_covered_at_every_level():
    """The held-out study re-solved: the calibrated band covers every closed form at every level but
    fine, and at fine a tube, a plate and a beam (the whole fine level is the record's: 8 minutes here)."""
    coarser = [lvl for lvl in LEVELS if lvl != "fine"]
    ho = held_out(BAND_FACTOR, levels=coarser)
    assert {lvl: (g["hits"], g["n"]) for lvl, g in ho["levels"].items()} == {lvl: (len(HELD_OUT),) * 2 for lvl in coarser}
    fine = held_out(BAND_FACTOR, levels=("fine",), cases=[HELD_OUT[i] for i in (0, 14, 25)])
    assert fine["levels"]["fine"]["hits"] == 3
