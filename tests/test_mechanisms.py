"""The seven geometry/MECHANISMS.md linkages, read from the shipped scene files, against closed-form
kinematics (and, for #5, a hand-solved Newton–Euler force analysis)."""

import numpy as np
import pytest

from rigfem.dynamics import fourbar_kinematics, loaded_linkage, simulate
from rigfem.linkage import build, coupler_point_path, transmission_angle
from rigfem.scene import builtin_scenes, load_scene

N = 120


def _run(name, samples=N):
    s = load_scene(name)
    h = simulate(loaded_linkage(s), samples=samples, speed_hz=s.speed_hz)
    return s, h


def _slider_crank_closed_form(r, l, th, w):
    """x, v, a of the slider and rod angle, rate, acceleration (no offset, constant w)."""
    s, c = np.sin(th), np.cos(th)
    S = np.sqrt(l**2 - r**2 * s**2)
    x = r * c + S
    x1 = -r * s - r**2 * s * c / S
    x2 = -r * c - r**2 * (c**2 - s**2) / S - r**4 * s**2 * c**2 / S**3
    phi = np.arcsin(-r * s / l)
    p1 = -r * c / (l * np.cos(phi))
    p2 = (r * s * l * np.cos(phi) - r * c * l * np.sin(phi) * p1) / (l * np.cos(phi)) ** 2
    return dict(x=x, v=x1 * w, a=x2 * w**2, phi=phi, omega=p1 * w, alpha=p2 * w**2)


def test_all_seven_scenes_ship_with_the_package():
    names = set(builtin_scenes())
    for k in range(1, 8):
        assert any(n.startswith(f"mech{k}-") for n in names)


@pytest.mark.parametrize("name", ["mech1-slider-crank", "mech5-compressor"])
def test_slider_crank_kinematics(name):
    s, h = _run(name)
    L = build(s).meta["lengths_mm"]
    w = 2 * np.pi * s.speed_hz
    cf = _slider_crank_closed_form(L["b2"], L["b3"], np.radians(h.crank_deg), w)
    sl, rod = h.bodies["slider"], h.bodies["rod"]
    assert np.allclose(sl.origin_mm[:, 0], cf["x"], rtol=0, atol=1e-9)
    assert np.allclose(sl.origin_acc_mm_s2[:, 0], cf["a"], rtol=1e-9, atol=1e-9 * np.abs(cf["a"]).max())
    assert np.allclose(rod.angle_rad, cf["phi"], atol=1e-12)
    assert np.allclose(rod.omega_rad_s, cf["omega"], atol=1e-9)
    assert np.allclose(rod.alpha_rad_s2, cf["alpha"], rtol=1e-9, atol=1e-9 * np.abs(cf["alpha"]).max())


def test_mech6_slider_crank_at_one_instant():
    """3 in / 7 in, crank at 60 deg turning at 3.12 rad/s clockwise.  Hand values from the
    closed form: rod omega = +0.7200 rad/s, alpha = +3.6837 rad/s^2, slider v = +9.9766 in/s,
    a = -8.4007 in/s^2 (x measured from the crank pivot towards the slider)."""
    s = load_scene("mech6-slider-crank-instant")
    assert s.speed_hz == pytest.approx(-3.12 / (2 * np.pi))
    h = simulate(loaded_linkage(s), samples=360, speed_hz=s.speed_hz)
    i = int(np.flatnonzero(np.isclose(h.crank_deg, s.table["instant_deg"]))[0])
    rod, sl = h.bodies["rod"], h.bodies["slider"]
    # slider velocity is not stored in the history: from the rod motion, v_B = v_A + w x r_AB
    A = h.joints["A"].position_mm[i] / 25.4
    B = h.joints["B"].position_mm[i] / 25.4
    wc = -3.12
    vA = wc * np.array([-A[1], A[0]])
    vB = vA + rod.omega_rad_s[i] * np.array([-(B - A)[1], (B - A)[0]])
    assert rod.omega_rad_s[i] == pytest.approx(0.7200, rel=1e-4)
    assert rod.alpha_rad_s2[i] == pytest.approx(3.6837, rel=1e-4)
    assert vB[0] == pytest.approx(9.9766, rel=1e-4) and abs(vB[1]) < 1e-9
    assert sl.origin_acc_mm_s2[i, 0] / 25.4 == pytest.approx(-8.4007, rel=1e-4)


def test_mech2_fourbar_with_coupler_point():
    s, h = _run("mech2-fourbar-coupler-point")
    L = build(s).meta["lengths_mm"]
    w = 2 * np.pi * s.speed_hz
    assert w == pytest.approx(20 * 2 * np.pi / 60)
    k = fourbar_kinematics(L["b2"], L["b3"], L["b4"], L["d"], np.radians(h.crank_deg), w, 1)
    ang = k["theta3"] + np.radians(50.0)
    P = k["A"] + 120.0 * np.stack([np.cos(ang), np.sin(ang)], -1)
    assert np.allclose(coupler_point_path(h), P, atol=1e-9)
    assert np.allclose(h.bodies["rocker"].omega_rad_s, k["omega4"], atol=1e-10)
    assert np.allclose(h.bodies["coupler"].alpha_rad_s2, k["alpha3"], atol=1e-9)
    # transmission angle from the triangle A-B-O4 (law of cosines)
    f2 = np.sum((k["A"] - [L["d"], 0.0]) ** 2, axis=1)
    mu = np.degrees(np.arccos((L["b3"] ** 2 + L["b4"] ** 2 - f2) / (2 * L["b3"] * L["b4"])))
    assert np.allclose(transmission_angle(h.bodies), mu, atol=1e-9)


def test_mech3_inverted_slider_crank():
    """Link 4: (A - O4)·u = arm with u the arm direction: phi4 = beta - acos(arm / f)."""
    s, h = _run("mech3-inverted-slider-crank")
    L = build(s).meta["lengths_mm"]
    d, r, e = L["d"], L["b2"], L["arm"]
    w = 2 * np.pi * s.speed_hz

    def closed(th):
        D = np.stack([r * np.cos(th) - d, r * np.sin(th)], -1)
        D1 = np.stack([-r * np.sin(th), r * np.cos(th)], -1)
        f = np.hypot(D[:, 0], D[:, 1])
        f1 = np.sum(D * D1, 1) / f
        beta1 = (D[:, 0] * D1[:, 1] - D[:, 1] * D1[:, 0]) / f**2
        phi = np.arctan2(D[:, 1], D[:, 0]) - np.arccos(e / f)
        return phi, (beta1 - e * f1 / (f * np.sqrt(f**2 - e**2))) * w

    th = np.radians(h.crank_deg)
    phi, om = closed(th)
    eps = 1e-5
    alpha = (closed(th + eps)[1] - closed(th - eps)[1]) / (2 * eps) * w   # derivative of the closed form
    r4 = h.bodies["rocker"]
    assert np.allclose(np.angle(np.exp(1j * (r4.angle_rad - phi))), 0.0, atol=1e-10)
    assert np.allclose(r4.omega_rad_s, om, atol=1e-9)
    assert np.allclose(r4.alpha_rad_s2, alpha, rtol=1e-6, atol=1e-6)
    # the block slides along link 4 and turns with it
    assert np.allclose(h.bodies["block"].angle_rad, r4.angle_rad, atol=1e-12)


def test_mech4_quick_return_ram():
    """Ram x = h Ax / (Ay + p) on the line h above O4 (similar triangles through the slot)."""
    s, h = _run("mech4-quick-return", 180)
    L = build(s).meta["lengths_mm"]
    r, p, hh = L["b2"], L["pivot_below"], L["ram_height"]
    w = 2 * np.pi * s.speed_hz
    th = np.radians(h.crank_deg)
    N, D = r * np.cos(th), r * np.sin(th) + p
    N1, D1, N2, D2 = -r * np.sin(th), r * np.cos(th), -r * np.cos(th), -r * np.sin(th)
    x = hh * N / D
    x1 = hh * (N1 * D - N * D1) / D**2
    x2 = hh * ((N2 * D - N * D2) / D**2 - 2 * D1 * (N1 * D - N * D1) / D**3)
    ram = h.bodies["ram"]
    assert np.allclose(ram.origin_mm[:, 0], x, atol=1e-8)
    assert np.allclose(ram.origin_mm[:, 1], hh - p, atol=1e-9)
    assert np.allclose(ram.origin_acc_mm_s2[:, 0], x2 * w**2, rtol=1e-9, atol=1e-8 * np.abs(x2 * w**2).max())
    # ram velocity from the rocker motion: C slides in the slot, v_C·n = omega4 (C - O4)·t
    phi = h.bodies["rocker"].angle_rad
    C = ram.origin_mm - [0.0, -p]
    v_c = h.bodies["rocker"].omega_rad_s * np.hypot(C[:, 0], C[:, 1]) / np.sin(phi)
    assert np.allclose(-v_c, x1 * w, rtol=1e-9, atol=1e-9 * np.abs(x1 * w).max())
    # quick return: the cutting stroke takes longer than the return (crank angle ratio)
    stroke = np.ptp(x)
    assert stroke == pytest.approx(2 * hh * r / np.sqrt(p**2 - r**2), rel=1e-3)


def test_mech5_compressor_reactions_and_torque():
    """Hand-solved Newton–Euler: piston, then rod (moments about its centre), then the massless crank."""
    s, h = _run("mech5-compressor", 180)
    r, l = 0.150, 0.350
    mp, m3, I3 = 4.8, 6.8, 0.0921
    w = 2 * np.pi * s.speed_hz
    th = np.radians(h.crank_deg)
    cf = _slider_crank_closed_form(r, l, th, w)
    A = r * np.stack([np.cos(th), np.sin(th)], -1)
    B = np.stack([cf["x"], np.zeros_like(th)], -1)
    G = (A + B) / 2
    aA = -(w**2) * A
    aB = np.stack([cf["a"], np.zeros_like(th)], -1)
    aG = (aA + aB) / 2
    F_gas = 2000.0 * ((1.0 - 0.1 - l + r) / (1.0 - 0.1 - cf["x"]) - 1.0)
    FBx = mp * aB[:, 0] + F_gas                    # rod on piston, x
    AG, AB = A - G, A - B

    def cross(a, b):
        return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]

    FBy = (I3 * cf["alpha"] - m3 * cross(AG, aG) + AB[:, 1] * FBx) / AB[:, 0]
    FB = np.stack([FBx, FBy], -1)
    FA = m3 * aG + FB                              # crank on rod
    T = cross(A, FA)
    assert np.allclose(h.joints["B"].force_N, FB, rtol=1e-8, atol=1e-6)
    assert np.allclose(h.joints["A"].force_N, FA, rtol=1e-8, atol=1e-6)
    assert np.allclose(h.joints["O2"].force_N, FA, rtol=1e-8, atol=1e-6)
    assert np.allclose(h.joints["slide"].force_N, np.stack([np.zeros_like(FBy), -FBy], -1), atol=1e-6)
    assert np.allclose(h.torque_Nm, T, rtol=1e-8, atol=1e-6)


def test_mech7_elliptical_trainer_transmission_and_advantage():
    s, h = _run("mech7-elliptical-trainer", 360)
    L = build(s).meta["lengths_mm"]
    b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
    mu_min = np.degrees(np.arccos((b3**2 + b4**2 - (d - b2) ** 2) / (2 * b3 * b4)))
    mu_max = np.degrees(np.arccos((b3**2 + b4**2 - (d + b2) ** 2) / (2 * b3 * b4)))
    assert h.meta["mu_deg"]["min"] == pytest.approx(mu_min, abs=1e-9)     # crank at 0 deg is sampled
    assert h.meta["mu_deg"]["max"] == pytest.approx(mu_max, abs=1e-9)     # and 180 deg
    # mechanical advantage (massless: T4/T2 = w2/w4); closed form from the loop equations
    k = fourbar_kinematics(b2, b3, b4, d, np.radians(h.crank_deg), 1.0, 1)
    ratio = b2 * np.sin(k["theta2"] - k["theta3"]) / (b4 * np.sin(k["theta4"] - k["theta3"]))
    assert np.allclose(h.bodies["rocker"].omega_rad_s / h.bodies["crank"].omega_rad_s, ratio, atol=1e-10)


@pytest.mark.parametrize("name", sorted(builtin_scenes()))
def test_every_shipped_scene_solves_without_toggle(name):
    s, h = _run(name, 72)
    assert h.meta["singular"] is None and "warnings" not in h.meta
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values())
    assert build(s).meta["type"] in ("four-bar", "slider-crank", "inverted-slider-crank", "quick-return")
