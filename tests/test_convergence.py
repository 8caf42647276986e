"""Convergence study: Richardson extrapolation (exact on synthetic sequences), singular flag,
a real coarse h sequence on the coupling plate, CLI refusals."""

import json
import math

import numpy as np
import pytest

from rigfem.cli import main
from rigfem.errors import ComputeError
from rigfem.cache import from_environment
from rigfem.job import Request
from rigfem.verification.convergence import (
    StepSpec,
    StudySpec,
    analyse,
    away_from_singular_edges,
    fine_step,
    needs_finer,
    richardson,
    run_step,
    scene_cases,
    study,
    to_json,
)
from said import one_line


@pytest.mark.parametrize("h", [[1.6, 0.8, 0.4, 0.2], [2.4, 1.7, 1.2, 0.85, 0.6], [2.0, 1.3, 0.7]])
@pytest.mark.parametrize("p", [1.0, 1.5, 2.0])
def test_richardson_exact_on_known_order_and_limit(h, p):
    ex = richardson(h, [250.0 - 7.0 * x ** p for x in h])
    assert ex.converging and ex.status == "converged" and ex.order == pytest.approx(p, abs=1e-9)
    assert ex.limit == pytest.approx(250.0, abs=1e-9)
    assert ex.asymptotic == (len(h) >= 4)
    assert all(o == pytest.approx(p, abs=1e-9) for o in ex.orders)


@pytest.mark.parametrize("q", [[100 * x ** -0.45 for x in (1.6, 0.8, 0.4, 0.2)],  # re-entrant corner
                               [100.0, 110.0, 120.0, 130.0]])  # log-like growth, equal differences
def test_singular_sequence_is_flagged_not_converged(q):
    ex = richardson([1.6, 0.8, 0.4, 0.2], q)
    assert not ex.converging and ex.limit is None and ex.order is None
    assert "singular" in ex.note
    assert "NaN" not in json.dumps(ex.as_dict())


def test_oscillating_sequence_has_no_richardson_limit():
    ex = richardson([1.6, 0.8, 0.4], [100.0, 110.0, 105.0])
    assert ex.converging and ex.order is None and ex.limit == 105.0 and ex.status == "oscillating"
    assert ex.gci == pytest.approx(5.0 / 105.0)


def test_noise_limited_only_when_small_and_not_growing():
    h = [1.6, 0.8, 0.4, 0.2]
    ex = richardson(h, [94.0, 99.7, 99.5, 99.2])  # falls by 0.2 % then 0.3 %: remeshing noise
    assert ex.converging and ex.status == "noise-limited" and ex.limit == 99.2 and ex.order is None
    assert ex.gci == pytest.approx(1.25 * 0.3 / 99.2)
    ex = richardson(h, [99.0, 99.2, 99.4, 99.7])  # rises level after level: never noise
    assert not ex.converging and ex.status == "not converging"
    ex = richardson(h, [90.0, 99.0, 97.0, 99.5])  # changes above 1 %
    assert not ex.converging


def test_richardson_refuses_bad_sequences():
    with pytest.raises(ComputeError, match="at least 3"):
        richardson([1.0, 0.5], [1.0, 2.0])
    with pytest.raises(ComputeError, match="decreasing"):
        richardson([0.5, 1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(ComputeError, match="finite"):
        richardson([1.0, 0.5, 0.25], [1.0, math.nan, 2.0])


@pytest.mark.heavy  # ~20 s alone, ~85 s on the shared 2-core machine
def test_real_coarse_h_sequence_on_the_plate_converges():
    """The plate's peak (screw-hole rim, original mode) on three coarse sqrt(2) levels ending at
    8/1.2 mm: it must converge to the reference of the full study (9.23 MPa at 4/0.6 mm, 297k
    DOF, results/convergence/plate_A.md) within the study's stated uncertainty."""
    job, by = scene_cases(Request("final-cm", {"parts": ["plate_A"], "modes": ["original"]}), from_environment())
    res = study(by["plate_A"], job.settings, StudySpec(levels=3, isolate=False, presets=False, finest=(8.0, 1.2)))
    steps = res["steps"]
    assert [s["label"] for s in steps] == ["h0", "h1", "h2"]
    assert steps[0]["dofs"] < steps[1]["dofs"] < steps[2]["dofs"]
    assert all(s["seconds"] > 0 and s["peak_rss_mib"] is None for s in steps)
    a = res["modes"]["original"]["peak_mpa"]
    ex = a["extrapolation"]
    assert ex["converging"] and ex["gci"] < 0.03, ex
    assert ex["limit"] == pytest.approx(9.23, rel=0.02)
    assert steps[-1]["modes"]["original"]["surface"].startswith("screw_")
    json.loads(to_json(res))


@pytest.mark.heavy  # a spawned process importing the FE stack: ~8 s alone, ~45 s on the busy machine
def test_isolated_step_measures_time_memory_and_a_finite_peak():
    """One coarse plate step in a spawned process: its own peak RSS above the post-import RSS."""
    job, by = scene_cases(Request("final-cm", {"parts": ["plate_A"], "modes": ["cycle"]}), from_environment())
    settings = job.settings
    spec = StepSpec("coarse", "h", 2, 30.0, 6.0, 8)
    r = run_step(by["plate_A"](8), settings, spec)
    assert r["peak_rss_mib"] > r["base_rss_mib"] > 0 and r["seconds"] > 0 and r["dofs"] > 1000
    assert 3.0 < r["modes"]["cycle"]["peak_mpa"] < 9.0  # 6.62 MPa converged; coarse is lower


@pytest.mark.parametrize("argv, msg", [
    (["plate_A", "--levels", "2"], "--levels"),
    (["plate_A", "--levels", "4.5"], "--levels"),
    (["plate_A", "--mode", "static"], "--mode"),
    (["plate_A", "--ratio", "5"], "--ratio"),
    (["plate_A", "--max-gib", "nan"], "--max-gib"),
    (["plate_A", "--extra-levels", "4"], "--extra-levels"),
    (["plate_A", "--extra-levels", "0.5"], "--extra-levels"),
    (["no-such-scene"], "no-such-scene"),
])
def test_cli_bad_input_is_one_line_exit_2(argv, msg, capsys, tmp_path):
    assert main(["convergence", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert one_line(err).startswith("rigfem: error:") and msg in err


def _synthetic_study(peaks: dict[str, list[float]]) -> dict:
    """A study dict as rigfem.verification.convergence writes it, from given h-sequence peaks per mode."""
    sizes = [(11.3, 1.7), (8.0, 1.2), (5.66, 0.85), (4.0, 0.6)]
    steps = [{"label": f"h{k}", "kind": "h", "order": 2, "size_mm": g, "local_size_mm": loc,
              "bearing_directions": 24, "dofs": 10000 * 3 ** k, "tets": 1000 * 3 ** k, "seconds": 2.0 ** k,
              "cpu_seconds": 1.5 * 2.0 ** k, "peak_rss_mib": 300.0 + k, "base_rss_mib": 250.0, "load_avg": 1.0,
              "modes": {m: {"peak_mpa": q[k], "crank_deg": 0.0, "surface": "hole_00", "xyz": [0.0, 0.0, 0.0],
                            "zz_error": 0.1} for m, q in peaks.items()}}
             for k, (g, loc) in enumerate(sizes)]
    steps.append(dict(steps[1], label="standard", kind="preset", bearing_directions=12))
    return {"part": "crank_rail", "part_def": "rail_size25", "params": {"length": 700.0}, "ratio": 2 ** 0.5,
            "h_directions": 24, "fine_is_finest": True, "steps": steps, "refused": [], "scene": "final-cm",
            "command": "rigfem convergence crank_rail"}


def test_render_tables_plot_and_summary(tmp_path, capsys):
    h = [1.7, 1.2, 0.85, 0.6]
    res = _synthetic_study({"original": [100 - 8 * x ** 2 for x in h],  # converges, order 2, limit 100
                            "cycle": [50 * x ** -0.45 for x in h]})  # singular
    (tmp_path / "crank_rail.json").write_text(json.dumps(res))
    (tmp_path / ".rigfem-result").write_text("")   # --render rewrites only a folder rigfem wrote
    assert main(["convergence", "--render", "--out", str(tmp_path)]) == 0
    md = (tmp_path / "crank_rail.md").read_text()
    assert "extrapolated **100.00 MPa**, observed order 2.00" in md and "**NOT CONVERGING**" in md
    summary = (tmp_path / "summary.md").read_text()
    assert "| crank_rail | cycle | **not converging**" in summary and "n/a (singular)" in summary
    std = 100 - 8 * 1.2 ** 2
    assert f"| {std:.2f} | {100 * (std / 100 - 1):+.2f} % | **no** |" in summary  # -11.5 %: misses 3 %
    assert (tmp_path / "crank_rail.png").stat().st_size > 10_000
    assert "nan" not in (tmp_path / "crank_rail.json").read_text().lower()


def test_away_mask_only_for_sharp_web_flange_corners():
    """The filleted post has no singular edge (None); with fillet_radius = 0 only points near the
    four re-entrant corners are excluded, not the base (a normal-only support is not singular)."""
    pts = np.array([[20.0, 3.5, 8.5], [20.0, -3.5, 51.5], [20.0, 0.0, 1.0], [20.0, 20.0, 4.0], [20.0, 0.0, 30.0]])
    assert away_from_singular_edges("PF_4b_003_v2", {}, pts) is None
    mask = away_from_singular_edges("PF_4b_003_v2", {"fillet_radius": 0.0}, pts)
    assert mask.tolist() == [False, False, True, True, True]
    assert away_from_singular_edges("PF_4b_006", {}, pts) is None


def test_a_finer_level_is_asked_for_only_while_not_converging():
    h = [1.7, 1.2, 0.85, 0.6]
    assert not needs_finer(analyse(_synthetic_study({"original": [100 - 8 * x ** 2 for x in h]})))
    assert needs_finer(analyse(_synthetic_study({"original": [100 - 8 * x ** 2 for x in h],
                                                 "cycle": [50 * x ** -0.45 for x in h]})))


def test_fine_preset_error_is_measured_against_an_extended_sequence():
    """With a fifth level beyond `fine`, the fine preset is the 4.0/0.6 mm level, not the finest,
    and its error is taken against the extrapolated limit."""
    h = [1.7, 1.2, 0.85, 0.6, 0.6 / 2 ** 0.5]
    res = _synthetic_study({"original": [100 - 8 * x ** 2 for x in h[:4]]})
    extra = dict(res["steps"][3], label="h4", size_mm=4.0 / 2 ** 0.5, local_size_mm=h[4],
                 modes={"original": dict(res["steps"][3]["modes"]["original"], peak_mpa=100 - 8 * h[4] ** 2)})
    res["steps"].insert(4, extra)
    assert fine_step([s for s in res["steps"] if s["kind"] == "h"])["label"] == "h3"
    fine = analyse(res)["modes"]["original"]["peak_mpa"]["presets"]["fine"]
    assert fine["step"] == "h3" and fine["error"] == pytest.approx(-8 * 0.36 / 100, rel=1e-6)


def test_levels_beyond_the_finest_continue_the_ratio():
    """The levels a non-converging study may add are the sequence continued past ``finest``."""
    from rigfem.verification import h_levels

    base = h_levels(4, 2 ** 0.5, (4.0, 0.6))
    more = h_levels(4, 2 ** 0.5, (4.0, 0.6), beyond=1)
    assert more[:4] == base and more[3].size_mm == pytest.approx(4.0)
    assert (more[4].label, more[4].size_mm, more[4].local_size_mm) == ("h4", pytest.approx(4.0 / 2 ** 0.5),
                                                                       pytest.approx(0.6 / 2 ** 0.5))
