"""General planar solver: four-bar kinematics vs closed form, Newton–Euler balance of every
body, agreement with the 2013 equations where their quirks vanish, branch continuity, toggles."""

import numpy as np
import pytest

from rigfem.linkage import AssemblyError, solve
from rigfem.mechanisms import RigMasses, crank_angles, four_bar, simulate, transmission_angle
from rigfem.original import fourbar_kinematics, original_reactions

REF = (540.0, 840.0, 780.0, 1020.0)


def _wrap(a):
    return np.angle(np.exp(1j * a))


@pytest.mark.parametrize("branch,sgn", [("open", 1), ("crossed", -1)])
def test_fourbar_kinematics_closed_form_full_turn(branch, sgn):
    """Loop-closure (Freudenstein) positions, velocities, accelerations at 720 angles; the
    continuation must stay on the starting branch all the way round."""
    deg = crank_angles(720)
    h = solve(four_bar(*REF, branch=branch), deg, speed_hz=1.0)
    k = fourbar_kinematics(*(x / 1000 for x in REF), np.radians(deg), 2 * np.pi, sgn)
    c, r = h.bodies["coupler"], h.bodies["rocker"]
    assert np.max(np.abs(_wrap(c.angle_rad - k["theta3"]))) < 1e-10
    assert np.max(np.abs(_wrap(r.angle_rad - k["theta4"]))) < 1e-10
    assert np.allclose(c.omega_rad_s, k["omega3"], atol=1e-9)
    assert np.allclose(r.omega_rad_s, k["omega4"], atol=1e-9)
    assert np.allclose(c.alpha_rad_s2, k["alpha3"], atol=1e-8)
    assert np.allclose(r.alpha_rad_s2, k["alpha4"], atol=1e-8)
    assert np.allclose(h.joints["B"].position_mm, k["B"] * 1000, atol=1e-8)


def test_branch_continuity_across_full_turn():
    """Successive samples move by a bounded step and the turn closes on itself."""
    h = simulate(four_bar(*REF), samples=360)
    for b in h.bodies.values():
        ang = np.unwrap(np.r_[b.angle_rad, b.angle_rad[0]])
        assert np.max(np.abs(np.diff(ang))) < np.radians(3.0)
        assert abs(ang[-1] - ang[0]) < 1e-9 or b.name == "crank"
    assert "warnings" not in h.meta


def _newton_euler_residual(h, body_name, lk):
    """Independent check: sum of joint forces/moments on a body vs m a_G, I_G alpha."""
    body = next(b for b in lk.bodies if b.name == body_name)
    m, c_m, inertia = body.totals()
    bh = h.bodies[body_name]
    c = np.cos(bh.angle_rad)[:, None] * np.array([1.0, 0]) * c_m[0] + \
        np.sin(bh.angle_rad)[:, None] * np.array([0, 1.0]) * c_m[0]
    c[:, 0] -= np.sin(bh.angle_rad) * c_m[1]
    c[:, 1] += np.cos(bh.angle_rad) * c_m[1]
    w, al = bh.omega_rad_s[:, None], bh.alpha_rad_s2[:, None]
    a_g = bh.origin_acc_mm_s2 / 1000 + al * np.c_[-c[:, 1], c[:, 0]] - w**2 * c
    g = bh.origin_mm / 1000 + c
    F = np.zeros_like(a_g)
    M = np.zeros(a_g.shape[0])
    for j in h.joints.values():
        if body_name not in (j.body_a, j.body_b):
            continue
        f = j.force_N if j.body_b == body_name else -j.force_N
        rr = j.position_mm / 1000 - g
        F += f
        M += rr[:, 0] * f[:, 1] - rr[:, 1] * f[:, 0]
    if body_name == "crank":
        M += h.torque_Nm
    return np.max(np.abs(F - m * a_g)), np.max(np.abs(M - inertia * bh.alpha_rad_s2))


@pytest.mark.parametrize("body", ["crank", "coupler", "rocker"])
def test_rigid_body_reactions_satisfy_newton_euler(body):
    lk = four_bar(*REF)
    h = simulate(lk, samples=180)
    fres, mres = _newton_euler_residual(h, body, lk)
    assert fres < 1e-9 * 700 and mres < 1e-9 * 200


def test_rigid_body_equals_original_where_quirks_vanish():
    """No point masses and rails as long as the bars: the 2013 equations are exact rigid-body
    dynamics, so both models must agree (an independent hand-written equation set)."""
    cat = RigMasses(carriage=0.0, plate=0.0, coupling=0.0)
    b2, b3, b4, d = REF
    lk = four_bar(b2, b3, b4, d, rails_mm=(b2, b3, b4), catalogue=cat)
    h = simulate(lk, samples=90)
    r = original_reactions(b2, b3, b4, d, np.radians(h.crank_deg), 1.0, cat, (b2, b3, b4))
    for name, key in (("O2", "R12"), ("A", "R23"), ("B", "R34"), ("O4", "R14")):
        assert np.allclose(h.joints[name].force_N, r[key], rtol=1e-9, atol=1e-9)
    assert np.allclose(h.torque_Nm, r["M2"], atol=1e-9)


def test_gravity_adds_static_weight():
    """A massive vertical-plane crank-rocker at rest speed -> reactions carry the weight."""
    lk = four_bar(*REF, gravity_mm_s2=(0.0, -9810.0))
    h = simulate(lk, samples=36, speed_hz=1e-6)
    total_w = sum(b.totals()[0] for b in lk.bodies) * 9.81
    fy = h.joints["O2"].force_N[:, 1] + h.joints["O4"].force_N[:, 1]
    assert np.allclose(fy, total_w, rtol=1e-9)


def test_toggle_is_flagged_and_never_a_plain_peak():
    """Change-point four-bar (b2 + d = b3 + b4): mu reaches 180 deg at crank 180 deg."""
    from rigfem.reactions import peaks

    h = simulate(four_bar(540, 840, 780, 1080), samples=360)
    assert h.meta["singular"] is not None
    lo, hi = h.meta["singular"][0]
    assert lo <= 180.0 <= hi
    p = peaks(h)
    assert all(p[j]["force_N"] is None and p[j]["singular"] for j in ("O2", "A", "B", "O4"))
    assert p["torque"]["peak"] is None
    assert np.all(np.isfinite(h.torque_Nm))


def test_near_toggle_flag_uses_transmission_angle():
    h = simulate(four_bar(540, 840, 780, 1079), samples=720)
    mu = transmission_angle(h.bodies)
    assert h.meta["singular"] is not None
    flagged = h.singular_mask
    near = np.sin(np.radians(mu)) < np.sin(np.radians(5.0))
    assert near.any() and np.array_equal(flagged, near)


def test_far_from_toggle_not_flagged():
    h = simulate(four_bar(*REF), samples=360)
    assert h.meta["singular"] is None and h.singular_mask is None


def test_cannot_close_names_crank_range():
    # d + b2 > b3 + b4 and d - b2 < b3 + b4: the loop breaks around 180 deg
    with pytest.raises(AssemblyError, match=r"crank angles \d+\.\d-\d+\.\d deg"):
        four_bar(540, 840, 780, 1200)
