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
    "final-cm": {("crank_rail", "original"): (24, 45), ("crank_rail", "cycle"): (20, 37),
                 ("coupler_rail", "original"): (20, 36), ("coupler_rail", "cycle"): (1.3, 2.5),
                 ("rocker_rail", "original"): (18, 34), ("rocker_rail", "cycle"): (1.1, 2.1),
                 ("plate_A", "original"): (1.7, 3.2), ("plate_A", "cycle"): (1.2, 2.3),
                 ("plate_B", "original"): (1.1, 2.0), ("plate_B", "cycle"): (0.77, 1.4),
                 ("post_B", "original"): (22, 41), ("post_B", "cycle"): (11, 20)},
    "final-nc": {("crank_rail", "original"): (41, 75), ("crank_rail", "cycle"): (35, 64),
                 ("coupler_rail", "original"): (28, 52), ("coupler_rail", "cycle"): (1.9, 3.5),
                 ("rocker_rail", "original"): (25, 47), ("rocker_rail", "cycle"): (1.6, 2.9),
                 ("plate_A", "original"): (2.6, 4.7), ("plate_A", "cycle"): (1.8, 3.4),
                 ("plate_B", "original"): (1.7, 3.2), ("plate_B", "cycle"): (1.2, 2.3),
                 ("post_B", "original"): (22, 41), ("post_B", "cycle"): (17, 32)},
    "final-nm": {("crank_rail", "original"): (40, 75), ("crank_rail", "cycle"): (36, 67),
                 ("coupler_rail", "original"): (41, 76), ("coupler_rail", "cycle"): (2.0, 3.6),
                 ("rocker_rail", "original"): (24, 45), ("rocker_rail", "cycle"): (1.6, 2.9),
                 ("plate_A", "original"): (2.7, 5.0), ("plate_A", "cycle"): (1.9, 3.5),
                 ("plate_B", "original"): (1.8, 3.4), ("plate_B", "cycle"): (1.3, 2.4),
                 ("post_B", "original"): (22, 41), ("post_B", "cycle"): (18, 34)},
    # the study never analysed a slider-crank: at 1 Hz its reactions are small (< 140 N)
    "slider-crank-300-840": {("crank_rail", "original"): (0.35, 0.64), ("crank_rail", "cycle"): (1.6, 3.0),
                             ("rod_rail", "original"): (0.61, 1.1), ("rod_rail", "cycle"): (0.32, 0.59),
                             ("plate_A", "original"): (0.36, 0.68), ("plate_A", "cycle"): (0.26, 0.48),
                             ("plate_B", "original"): (0.081, 0.15), ("plate_B", "cycle"): (0.059, 0.11)},
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
