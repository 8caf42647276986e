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
    return {"scene": "demo", "description": "", "verdict": "pass", "limit_mpa": 375.0,
            "configuration": {"type": "four-bar", "lengths_mm": {"b2": 480.0}, "speed_hz": 1.0,
                              "model": "rigid-body", "samples": 360},
            "transmission_angle_deg": {"min": 40.0, "max": 140.0}, "singular": None,
            "rules": [{"name": "grashof", "value": 1.0, "limit": 0.0, "ok": True}],
            "peaks": {"A": {"force_N": 430.2, "crank_deg": 16.6}},
            "torque_Nm": {"peak": 150.0, "crank_deg": 20.0},
            "settings": {"modes": ["original"], "limit_factor": 0.5, "material": "rig_steel",
                         "fidelity": "standard", "order": 2, "size_mm": 6.0, "local_size_mm": 1.2},
            "parts": [part]}


def test_markdown_and_json(tmp_path):
    r = _report()
    md = render_markdown(r)
    assert "| crank_rail (rail_size25) | 123.4 | 16.6 | hole_02 (80.0, 3.5, 12.0) | ±2.0 % | 32.9 % | **pass** | – |" in md
    assert "Overall verdict: PASS" in md
    write_json(r, tmp_path / "r.json")
    assert json.loads((tmp_path / "r.json").read_text())["parts"][0]["peak_mpa"] == 123.4
