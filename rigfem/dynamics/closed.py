"""Closed-form rigid-body dynamics of the rig's four-bar and slider-crank.

The general solver (``rigfem.linkage.general``) closes the loop by continuation and Newton
and inverts a 9×9 constraint Jacobian per crank angle; for the two linkages the rig is
built as, positions, rates and accelerations have closed forms
(``rigfem.linkage.loops``) and the joint reactions follow from two moment balances
per angle (a 2×2 system solved by Cramer's rule), all vectorised over crank angles:

* four-bar: rocker about O4 and coupler about A give the force at B; force balances then
  give A, O4, O2, and the crank's moment about O2 the driver torque;
* slider-crank: rod about A and the slider's balance along the slide give the force at B.

``closed_form`` returns None where it does not apply (another topology, or a toggle
anywhere in the turn: there the general solver's continuation and toggle report are
the reference), so ``solve`` can always try it first.  Same sign conventions and units
as the general solver (``rigfem.dynamics.history``).
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.forces import applied, inertia_load
from rigfem.dynamics.history import JointHistory, ReactionHistory
from rigfem.linkage.loops import BRANCHES, MU_TOGGLE_DEG, fourbar_angles, slider_crank_angles
from rigfem.linkage.model import GROUND, CrankDriver, Linkage, Prismatic, Revolute, cross, perp, rotate

__all__ = ["closed_form"]

#: joints (name, body_a, body_b, local_a, local_b) the builders make; lengths filled from meta
_FOURBAR = (("O2", GROUND, "crank"), ("A", "crank", "coupler"), ("B", "coupler", "rocker"), ("O4", GROUND, "rocker"))
_SLIDER = (("O2", GROUND, "crank"), ("A", "crank", "rod"), ("B", "rod", "slider"), ("slide", GROUND, "slider"))


def _kind(lk: Linkage) -> str | None:
    """'four-bar' or 'slider-crank' when ``lk`` is exactly the builders' topology, else None."""
    typ, L = lk.meta.get("type"), lk.meta.get("lengths_mm") or {}
    d = lk.driver
    if not isinstance(d, CrankDriver) or d.body != "crank" or d.offset_rad != 0.0:
        return None
    names = [(j.name, j.body_a, j.body_b) for j in lk.joints]
    if typ == "four-bar" and names == list(_FOURBAR):
        want = [((0, 0), (0, 0)), ((L["b2"], 0), (0, 0)), ((L["b3"], 0), (L["b4"], 0)), ((L["d"], 0), (0, 0))]
        ok = all(isinstance(j, Revolute) for j in lk.joints)
    elif typ == "slider-crank" and names == list(_SLIDER):
        want = [((0, 0), (0, 0)), ((L["b2"], 0), (0, 0)), ((L["b3"], 0), (0, 0))]
        s = lk.joints[3]
        ok = (all(isinstance(j, Revolute) for j in lk.joints[:3]) and isinstance(s, Prismatic)
              and tuple(s.local_a_mm) == (0.0, L.get("offset", 0.0)) and tuple(s.axis_a) == (1.0, 0.0)
              and tuple(s.local_b_mm) == (0.0, 0.0) and s.rel_angle_rad == 0.0)
    else:
        return None
    for j, (la, lb) in zip(lk.joints, want):
        ok = ok and tuple(map(float, j.local_a_mm)) == la and tuple(map(float, j.local_b_mm)) == lb
    return typ if ok else None


def _toggle_free(lk: Linkage, kind: str) -> bool:
    """No toggle anywhere in the turn: the transmission angle's extremes are at crank 0 and
    180 deg (four-bar), the rod's steepest angle at crank ±90 deg (slider-crank)."""
    L = lk.meta["lengths_mm"]
    lim = np.sin(np.radians(MU_TOGGLE_DEG))
    if kind == "four-bar":
        b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
        f2 = np.array([(d - b2) ** 2, (d + b2) ** 2])
        cmu = (b3**2 + b4**2 - f2) / (2 * b3 * b4)
        return bool(np.all(np.abs(cmu) <= 1.0) and np.all(np.sqrt(1.0 - cmu**2) >= lim))
    s3 = (abs(L.get("offset", 0.0)) + L["b2"]) / L["b3"]
    return bool(s3 < 1.0 and np.sqrt(1.0 - s3**2) >= lim)


def _cramer(r1: np.ndarray, b1: np.ndarray, r2: np.ndarray, b2: np.ndarray) -> np.ndarray:
    """F (n, 2) with r1·F = b1 and r2·F = b2 (rows (n, 2); a moment r × F is perp(r)·F)."""
    det = r1[:, 0] * r2[:, 1] - r1[:, 1] * r2[:, 0]
    return np.stack([(b1 * r2[:, 1] - r1[:, 1] * b2) / det, (r1[:, 0] * b2 - b1 * r2[:, 0]) / det], -1)


def _motion(lk: Linkage, kind: str, theta: np.ndarray, w2: float) -> dict:
    """Per body (name -> (phi, omega, alpha, origin, origin velocity, origin acceleration)), SI."""
    L = {k: v / 1000 for k, v in lk.meta["lengths_mm"].items()}
    n = theta.size
    zero, zeros2 = np.zeros(n), np.zeros((n, 2))
    c2, s2 = np.cos(theta), np.sin(theta)
    A = L["b2"] * np.stack([c2, s2], -1)
    vA = L["b2"] * w2 * np.stack([-s2, c2], -1)
    aA = -(w2**2) * A
    out = {"crank": (theta, np.full(n, w2), zero, zeros2, zeros2, zeros2)}
    if kind == "four-bar":
        k = fourbar_angles(L["b2"], L["b3"], L["b4"], L["d"], theta, w2, 0.0, BRANCHES[lk.meta.get("branch", "open")])
        O4 = np.zeros((n, 2))
        O4[:, 0] = L["d"]
        out["coupler"] = (k["theta3"], k["omega3"], k["alpha3"], A, vA, aA)
        out["rocker"] = (k["theta4"], k["omega4"], k["alpha4"], O4, zeros2, zeros2)
        return out
    k = slider_crank_angles(L["b2"], L["b3"], L.get("offset", 0.0), theta, w2)
    x = k["x"]
    out["rod"] = (k["theta3"], k["omega3"], k["alpha3"], A, vA, aA)
    out["slider"] = (zero, zero, zero, np.stack([x, np.full(n, L.get("offset", 0.0))], -1),
                     np.stack([k["v"], zero], -1), np.stack([k["acc"], zero], -1))
    return out


def _history(lk: Linkage, kind: str, deg: np.ndarray, speed_hz: float) -> ReactionHistory:
    theta = np.radians(deg)
    w2 = 2 * np.pi * speed_hz
    mo = _motion(lk, kind, theta, w2)
    g = np.asarray(lk.gravity_mm_s2, float) / 1000
    D, M = {}, {}                       # per body: applied + d'Alembert force, its moment about the origin
    for b in lk.bodies:
        phi, w, al, _, _, acc = mo[b.name]
        D[b.name], M[b.name] = inertia_load(b, phi, w, al, acc, g)
    if lk.loads:  # the loads see the general solver's coordinates (x, y, phi per body, SI)
        q = np.concatenate([np.column_stack([mo[b.name][3], mo[b.name][0]]) for b in lk.bodies], 1)
        qd = np.concatenate([np.column_stack([mo[b.name][4], mo[b.name][1]]) for b in lk.bodies], 1)
        for ld in lk.loads:
            f, m = applied(ld, theta, mo[ld.body][3], mo[ld.body][0], q, qd)
            D[ld.body] = D[ld.body] + f
            M[ld.body] = M[ld.body] + m
    A = mo["coupler" if kind == "four-bar" else "rod"][3]
    if kind == "four-bar":
        B = mo["rocker"][3] + rotate(mo["rocker"][0], (lk.meta["lengths_mm"]["b4"] / 1000, 0.0))
        # rocker about O4: (B - O4) x F_B = -M_r;  coupler about A: (B - A) x F_B = M_c
        FB = _cramer(perp(B - mo["rocker"][3]), -M["rocker"], perp(B - A), M["coupler"])
        FA = FB - D["coupler"]
        forces = {"O2": FA - D["crank"], "A": FA, "B": FB, "O4": -FB - D["rocker"]}
        pos = {"O2": np.zeros_like(A), "A": A, "B": B, "O4": mo["rocker"][3]}
    else:
        B = mo["slider"][3]
        u = np.broadcast_to([1.0, 0.0], B.shape)
        # rod about A: (B - A) x F_B = M_rod;  slider along the slide: u · F_B = -u · D_s
        FB = _cramer(perp(B - A), M["rod"], u, -D["slider"][:, 0])
        FA = FB - D["rod"]
        forces = {"O2": FA - D["crank"], "A": FA, "B": FB, "slide": -FB - D["slider"]}
        pos = {"O2": np.zeros_like(A), "A": A, "B": B, "slide": B}
    torque = cross(A, FA) - M["crank"]
    bodies = {b.name: b.history(*mo[b.name]) for b in lk.bodies}
    joints = {}
    for j in lk.joints:
        prism = isinstance(j, Prismatic)
        joints[j.name] = JointHistory(j.name, j.body_a, j.body_b, forces[j.name], pos[j.name] * 1000,
                                      -M["slider"] if prism else None, "prismatic" if prism else "revolute")
    lk.record_joint_points(bodies)
    meta = {k: v for k, v in lk.meta.items() if k != "singular_fn"}
    meta.update(speed_hz=speed_hz, driver_unit="N·m", solver="closed form", singular=None)
    return ReactionHistory(deg, joints, torque, bodies, meta, singular_mask=None,
                           evaluator=lambda a: _history(lk, kind, np.atleast_1d(np.asarray(a, float)), speed_hz))


def closed_form(lk: Linkage, crank_deg: np.ndarray, speed_hz: float) -> ReactionHistory | None:
    """Reaction history of a toggle-free rig four-bar or slider-crank in closed form, or None.

    A linkage that enters the toggle band (``MU_TOGGLE_DEG``) anywhere in the turn is left
    to the general solver, whose continuation reports the toggle ranges.
    """
    kind = _kind(lk)
    if kind is None or not _toggle_free(lk, kind):
        return None
    return _history(lk, kind, np.asarray(crank_deg, float), float(speed_hz))
