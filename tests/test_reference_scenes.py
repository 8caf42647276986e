"""The reference scenes' verdicts and peaks stay where the committed reports put them (issue 26).

The rule (benchmarks/compare_reports.py ``band_problems``, the one home of it): for every part
case, the verdict is unchanged, and the new peak's band overlaps the committed one's, a band
being peak ± peak·error_pct/100 of its own report: |new − old| ≤ old·e_old + new·e_new.  A
faster mesh or solver may move a peak within what both reports claim, never a verdict.

Each check runs at the fidelity its committed report states.  The whole scenes are ``heavy``
(``pytest -m heavy tests/test_reference_scenes.py``); the default suite re-checks plate_A of
final-cm at draft against the committed standard report.
"""

import copy
import importlib
import json
import sys
from pathlib import Path

import pytest

from rigfem.pipeline import Output, Request, run_check

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmark scripts import each other as siblings
compare = importlib.import_module("compare_reports")
SCENES = ("final-cm", "final-nc", "final-nm", "slider-crank-300-840")


def committed(scene: str) -> dict:
    return json.loads((ROOT / "results" / scene / "report.json").read_text())


def test_band_rule_catches_a_moved_peak_and_a_changed_verdict():
    old = committed("final-cm")
    assert compare.band_problems(old, old) == []
    new = copy.deepcopy(old)
    p = new["parts"][0]
    p["peak_mpa"] *= 1 + 1.01 * (2 * p["error_pct"] / 100) / (1 - p["error_pct"] / 100)  # just outside both bands
    assert any("bands do not overlap" in b for b in compare.band_problems(old, new))
    p["peak_mpa"], new["parts"][1]["verdict"] = old["parts"][0]["peak_mpa"] * 1.01, "fail"
    assert compare.band_problems(old, new) == [f"{p['name']} cycle: verdict pass -> fail"]


def test_plate_a_draft_stays_in_the_committed_band(tmp_path):
    new = run_check(Request("final-cm", {"parts": ["plate_A"], "fidelity": "draft", "frames": 0}), Output(tmp_path / "o"))
    assert [p["name"] for p in new["parts"]] == ["plate_A", "plate_A"]
    assert compare.band_problems(committed("final-cm"), new) == []


@pytest.mark.heavy
@pytest.mark.parametrize("scene", SCENES)
def test_reference_scene_is_unchanged_within_its_bands(scene, tmp_path):
    old = committed(scene)
    new = run_check(Request(scene, {"fidelity": old["settings"]["fidelity"], "frames": 0}, bool(old["rule_violations"])), Output(tmp_path / "o"))
    assert len(new["parts"]) == len(old["parts"])
    assert compare.band_problems(old, new) == []
