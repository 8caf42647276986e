"""Closed-form motion of the rig's four-bar and slider-crank over crank angles.

For the two linkages the rig is built as, every body's angle, rates, frame origin and its
acceleration, and every joint's position follow from the loop closures
(:mod:`rigfem.linkage.loops`), vectorised over crank angles; the general solver
(:mod:`rigfem.linkage.general`) is needed only for other topologies or near a toggle.
The closed-form dynamics (``rigfem.dynamics.closed``) balance forces on this motion, handed
over whole as a :class:`~rigfem.linkage.model.LinkageState`.
SI (m, rad, s) like the dynamics.
"""

from __future__ import annotations

import numpy as np

from rigfem.linkage.loops import BRANCHES, MU_TOGGLE_DEG, change_points_deg, fourbar_angles, fourbar_closes, slider_crank_angles
from rigfem.linkage.model import GROUND, CrankDriver, Linkage, LinkageState, Prismatic, Revolute, state_of

__all__ = ["closed_motion", "change_point_turn"]

#: joints (name, body_a, body_b) the builders make
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


def _toggle_free(L: dict, kind: str) -> bool:
    """No toggle anywhere in the turn: the transmission angle's extremes are at crank 0 and
    180 deg (four-bar), the rod's steepest angle at crank ±90 deg (slider-crank)."""
    lim = np.sin(np.radians(MU_TOGGLE_DEG))
    if kind == "four-bar":
        b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
        f2 = np.array([(d - b2) ** 2, (d + b2) ** 2])
        cmu = (b3**2 + b4**2 - f2) / (2 * b3 * b4)
        return bool(np.all(np.abs(cmu) <= 1.0) and np.all(np.sqrt(1.0 - cmu**2) >= lim))
    s3 = (abs(L.get("offset", 0.0)) + L["b2"]) / L["b3"]
    return bool(s3 < 1.0 and np.sqrt(1.0 - s3**2) >= lim)


def change_point_turn(L: dict, kind: str | None) -> bool:
    """A change-point four-bar whose crank turns fully: its closed form follows the smooth branch
    through the change points (:func:`rigfem.linkage.loops.fourbar_angles`), where the general
    solver, keeping its Jacobian's sign, may bounce back onto the other branch."""
    if kind != "four-bar" or not change_points_deg(L["b2"], L["b3"], L["b4"], L["d"]):
        return False
    return bool(fourbar_closes(L["b2"], L["b3"], L["b4"], L["d"], np.linspace(0.0, 360.0, 3601)).all())


def closed_motion(lk: Linkage, theta: np.ndarray, w2: float) -> LinkageState | None:
    """The motion of ``lk`` at crank angles ``theta`` (rad) and crank speed ``w2`` (rad/s), or
    None where no closed form applies (another topology, or a toggle anywhere in the turn other
    than a change-point four-bar's)."""
    def at(deg: np.ndarray) -> LinkageState | None:
        return closed_motion(lk, np.radians(np.atleast_1d(np.asarray(deg, float))), w2)

    kind = _kind(lk)
    if kind is None or not (_toggle_free(lk.meta["lengths_mm"], kind) or change_point_turn(lk.meta["lengths_mm"], kind)):
        return None
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
    else:
        k = slider_crank_angles(L["b2"], L["b3"], L.get("offset", 0.0), theta, w2)
        out["rod"] = (k["theta3"], k["omega3"], k["alpha3"], A, vA, aA)
        B = np.stack([k["x"], np.full(n, L.get("offset", 0.0))], -1)
        out["slider"] = (zero, zero, zero, B, np.stack([k["v"], zero], -1), np.stack([k["acc"], zero], -1))
    st = state_of(lk, theta, out, None, kind)  # every joint at its point on its body_b
    st.at = at
    return st
