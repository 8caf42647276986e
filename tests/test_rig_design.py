"""From a synthesised four-bar to rig configurations (rigfem.design.rig_design and
``rigfem synthesize --rig``): every candidate buildable, its error re-measured independently
by the general planar solver, the ranking right, the stress verdict the sweep's."""

import numpy as np
import pytest

from rigfem.cli import main
from rigfem.dynamics import solve
from rigfem.linkage import four_bar
from rigfem.linkage.mechanisms import build
from rigfem.linkage.synthesis import check_three_position, synthesize_function, three_position
from rigfem.scene import load_scene
from rigfem.sweep import SweepParams, build_bases, evaluate
from rigfem.design.rig_design import _function_error, rig_fourbars, snap_function, snap_motion, stress_verdicts
from said import one_line

FUNCTION = ("x*log(x)", 1.0, 3.0, 20.0, 60.0, 80.0, 45.0, 2.0)


def _angles(lk, crank_deg):
    """Rocker angle and coupler pose by the general solver (independent of the closed forms)."""
    order = np.argsort(crank_deg)
    h = solve(lk, np.asarray(crank_deg, float)[order], general=True)
    inv = np.argsort(order)
    return {n: (b.angle_rad[inv], b.origin_mm[inv]) for n, b in h.bodies.items()}


@pytest.fixture(scope="module")
def function_design():
    r = synthesize_function(*FUNCTION)
    return r, snap_function(r, top=4)


def test_function_candidates_are_buildable_ranked_and_re_measured(function_design):
    r, cands = function_design
    allowed = {tuple(x) for x in rig_fourbars()}
    assert len(cands) == 4 and [c["error"] for c in cands] == sorted(c["error"] for c in cands)
    (x0, x1), (y0, y1) = r["x_range"], r["y_range"]
    xs = np.linspace(x0, x1, 241)
    rel_in = (xs - x0) / (x1 - x0) * r["input_deg"]["range"]
    want = (xs * np.log(xs) - y0) / (y1 - y0) * r["output_deg"]["range"]
    for c in cands:
        L = c["lengths_mm"]
        assert tuple(L.values()) in allowed and all(rule["ok"] for rule in c["rules"])
        rocker = _angles(four_bar(**L, branch=c["branch"], masses=None), c["input_start_deg"] + rel_in)["rocker"][0]
        turn = np.degrees(np.unwrap(rocker - rocker[0]))
        err = np.abs(turn - want).max() / abs(r["output_deg"]["range"]) * (y1 - y0)
        assert c["error"] == pytest.approx(err, rel=1e-6, abs=1e-9)
        assert c["output_start_deg"] == pytest.approx(np.degrees(rocker[0]) % 360, abs=1e-6)


@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
def test_function_best_beats_every_other_rig_fourbar_sampled(function_design):
    """Brute force on a random sample of rig four-bars (input start on a 0.25 deg grid)."""
    r, cands = function_design
    L = rig_fourbars()
    rng = np.random.default_rng(1)
    pick = L[rng.choice(len(L), 40, replace=False)]
    xs = np.linspace(r["x_range"][0], r["x_range"][1], 241)
    rel_in = (xs - xs[0]) / (xs[-1] - xs[0]) * r["input_deg"]["range"]
    y = xs * np.log(xs)
    rel_out = (y - y[0]) / (y[-1] - y[0]) * r["output_deg"]["range"]
    starts = np.broadcast_to(np.arange(0, 360, 0.25), (len(pick), 1440))
    for sgn in (1, -1):
        err, _ = _function_error(pick, sgn, starts, rel_in, rel_out)
        best_deg = err.min(axis=1).min()
        assert cands[0]["error"] <= best_deg / abs(r["output_deg"]["range"]) * (y[-1] - y[0]) + 1e-9


def test_motion_candidates_reach_the_positions():
    P = [(0.0, 0.0), (-15.12, -9.0), (-29.128, -4.0)]
    r = three_position(P, [-20.0, -35.0], [100.0, 200.0], [30.0, 55.0])
    r.update(check_three_position(r))
    cands = snap_motion(r, top=3, scale=30.0)
    assert cands and all(c["scale"] == 30.0 for c in cands)
    allowed = {tuple(x) for x in rig_fourbars()}
    th = np.radians(r["ground_angle_deg"])
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    for c in cands:
        assert tuple(c["lengths_mm"].values()) in allowed
        cp = c["coupler_point"]
        pose = _angles(four_bar(**c["lengths_mm"], branch=c["branch"], masses=None), c["crank_deg"])["coupler"]
        ang = pose[0] + np.radians(cp["angle_deg"])
        local = pose[1] + cp["distance_mm"] * np.stack([np.cos(ang), np.sin(ang)], -1)
        got = 30.0 * np.asarray(r["O2"]) + local @ R.T
        dist = np.linalg.norm(got - 30.0 * np.asarray(P), axis=1)
        assert dist.max() == pytest.approx(c["error_mm"], rel=1e-6, abs=1e-6)
        span = max(np.hypot(*np.subtract(a, b)) for a in P for b in P)
        assert c["error_pct"] == pytest.approx(100 * c["error_mm"] / (30.0 * span), rel=1e-9)


def test_the_motion_fit_uses_the_linkages_own_jacobian(monkeypatch):
    """The coupler-point fit's Jacobian comes from the linkage's velocities, not from finite
    differences: it equals central differences of the residual, and the fits are those that
    scipy's finite-difference Jacobian finds."""
    import scipy.optimize as so

    P = [(0.0, 0.0), (-15.12, -9.0), (-29.128, -4.0)]
    r = three_position(P, [-20.0, -35.0], [100.0, 200.0], [30.0, 55.0])
    r.update(check_three_position(r))
    least_squares, seen = so.least_squares, []

    def spy(fun, x0, jac=None, **kw):
        seen.append((fun, jac, np.asarray(x0, float)))
        return least_squares(fun, x0, jac=jac, **kw)

    monkeypatch.setattr(so, "least_squares", spy)
    fast = snap_motion(r, top=3, scale=30.0)
    fun, jac, x0 = seen[0]
    x = x0 + 0.3
    h = 1e-4
    central = np.column_stack([(fun(x + h * e) - fun(x - h * e)) / (2 * h) for e in np.eye(len(x))])
    assert np.abs(jac(x) - central).max() < 1e-6 * np.abs(central).max()
    monkeypatch.setattr(so, "least_squares", lambda fun, x0, jac=None, **kw: least_squares(fun, x0, **kw))
    slow = snap_motion(r, top=3, scale=30.0)
    assert [(c["lengths_mm"], c["branch"]) for c in fast] == [(c["lengths_mm"], c["branch"]) for c in slow]
    for a, b in zip(fast, slow):
        assert a["error_mm"] == pytest.approx(b["error_mm"], rel=1e-5, abs=1e-6)


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_stress_verdicts_are_the_sweeps_on_the_candidates_branch():
    from test_sweep import CHECK  # the coarse sweep meshes of the default tests

    p = SweepParams(check=CHECK)
    cands = [{"lengths_mm": dict(b2=480.0, b3=840.0, b4=780.0, d=1020.0), "branch": b} for b in ("open", "crossed")]
    stress_verdicts(cands, p)
    bases = build_bases(p)
    for c in cands:
        row = evaluate(dict(c["lengths_mm"], branch=c["branch"]), p, bases)
        assert c["stress"]["verdict"] == row["verdict"] == "pass"
        assert c["stress"]["max_util_pct"] == row["max_util_pct"]
    # the crossed assembly is the open one mirrored about the ground line and turned the other
    # way; at constant crank speed the inertia loads, hence the peaks, are the same
    assert cands[0]["stress"]["peak_torque_Nm"] == pytest.approx(cands[1]["stress"]["peak_torque_Nm"], rel=1e-9)


def test_cli_writes_a_checkable_scene_and_refuses_bad_options(tmp_path, capsys):
    scene = tmp_path / "best.toml"
    args = ["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "60", "--output", "80", "45",
            "--ground", "2"]
    assert main([*args, "--rig", "--no-stress", "--top", "2", "--scene-out", str(scene)]) == 0
    out = capsys.readouterr().out
    assert "nearest buildable rig configurations" in out and out.count("on the hole grid (whole 60 mm") == 2
    lk = build(load_scene(scene))
    first = out.split("\n1. ")[1].split(" mm,")[0]
    assert first == "b2 {b2:g}, b3 {b3:g}, b4 {b4:g}, d {d:g}".format(**lk.meta["lengths_mm"])
    for bad, msg in (([*args, "--rig", "--top", "0"], "--top"), ([*args, "--top", "3"], "--top needs --rig"),
                     ([*args, "--rig", "--fidelity", "rough"], "--fidelity"),
                     ([*args, "--rig", "--scene-out", str(scene)], "already exists"),
                     ([*args, "--rig", "--scene-out", str(tmp_path / "x.txt")], ".toml")):
        assert main(bad) == 2
        err = capsys.readouterr().err
        assert msg in one_line(err)
