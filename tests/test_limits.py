"""Acceptance limits of the reference scenes: which parts pass, and utilisation bands.

A change to the code or to a part definition that makes the rig less safe (utilisation above
its band) or that silently drops a load (below its band) fails here.  The limits run at draft
fidelity with 72 crank angles (peaks are refined between samples) to keep the default test run
short; the bands (utilisation of σu/2, in %) are ±30 % around the draft values measured with
``rigfem check SCENE --fidelity draft --samples 72``, wide enough for the draft-vs-standard
discretisation difference (see results/convergence/).
"""

import pytest

from rigfem.pipeline import Output, Request, run_check

FAST = {"fidelity": "draft", "samples": 72, "frames": 0}

#: scene -> (part, mode) -> utilisation band (%); every part must pass
LIMITS = {
    "final-cm": {("crank_rail", "original"): (27, 50), ("crank_rail", "cycle"): (21, 39),
                 ("coupler_rail", "original"): (21, 39), ("coupler_rail", "cycle"): (1.4, 2.7),
                 ("rocker_rail", "original"): (20, 37), ("rocker_rail", "cycle"): (1.2, 2.3),
                 ("plate_A", "original"): (1.7, 3.2), ("plate_A", "cycle"): (1.2, 2.3),
                 ("plate_B", "original"): (1.1, 2), ("plate_B", "cycle"): (0.77, 1.4),
                 ("post_B", "original"): (23, 42), ("post_B", "cycle"): (11, 20)},
    "final-nc": {("crank_rail", "original"): (45, 83), ("crank_rail", "cycle"): (37, 69),
                 ("coupler_rail", "original"): (30, 56), ("coupler_rail", "cycle"): (2.1, 3.9),
                 ("rocker_rail", "original"): (27, 51), ("rocker_rail", "cycle"): (1.7, 3.2),
                 ("plate_A", "original"): (2.6, 4.8), ("plate_A", "cycle"): (1.8, 3.4),
                 ("plate_B", "original"): (1.7, 3.2), ("plate_B", "cycle"): (1.2, 2.3),
                 ("post_B", "original"): (23, 42), ("post_B", "cycle"): (17, 32)},
    "final-nm": {("crank_rail", "original"): (45, 83), ("crank_rail", "cycle"): (38, 71),
                 ("coupler_rail", "original"): (45, 84), ("coupler_rail", "cycle"): (2.2, 4),
                 ("rocker_rail", "original"): (26, 48), ("rocker_rail", "cycle"): (1.7, 3.2),
                 ("plate_A", "original"): (2.7, 5.1), ("plate_A", "cycle"): (1.9, 3.5),
                 ("plate_B", "original"): (1.9, 3.4), ("plate_B", "cycle"): (1.3, 2.4),
                 ("post_B", "original"): (23, 42), ("post_B", "cycle"): (19, 35)},
    # the study never analysed a slider-crank: at 1 Hz its reactions are small (< 140 N)
    "slider-crank-300-840": {("crank_rail", "original"): (0.36, 0.66), ("crank_rail", "cycle"): (1.7, 3.2),
                             ("rod_rail", "original"): (0.66, 1.2), ("rod_rail", "cycle"): (0.35, 0.65),
                             ("plate_A", "original"): (0.37, 0.68), ("plate_A", "cycle"): (0.26, 0.48),
                             ("plate_B", "original"): (0.082, 0.15), ("plate_B", "cycle"): (0.059, 0.11)},
}


@pytest.mark.parametrize("scene", sorted(LIMITS))
def test_reference_scene_limits(scene, tmp_path):
    # final-nc and final-nm break rig rules (transmission angle, hole grid): checked on request only
    r = run_check(Request(scene, FAST, True), Output(tmp_path / scene))
    assert bool(r["rule_violations"]) == (scene in ("final-nc", "final-nm"))
    got = {(p["name"], p["mode"]): p for p in r["parts"]}
    assert set(got) == set(LIMITS[scene])
    assert r["verdict"] == ("fail" if r["rule_violations"] else "pass")  # not mountable: never a pass
    for key, (lo, hi) in LIMITS[scene].items():
        u = got[key]["utilisation_pct"]
        assert got[key]["verdict"] == "pass", key
        assert lo <= u <= hi, f"{scene} {key}: utilisation {u:.2f} % outside [{lo}, {hi}] %"
