"""Acceptance limits of the reference scenes: which parts pass, and utilisation bands.

A change to the code or to a part definition that makes the rig less safe (utilisation above
its band) or that silently drops a load (below its band) fails here.  The limits run at draft
fidelity with 72 crank angles (peaks are refined between samples) to keep the default test run
short; the bands (utilisation of σu/2, in %) are ±30 % around the draft values measured with
``rigfem check SCENE --fidelity draft --samples 72``, wide enough for the draft-vs-standard
discretisation difference (see results/convergence/).
"""

import pytest

from rigfem.check import run_check

FAST = {"fidelity": "draft", "samples": 72, "frames": 0}

#: scene -> (part, mode) -> utilisation band (%); every part must pass
LIMITS = {
    "final-cm": {("crank_rail", "original"): (13, 25), ("crank_rail", "cycle"): (11, 20),
                 ("coupler_rail", "original"): (10, 20), ("coupler_rail", "cycle"): (0.9, 1.9),
                 ("rocker_rail", "original"): (10, 20), ("rocker_rail", "cycle"): (0.6, 1.4),
                 ("plate_A", "original"): (1.5, 2.9), ("plate_A", "cycle"): (1.1, 2.1),
                 ("plate_B", "original"): (1.0, 2.0), ("plate_B", "cycle"): (0.7, 1.4),
                 ("post_B", "original"): (19, 36), ("post_B", "cycle"): (10, 18)},
    "final-nc": {("crank_rail", "original"): (22, 41), ("crank_rail", "cycle"): (19, 35),
                 ("coupler_rail", "original"): (15, 29), ("coupler_rail", "cycle"): (1.4, 2.8),
                 ("rocker_rail", "original"): (14, 27), ("rocker_rail", "cycle"): (1.0, 2.0),
                 ("plate_A", "original"): (2.3, 4.3), ("plate_A", "cycle"): (1.7, 3.1),
                 ("plate_B", "original"): (1.7, 3.1), ("plate_B", "cycle"): (1.2, 2.2),
                 ("post_B", "original"): (19, 36), ("post_B", "cycle"): (16, 30)},
    "final-nm": {("crank_rail", "original"): (22, 41), ("crank_rail", "cycle"): (19, 36),
                 ("coupler_rail", "original"): (22, 41), ("coupler_rail", "cycle"): (1.3, 2.5),
                 ("rocker_rail", "original"): (14, 26), ("rocker_rail", "cycle"): (1.0, 2.0),
                 ("plate_A", "original"): (2.4, 4.5), ("plate_A", "cycle"): (1.7, 3.2),
                 ("plate_B", "original"): (1.7, 3.2), ("plate_B", "cycle"): (1.2, 2.3),
                 ("post_B", "original"): (19, 36), ("post_B", "cycle"): (17, 31)},
    # the study never analysed a slider-crank: at 1 Hz its reactions are small (< 140 N)
    "slider-crank-300-840": {("crank_rail", "original"): (0.26, 0.50), ("crank_rail", "cycle"): (0.85, 1.6),
                             ("rod_rail", "original"): (0.18, 0.35), ("rod_rail", "cycle"): (0.16, 0.30),
                             ("plate_A", "original"): (0.33, 0.62), ("plate_A", "cycle"): (0.24, 0.45),
                             ("plate_B", "original"): (0.07, 0.14), ("plate_B", "cycle"): (0.05, 0.10)},
}


@pytest.mark.parametrize("scene", sorted(LIMITS))
def test_reference_scene_limits(scene, tmp_path):
    r = run_check(scene, out=tmp_path / scene, overrides=FAST, quiet=True)
    got = {(p["name"], p["mode"]): p for p in r["parts"]}
    assert set(got) == set(LIMITS[scene])
    assert r["verdict"] == "pass"
    for key, (lo, hi) in LIMITS[scene].items():
        u = got[key]["utilisation_pct"]
        assert got[key]["verdict"] == "pass", key
        assert lo <= u <= hi, f"{scene} {key}: utilisation {u:.2f} % outside [{lo}, {hi}] %"
