"""The forces on a linkage's bodies besides the joints': gravity and d'Alembert inertia from
each body's motion and mass totals, and the external loads (the compressor's gas force).

The one home of the Newton–Euler body terms: :func:`body_loads` sums them per body once, and the
closed forms (``rigfem.dynamics.closed``) or the general inverse dynamics
(``rigfem.dynamics.inverse``) balance the joint forces against them, on the whole motion the
linkage hands over (:class:`rigfem.linkage.model.LinkageState`).
SI inside (m, rad, N, N·m); a scene's gas force is given in N and mm.
"""

from __future__ import annotations

import numpy as np

from rigfem.linkage.mechanisms import build
from rigfem.linkage.model import BodyState, Linkage, LinkageState, Load

__all__ = ["cross", "inertia_load", "applied", "body_loads", "compressor_gas_force", "loaded_linkage"]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z component of a × b, (..., 2) -> (...): the moment of a planar force b at lever arm a."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def inertia_load(body: BodyState, gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gravity plus d'Alembert force at the centre of mass (N, (n, 2)) and its moment about
    the body's frame origin (N·m, (n,)), from the body's motion (SI)."""
    f = body.mass_kg * (gravity - body.com_acc)
    return f, cross(body.com, f) - body.inertia_kg_m2 * body.alpha


def applied(load: Load, arm: np.ndarray, motion: LinkageState) -> tuple[np.ndarray, np.ndarray]:
    """An external load's force (N, (n, 2)) and its moment about the body's origin (N·m) on
    ``motion``, its point at ``arm`` (m) from the body's origin."""
    point = motion.bodies[load.body].origin + arm
    f = np.asarray(load.force({"theta_rad": motion.theta, "point_mm": point * 1000, "q": motion.q,
                               "qd": motion.qd}), float).reshape(len(motion.theta), 2)
    return f, cross(arm, f)


def body_loads(lk: Linkage, motion: LinkageState) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every body's gravity, d'Alembert and external load on ``motion``: body -> (force N (n, 2),
    its moment about the body's frame origin N·m (n,)), what the joint forces balance."""
    g = np.asarray(lk.gravity_mm_s2, float) / 1000
    out = {b.name: inertia_load(motion.bodies[b.name], g) for b in lk.bodies}
    for ld, arm in zip(lk.loads, motion.load_arms):
        f, m = applied(ld, arm, motion)
        out[ld.body] = (out[ld.body][0] + f, out[ld.body][1] + m)
    return out


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
