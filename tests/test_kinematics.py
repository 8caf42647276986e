"""Closed-form kinematics (rigfem.linkage.kinematics) against finite differences of its own
positions, against the general planar solver on every geometry/MECHANISMS.md linkage, and the
geometry/MECHANISMS.md §6 instant against a hand-derived closed form."""

import json

import numpy as np
import pytest

from rigfem.dynamics import solve
from rigfem.errors import InputError
from rigfem.linkage import (
    build,
    inverted_slider_crank,
    crank_angles,
    fourbar_motion,
    fourbar_turn,
    grashof_class,
    linkage_motion,
    linkage_turn,
    motion_from_history,
    slider_crank_motion,
    slider_crank_turn,
)
from rigfem.scene import load_scene

DT = 1e-4   # s


def _fd_check(make, theta0_deg, omega, alpha):
    """Positions at t = -DT, 0, +DT of a driver theta(t) = theta0 + omega t + alpha t^2 / 2
    (each evaluated at its own instantaneous speed) -> central differences vs the closed form."""
    th = np.radians(theta0_deg)
    ms = [make(np.degrees(th + omega * t + alpha * t * t / 2), omega + alpha * t, alpha) for t in (-DT, 0.0, DT)]
    m0 = ms[1]
    for name, p in m0.points.items():
        P = [m.points[name]["position_mm"] for m in ms]
        v = (P[2] - P[0]) / (2 * DT)
        a = (P[2] - 2 * P[1] + P[0]) / DT**2
        scale_v = max(1.0, np.abs(p["velocity_mm_s"]).max())
        scale_a = max(1.0, np.abs(p["acceleration_mm_s2"]).max())
        assert np.allclose(p["velocity_mm_s"], v, atol=1e-6 * scale_v), name
        assert np.allclose(p["acceleration_mm_s2"], a, atol=1e-4 * scale_a), name
    for name, lk in m0.links.items():
        T = [np.radians(m.links[name]["angle_deg"]) for m in ms]
        d1 = np.angle(np.exp(1j * (T[2] - T[0]))) / (2 * DT)
        d2 = (np.angle(np.exp(1j * (T[2] - T[1]))) - np.angle(np.exp(1j * (T[1] - T[0])))) / DT**2
        assert np.allclose(lk["omega_rad_s"], d1, atol=1e-6 * max(1, np.abs(d1).max())), name
        assert np.allclose(lk["alpha_rad_s2"], d2, atol=1e-4 * max(1, np.abs(d2).max())), name
    return m0


@pytest.mark.parametrize("branch", ["open", "crossed"])
@pytest.mark.parametrize("alpha", [0.0, 4.0])
def test_fourbar_rates_are_derivatives_of_positions(branch, alpha):
    deg = np.arange(0.0, 360.0, 7.5)
    _fd_check(lambda d, w, a: fourbar_motion(36, 64, 54, 52, d, w, a, branch, (120.0, 50.0)), deg, -2.1, alpha)


@pytest.mark.parametrize("alpha", [0.0, -3.0])
def test_slider_crank_rates_are_derivatives_of_positions(alpha):
    deg = np.arange(0.0, 360.0, 7.5)
    m = _fd_check(lambda d, w, a: slider_crank_motion(100, 420, 35, d, w, a), deg, 5.0, alpha)
    assert np.allclose(m.slider["velocity_mm_s"], m.points["B"]["velocity_mm_s"][:, 0])
    assert np.allclose(m.points["B"]["position_mm"][:, 1], 35.0)


@pytest.mark.parametrize("name", ["mech1-slider-crank", "mech2-fourbar-coupler-point", "mech5-compressor",
                                  "mech6-slider-crank-instant", "mech7-elliptical-trainer",
                                  "rig-fourbar-reference", "rig-slider-crank"])
def test_closed_form_agrees_with_the_general_solver(name):
    s = load_scene(name)
    h = solve(build(s), crank_angles(90), speed_hz=s.speed_hz, general=True)
    assert h.meta["solver"] == "general"
    gen = motion_from_history(h)
    cf = linkage_motion(build(s), h.crank_deg, 2 * np.pi * s.speed_hz)
    size = max(build(s).meta["lengths_mm"].values())
    for link, v in gen.links.items():
        if link == "slider":
            continue
        c = cf.links[link]
        assert np.allclose(np.angle(np.exp(1j * np.radians(v["angle_deg"] - c["angle_deg"]))), 0, atol=1e-10)
        assert np.allclose(v["omega_rad_s"], c["omega_rad_s"], atol=1e-9 * max(1, np.abs(c["omega_rad_s"]).max()))
        assert np.allclose(v["alpha_rad_s2"], c["alpha_rad_s2"], atol=1e-8 * max(1, np.abs(c["alpha_rad_s2"]).max()))
    for pt in ("A", "B"):
        g, c = gen.points[pt], cf.points[pt]
        assert np.allclose(g["position_mm"], c["position_mm"], atol=1e-8 * size)
        for k in ("velocity_mm_s", "acceleration_mm_s2"):
            assert np.allclose(g[k], c[k], atol=1e-8 * np.abs(c[k]).max()), (pt, k)


@pytest.mark.parametrize("name", ["mech3-inverted-slider-crank", "mech4-quick-return"])
def test_general_solver_point_velocities_are_derivatives_of_positions(name):
    """The fallback for linkages without a closed form: joint velocities/accelerations of the
    general solver (origin velocity, omega x r) against differences of its positions."""
    s = load_scene(name)
    w = 2 * np.pi * s.speed_hz
    deg = np.arange(0.0, 360.0, 15.0)
    h = np.degrees(w * DT)
    ms = [linkage_motion(build(s), deg + k * h, w) for k in (-1, 0, 1)]
    for pt, p in ms[1].points.items():
        P = [m.points[pt]["position_mm"] for m in ms]
        v = (P[2] - P[0]) / (2 * DT)
        a = (P[2] - 2 * P[1] + P[0]) / DT**2
        assert np.allclose(p["velocity_mm_s"], v, atol=1e-5 * max(1, np.abs(v).max())), pt
        assert np.allclose(p["acceleration_mm_s2"], a, atol=1e-3 * max(1, np.abs(a).max())), pt


def test_mech6_instant_against_hand_closed_form():
    """3 in crank, 7 in rod, crank at 60 deg turning at 3.12 rad/s clockwise, constant speed.
    By hand with beta the rod's angle below the slide axis: sin beta = r sin th / l,
    beta' = r w cos th / (l cos beta), beta'' = (r w^2 (-sin th) + l beta'^2 sin beta) / (l cos beta),
    x = r cos th + l cos beta, x' = -r w sin th - l beta' sin beta,
    x'' = -r w^2 cos th - l (beta'' sin beta + beta'^2 cos beta)."""
    s = load_scene("mech6-slider-crank-instant")
    r, l, w, th = 3.0, 7.0, -3.12, np.radians(60.0)
    beta = np.arcsin(r * np.sin(th) / l)
    b1 = r * w * np.cos(th) / (l * np.cos(beta))
    b2 = (-r * w**2 * np.sin(th) + l * b1**2 * np.sin(beta)) / (l * np.cos(beta))
    x1 = -r * w * np.sin(th) - l * b1 * np.sin(beta)
    x2 = -r * w**2 * np.cos(th) - l * (b2 * np.sin(beta) + b1**2 * np.cos(beta))
    m = linkage_motion(build(s), [s.table["instant_deg"]], 2 * np.pi * s.speed_hz)
    rod = m.links["rod"]
    assert rod["omega_rad_s"][0] == pytest.approx(-b1, rel=1e-12)       # rod angle = -beta
    assert rod["alpha_rad_s2"][0] == pytest.approx(-b2, rel=1e-12)
    assert m.slider["velocity_mm_s"][0] / 25.4 == pytest.approx(x1, rel=1e-12)
    assert m.slider["acceleration_mm_s2"][0] / 25.4 == pytest.approx(x2, rel=1e-12)
    # the textbook's rounded answer
    assert (-b1, -b2, x1, x2) == pytest.approx((0.7200, 3.6837, 9.9766, -8.4007), rel=1e-4)


@pytest.mark.parametrize("lengths,cls", [((36, 64, 54, 52), "crank-rocker"), ((60, 100, 90, 30), "double-crank"),
                                         ((100, 60, 30, 90), "rocker-crank"), ((80, 30, 90, 100), "double-rocker"),
                                         ((100, 70, 75, 80), "triple-rocker"), ((40, 80, 60, 60), "change-point")])
def test_grashof_classes(lengths, cls):
    assert grashof_class(*lengths) == cls


@pytest.mark.parametrize("lengths,branch", [((144, 673.8, 361.7, 726.4), "open"), ((36, 64, 54, 52), "open"),
                                            ((540, 840, 780, 1020), "crossed")])
def test_crank_rocker_toggles_are_the_rocker_limits(lengths, branch):
    t = fourbar_turn(*lengths, branch=branch)
    assert t["grashof"] == "crank-rocker" and t["crank_turns_fully"] and t["dead_points_deg"] == []
    assert sorted(x["kind"] for x in t["toggles"]) == ["extended", "folded"]
    m = fourbar_motion(*lengths, [x["crank_deg"] for x in t["toggles"]], 1.0, 0.0, branch)
    assert np.allclose(m.links["rocker"]["omega_rad_s"], 0.0, atol=1e-9)       # limit positions
    dense = np.linspace(0, 360, 720001)
    th4 = fourbar_motion(*lengths, dense, 1.0, 0.0, branch).links["rocker"]["angle_deg"]
    th4 = np.degrees(np.unwrap(np.radians(th4)))
    assert t["rocker_swing_deg"] == pytest.approx(np.ptp(th4), abs=1e-6)
    fwd = (dense[np.argmax(th4)] - dense[np.argmin(th4)]) % 360
    assert max(fwd, 360 - fwd) / min(fwd, 360 - fwd) == pytest.approx(t["time_ratio"], rel=1e-4)


def test_non_grashof_dead_points_bound_the_crank():
    t = fourbar_turn(100, 70, 75, 80)
    assert not t["crank_turns_fully"] and len(t["dead_points_deg"]) == 2
    m = fourbar_motion(100, 70, 75, 80, t["dead_points_deg"], 1.0)
    assert np.allclose(np.sin(np.radians(m.transmission_deg)), 0.0, atol=1e-6)     # coupler and rocker aligned
    a, b = t["crank_range_deg"]
    fourbar_motion(100, 70, 75, 80, np.linspace(a + 1e-6, b - 1e-6, 50))           # closes inside
    with pytest.raises(InputError, match="cannot be assembled"):
        fourbar_motion(100, 70, 75, 80, [(b + 1.0) % 360])


def test_slider_crank_stroke_and_quick_return_with_offset():
    b2, b3, e = 100.0, 300.0, 60.0
    t = slider_crank_turn(b2, b3, e)
    dense = np.linspace(0, 360, 720001)
    x = slider_crank_motion(b2, b3, e, dense, 1.0).slider["position_mm"]
    assert t["stroke_mm"] == pytest.approx(np.ptp(x), abs=1e-6)
    fwd = (dense[np.argmin(x)] - dense[np.argmax(x)]) % 360
    assert t["stroke_crank_deg"][0] == pytest.approx(fwd, abs=1e-3)
    assert t["time_ratio"] > 1.0
    assert slider_crank_turn(b2, b3)["time_ratio"] == pytest.approx(1.0)     # no offset: no quick return


def test_linkage_turn_and_instant_from_scenes():
    s = load_scene("mech2-fourbar-coupler-point")
    assert linkage_turn(build(s))["grashof"] == "crank-rocker"
    m = linkage_motion(build(s), [0.0, 90.0], 2 * np.pi * s.speed_hz)
    assert "P" in m.points and np.all(np.isfinite(m.mechanical_advantage))
    assert linkage_turn(build(load_scene("mech3-inverted-slider-crank"))) is None


def test_bad_input_is_one_line_error():
    with pytest.raises(InputError, match="b3"):
        fourbar_motion(36, -1, 54, 52, [0.0])
    with pytest.raises(InputError, match="branch"):
        fourbar_motion(36, 64, 54, 52, [0.0], branch="upside")
    with pytest.raises(InputError, match="cannot be assembled"):
        slider_crank_motion(300, 200, 0.0, [90.0])


@pytest.mark.parametrize("arm", [0.0, 120.0])
def test_inverted_slider_crank_gives_the_block_along_the_link(arm):
    """The block's position along the link it slides on (O4A when arm = 0), its sliding speed
    and acceleration, against the closed form s² = b2² + d² − 2 b2 d cos θ − arm², in the JSON,
    the CSV and the table of ``rigfem kinematics``."""
    d, b2, w = 500.0, 200.0, 3.0
    deg = np.array([0.0, 30.0, 90.0, 200.0, 300.0])
    m = linkage_motion(inverted_slider_crank(d, b2, arm, masses=None), deg, w)
    th = np.radians(deg)
    s = np.sqrt(b2**2 + d**2 - 2 * b2 * d * np.cos(th) - arm**2)
    v = b2 * d * w * np.sin(th) / s                       # d(s²)/dt = 2 b2 d w sin θ
    a = (b2 * d * w**2 * np.cos(th) - v**2) / s           # d²(s²)/dt² / 2 = v² + s a
    assert np.allclose(m.slider["position_mm"], s, rtol=1e-9, atol=1e-9)
    assert np.allclose(m.slider["velocity_mm_s"], v, rtol=1e-7, atol=1e-6)
    assert np.allclose(m.slider["acceleration_mm_s2"], a, rtol=1e-6, atol=1e-4)


def test_inverted_slider_crank_cli_reports_the_slider(tmp_path, capsys):
    from rigfem.cli import main

    assert main(["kinematics", "mech3-inverted-slider-crank", "--at", "90", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)["angles"][0]
    # d = 500, b2 = 200, arm = 200 mm: at 90 deg s = sqrt(200² + 500² − 200²) = 500 mm
    assert rec["slider"]["position_mm"] == pytest.approx(500.0, rel=1e-9)
    assert main(["kinematics", "mech3-inverted-slider-crank", "--at", "90", "--csv", str(tmp_path / "k.csv")]) == 0
    head, row = (tmp_path / "k.csv").read_text().splitlines()[:2]
    assert float(dict(zip(head.split(","), row.split(",")))["slider_position_mm"]) == pytest.approx(500.0)
    capsys.readouterr()
    assert main(["kinematics", "mech3-inverted-slider-crank", "--at", "90"]) == 0
    table = capsys.readouterr().out.splitlines()
    head = next(r for r in table if r.lstrip().startswith("crank deg"))
    row = table[table.index(head) + 1].split()
    assert head.split()[-6:-4] == ["slider", "mm"] and float(row[-3]) == pytest.approx(500.0)
