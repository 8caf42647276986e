"""The report dict: no NaN or infinity ever reaches it; verdicts combine as documented."""

import json

import numpy as np
import pytest

from rigfem.report import finite, render_markdown, write_json
from rigfem.verdict import overall


def test_finite_refuses_nan_and_inf_and_names_the_field():
    assert finite({"a": np.float64(1.5), "b": [np.int64(2)]}) == {"a": 1.5, "b": [2]}
    with pytest.raises(ValueError, match=r"report.parts\[0\].peak_mpa is nan"):
        finite({"parts": [{"peak_mpa": float("nan")}]})
    with pytest.raises(ValueError, match="inf"):
        finite({"x": np.array([1.0, np.inf])})


def test_overall_verdict():
    assert overall([{"verdict": "pass"}, {"verdict": "pass"}]) == "pass"
    assert overall([{"verdict": "pass"}, {"verdict": "undecided"}]) == "undecided"
    assert overall([{"verdict": "undecided"}, {"verdict": "fail"}]) == "fail"


def _report():
    part = {"name": "crank_rail", "part": "rail_size25", "mode": "original", "peak_mpa": 123.4,
            "crank_deg": 16.6, "surface": "hole_02", "location_mm": [80.0, 3.5, 12.0], "error_pct": 2.0,
            "utilisation_pct": 32.9, "verdict": "pass", "fatigue": None, "notes": ["held by its pivot"]}
    return {"scene": "demo", "description": "", "verdict": "pass", "stress_verdict": "pass",
            "standing": "assembles; meets the rig rules; passes the stress criterion", "limit_mpa": 375.0,
            "configuration": {"type": "four-bar", "lengths_mm": {"b2": 480.0}, "speed_hz": 1.0,
                              "model": "rigid-body", "samples": 360},
            "transmission_angle_deg": {"min": 40.0, "max": 140.0}, "singular": None,
            "rules": [{"name": "grashof", "value": 1.0, "limit": 0.0, "ok": True}],
            "peaks": {"A": {"force_N": 430.2, "crank_deg": 16.6}},
            "torque_Nm": {"peak": 150.0, "crank_deg": 20.0},
            "settings": {"modes": ["original"], "limit_factor": 0.5, "material": "rig_steel", "sigma_u_mpa": 750.0,
                         "fidelity": "standard", "order": 2, "size_mm": 6.0, "local_size_mm": 1.2},
            "parts": [part]}


def test_markdown_and_json(tmp_path):
    r = _report()
    md = render_markdown(r)
    assert ("| crank_rail (rail_size25) | original | 123.4 | 32.9 | ±2.5 | ±0.7 | ±2.0 | **PASS** | 3.04 | 16.6 | "
            "hole_02 (80.0, 3.5, 12.0) | – | – |") in md
    assert "Overall verdict: PASS" in md
    write_json(r, tmp_path / "r.json")
    assert json.loads((tmp_path / "r.json").read_text())["parts"][0]["peak_mpa"] == 123.4


@pytest.fixture(scope="module")
def two_plates(tmp_path_factory):
    """A draft check of two parts whose peaks differ (plate_A, post_B), original mode only."""
    from rigfem.pipeline import Output, Request, run_check

    out = tmp_path_factory.mktemp("tables") / "final-cm"
    report = run_check(Request("final-cm", {
        "fidelity": "draft", "parts": ["plate_A", "post_B"], "modes": ["original"], "frames": 0}), Output(out))
    return report, out


def test_report_json_has_material_mesh_and_balance_tables(two_plates):
    report, out = two_plates
    assert report["schema"] == 7 and report["configuration"]["branch"] == "open"
    mat = {m["property"]: m for m in report["material"]}
    assert set(mat) == {"E", "nu", "sigma_u", "sigma_y", "density"}
    assert mat["E"]["value"] == 210000.0 and mat["density"]["value"] == pytest.approx(7850.0)
    assert all(m["source"] and m["unit"] for m in mat.values())
    assert "geometry/RIG.md §5" in mat["sigma_u"]["source"]
    for p in report["parts"]:
        m = p["mesh"]
        assert m["element"].startswith("tetrahedron, 10-node") and m["fe_nodes"] > m["nodes"] > 0
        assert 0 < m["size_at_peak_mm"] < 20 and 0 < m["quality_min"] <= 1
        b = p["balance"]
        applied = np.linalg.norm(b["applied_N"])
        assert applied > 100  # the pin loads of the original mode
        assert np.allclose(b["applied_N"], -np.asarray(b["supports_N"]), atol=1e-3 * applied)
        assert np.allclose(b["applied_Nmm"], -np.asarray(b["supports_Nmm"]), atol=1e-3 * applied * 100)
        assert b["residual_N"] < 1e-3 * applied and b["supports"]
    md = (out / "report.md").read_text()
    for head in ("## Material: rig\\_steel", "## Mesh per part", "## Free-body balance per part"):
        assert head in md


def test_a_small_peak_reads_its_band_in_mpa_and_in_percent_of_the_allowable():
    """A plate at 2.2 % of the allowable with ±43.7 % of its peak: the band is ±3.5 MPa = ±1.0 % of the
    allowable, and the Markdown says so beside the % of the peak (issue 40 §2)."""
    r = _report()
    from rigfem.report.document import verdict_table

    r["parts"][0].update(peak_mpa=8.1, utilisation_pct=2.16, error_pct=43.7, mesh={"stopped": "reached the cap"})
    md = "\n".join(verdict_table(r))
    assert "| 8.1 | 2.2 | ±3.5 | ±0.9 | ±43.7 | **PASS** |" in md and "| reached the cap |" in md
    assert "band ± (MPa) | band ± (% of allowable) | band ± (% of peak)" in md


def test_band_in_mpa_is_in_every_entry_the_tables_and_the_pictures(two_plates):
    from rigfem.cli.check import _summary
    from rigfem.report.pictures import band_lines

    report, out = two_plates
    md, html, summary = (out / "report.md").read_text(), (out / "report.html").read_text(), _summary(report)
    for p in report["parts"]:
        assert p["band_mpa"] == pytest.approx(p["peak_mpa"] * p["error_pct"] / 100, rel=1e-12)
        assert p["band_pct_of_allowable"] == pytest.approx(p["utilisation_pct"] * p["error_pct"] / 100, rel=1e-12)
        assert p["band_pct_of_allowable"] == pytest.approx(100 * p["band_mpa"] / report["limit_mpa"], rel=1e-9)
        cells = f"| ±{p['band_mpa']:.1f} | ±{p['band_pct_of_allowable']:.1f} | ±{p['error_pct']:.1f} |"
        assert cells in md, cells
        assert (f"±{p['band_mpa']:.1f} MPa</span><br><span class=note>±{p['band_pct_of_allowable']:.1f} % of "
                f"allowable, ±{p['error_pct']:.1f} % of peak") in html
        assert p["mesh"]["stopped"] and p["mesh"]["stopped"] in md and p["mesh"]["stopped"] in html
        row = next(x for x in summary.splitlines() if x.startswith(p["name"]))
        assert f"{p['band_mpa']:.1f}" in row.split() and f"{p['band_pct_of_allowable']:.1f}" in row.split()
        assert p["mesh"]["stopped"] in row
        caption = " ".join(band_lines(p, "allowable"))
        assert f"±{p['band_mpa']:.1f} MPa = ±{p['band_pct_of_allowable']:.1f} % of the allowable" in caption
    assert report["conclusion"]["band_mpa"] == pytest.approx(
        report["conclusion"]["peak_mpa"] * report["conclusion"]["error_pct"] / 100)


def test_every_file_named_in_the_report_exists(two_plates):
    report, out = two_plates
    assert report["files"] and report["field_files"]
    assert not [f for f in report["files"] if f.endswith((".vtu", ".pvd", ".inp"))]  # not kept: never linked
    for f in report["files"] + report["field_files"]:
        assert (out / f).is_file(), f
    for p in report["parts"]:
        for f in p["pictures"]["files"].values():
            assert f in report["files"]
    md = (out / "report.md").read_text()
    import re

    for link in re.findall(r"\]\(([^)]+)\)", md):
        assert (out / link).is_file(), link


def test_every_part_picture_uses_one_colour_scale(two_plates):
    from rigfem.report.pictures import UTILISATION_SCALE_PCT

    report, _ = two_plates
    pics = [p["pictures"] for p in report["parts"]]
    peaks = [p["peak_mpa"] for p in report["parts"]]
    assert len(pics) == 2 and peaks[1] > 2 * peaks[0]  # very different peaks ...
    assert pics[0]["utilisation_scale_mpa"] == pics[1]["utilisation_scale_mpa"] == [0.0, report["limit_mpa"]]
    assert pics[0]["utilisation_scale_pct"] == pics[1]["utilisation_scale_pct"] == list(UTILISATION_SCALE_PCT)
    assert {"von_mises", "displacement", "safety_factor"} == set(pics[0]["files"])


def test_linkage_gif_is_at_least_800_px_wide(tmp_path):
    from PIL import Image

    from rigfem.linkage.kinematics import fourbar_motion
    from rigfem.report.motion import motion_gif

    m = fourbar_motion(480.0, 840.0, 780.0, 1020.0, np.linspace(0, 360, 4, endpoint=False))
    path = motion_gif(m, tmp_path / "turn.gif", "rig four-bar")
    with Image.open(path) as img:
        assert img.size[0] >= 800 and img.n_frames == 4
