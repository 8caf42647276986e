"""The forces on a linkage's bodies besides the joints': gravity and d'Alembert inertia from
each body's mass data and motion, and the external loads (the compressor's gas force).

The one home of the Newton–Euler body terms: the general solver (``rigfem.dynamics.solver``)
and the closed forms (``rigfem.dynamics.closed``) both balance the joint forces against these.
SI inside (m, rad, N, N·m); a scene's gas force is given in N and mm.
"""

from __future__ import annotations

import numpy as np

from rigfem.linkage.mechanisms import build
from rigfem.linkage.model import Body, Linkage, Load, cross, perp, rotate

__all__ = ["inertia_load", "applied", "compressor_gas_force", "loaded_linkage"]


def inertia_load(body: Body, phi: np.ndarray, omega: np.ndarray, alpha: np.ndarray, acc_origin: np.ndarray,
                 gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gravity plus d'Alembert force at the centre of mass (N, (n, 2)) and its moment about
    the body's frame origin (N·m, (n,)), from the body's motion (SI: rad, rad/s, rad/s², m/s²)."""
    m, c, inertia = body.totals()
    rc = rotate(phi, c)
    f = m * (gravity - (acc_origin + perp(rc) * alpha[:, None] - rc * (omega**2)[:, None]))
    return f, cross(rc, f) - inertia * alpha


def applied(load: Load, theta_rad: np.ndarray, origin_m: np.ndarray, phi: np.ndarray, q: np.ndarray,
            qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An external load's force (N, (n, 2)) and its moment about the body's origin (N·m) at driver
    phases ``theta_rad``, the body at ``origin_m``/``phi``; ``q``, ``qd`` the solver's coordinates."""
    s = rotate(phi, np.asarray(load.local_mm, float) / 1000)
    f = np.asarray(load.force({"theta_rad": theta_rad, "point_mm": (origin_m + s) * 1000, "q": q, "qd": qd}),
                   float).reshape(len(theta_rad), 2)
    return f, cross(s, f)


def compressor_gas_force(b2: float, b3: float, p_N: float = 2000.0, L_mm: float = 1000.0,
                         c_mm: float = 100.0):
    """geometry/MECHANISMS.md #5 gas force on the piston, F = p (V1/V2 - 1) pushing it towards the crank.

    V1 ∝ L - c - b3 + b2 (bottom dead centre), V2 ∝ L - c - x (x = piston distance from O2).
    """
    def force(state: dict) -> np.ndarray:
        x = state["point_mm"][:, 0]
        f = p_N * ((L_mm - c_mm - b3 + b2) / (L_mm - c_mm - x) - 1.0)
        return np.stack([-f, np.zeros_like(f)], -1)

    return force


def loaded_linkage(scene) -> Linkage:
    """The linkage a scene (:class:`rigfem.scene.Scene`) describes, with the external force it
    names (``[linkage.gas]``: the compressor's gas force on the slider) attached."""
    gas = None
    if scene.gas is not None:
        gas = compressor_gas_force(float(scene.params["b2"]), float(scene.params["b3"]), **scene.gas)
    return build(scene, slider_force=gas)
