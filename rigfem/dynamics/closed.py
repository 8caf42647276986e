"""Closed-form rigid-body dynamics of the rig's four-bar and slider-crank.

The general solver (``rigfem.linkage.general``) closes the loop by continuation and Newton
and inverts a 9×9 constraint Jacobian per crank angle; for the two linkages the rig is
built as, positions, rates and accelerations have closed forms
(``rigfem.linkage.closed``) and the joint reactions follow from two moment balances
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
from rigfem.linkage.closed import ClosedMotion, closed_motion
from rigfem.linkage.model import Linkage, Prismatic, cross, perp

__all__ = ["closed_form"]


def _cramer(r1: np.ndarray, b1: np.ndarray, r2: np.ndarray, b2: np.ndarray) -> np.ndarray:
    """F (n, 2) with r1·F = b1 and r2·F = b2 (rows (n, 2); a moment r × F is perp(r)·F)."""
    det = r1[:, 0] * r2[:, 1] - r1[:, 1] * r2[:, 0]
    return np.stack([(b1 * r2[:, 1] - r1[:, 1] * b2) / det, (r1[:, 0] * b2 - b1 * r2[:, 0]) / det], -1)


def _history(lk: Linkage, motion: ClosedMotion, deg: np.ndarray, speed_hz: float) -> ReactionHistory:
    """The joint forces and driver torque balancing the bodies' loads on ``motion``."""
    theta, kind, mo = motion.theta, motion.kind, motion.bodies
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
    pos = motion.joints
    A, B = pos["A"], pos["B"]
    if kind == "four-bar":
        # rocker about O4: (B - O4) x F_B = -M_r;  coupler about A: (B - A) x F_B = M_c
        FB = _cramer(perp(B - mo["rocker"][3]), -M["rocker"], perp(B - A), M["coupler"])
        FA = FB - D["coupler"]
        forces = {"O2": FA - D["crank"], "A": FA, "B": FB, "O4": -FB - D["rocker"]}
    else:
        u = np.broadcast_to([1.0, 0.0], B.shape)
        # rod about A: (B - A) x F_B = M_rod;  slider along the slide: u · F_B = -u · D_s
        FB = _cramer(perp(B - A), M["rod"], u, -D["slider"][:, 0])
        FA = FB - D["rod"]
        forces = {"O2": FA - D["crank"], "A": FA, "B": FB, "slide": -FB - D["slider"]}
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
                           evaluator=lambda a: _at(lk, np.atleast_1d(np.asarray(a, float)), speed_hz))


def _at(lk: Linkage, deg: np.ndarray, speed_hz: float) -> ReactionHistory | None:
    motion = closed_motion(lk, np.radians(deg), 2 * np.pi * speed_hz)
    return None if motion is None else _history(lk, motion, deg, speed_hz)


def closed_form(lk: Linkage, crank_deg: np.ndarray, speed_hz: float) -> ReactionHistory | None:
    """Reaction history of a toggle-free rig four-bar or slider-crank in closed form, or None.

    A linkage that enters the toggle band (``MU_TOGGLE_DEG``) anywhere in the turn is left
    to the general solver, whose continuation reports the toggle ranges.
    """
    return _at(lk, np.asarray(crank_deg, float), float(speed_hz))
