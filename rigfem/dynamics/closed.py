"""Closed-form rigid-body dynamics of the rig's four-bar and slider-crank.

The general solver (``rigfem.linkage.general``) closes the loop by continuation and Newton
and inverts a 9×9 constraint Jacobian per crank angle; for the two linkages the rig is
built as, positions, rates and accelerations have closed forms
(``rigfem.linkage.closed``, handed over as a ``LinkageState`` by
``rigfem.linkage.state.linkage_state``) and the joint reactions follow from two moment balances
per angle (a 2×2 system solved in closed form), all vectorised over crank angles:

* four-bar: rocker about O4 and coupler about A give the force at B; force balances then
  give A, O4, O2, and the crank's moment about O2 the driver torque;
* slider-crank: rod about A and the slider's balance along the slide give the force at B.

Same sign conventions and units as the general solver (``rigfem.dynamics.history``).
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.forces import cross
from rigfem.dynamics.history import JointHistory, ReactionHistory
from rigfem.linkage.closed import change_point_turn
from rigfem.linkage.loops import change_points_deg, singular_ranges
from rigfem.linkage.model import Linkage, LinkageState, Prismatic

__all__ = ["closed_reactions"]


def _two_moments(r1: np.ndarray, m1: np.ndarray, r2: np.ndarray, m2: np.ndarray) -> np.ndarray:
    """F (n, 2) with r1 × F = m1 and r2 × F = m2 (lever arms (n, 2)): F = (m1 r2 - m2 r1) / (r1 × r2);
    not finite where the arms align (a change point: flagged as a toggle)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return (m1[:, None] * r2 - m2[:, None] * r1) / cross(r1, r2)[:, None]


def closed_reactions(lk: Linkage, motion: LinkageState, loads: dict, deg: np.ndarray,
                     speed_hz: float) -> ReactionHistory:
    """The joint forces and driver torque balancing the bodies' ``loads``
    (:func:`rigfem.dynamics.forces.body_loads`) on the closed-form ``motion`` (at ``deg``)."""
    D = {n: f for n, (f, _) in loads.items()}      # per body: applied + d'Alembert force,
    M = {n: m for n, (_, m) in loads.items()}      # its moment about the body's origin
    pos = motion.joints
    A, B = pos["A"], pos["B"]
    if motion.kind == "four-bar":
        # rocker about O4: (B - O4) x F_B = -M_r;  coupler about A: (B - A) x F_B = M_c
        FB = _two_moments(B - pos["O4"], -M["rocker"], B - A, M["coupler"])
        FA = FB - D["coupler"]
        forces = {"O2": FA - D["crank"], "A": FA, "B": FB, "O4": -FB - D["rocker"]}
    else:
        # slider along the slide: F_B,x = -D_s,x;  rod about A: (B - A) x F_B = M_rod
        r = B - A
        fx = -D["slider"][:, 0]
        FB = np.stack([fx, (M["rod"] + r[:, 1] * fx) / r[:, 0]], -1)
        FA = FB - D["rod"]
        forces = {"O2": FA - D["crank"], "A": FA, "B": FB, "slide": -FB - D["slider"]}
    with np.errstate(invalid="ignore"):  # an unbounded force at a change point (inf × 0): flagged below
        torque = cross(A, FA) - M["crank"]
    joints = {}
    for j in lk.joints:
        prism = isinstance(j, Prismatic)
        joints[j.name] = JointHistory(j.name, j.body_a, j.body_b, forces[j.name], pos[j.name] * 1000,
                                      -M["slider"] if prism else None, "prismatic" if prism else "revolute")
    bad = _toggles(lk, motion, deg, joints, torque)
    meta = {k: v for k, v in lk.meta.items() if k != "singular_fn"}
    meta.update(speed_hz=speed_hz, driver_unit="N·m", solver="closed form", singular=singular_ranges(deg, bad))
    if bad.any():  # non-finite values (a change point, an unbounded force) become 0; peaks() refuses them
        for jh in joints.values():
            jh.force_N = np.where(np.isfinite(jh.force_N), jh.force_N, 0.0)
        torque = np.where(np.isfinite(torque), torque, 0.0)
    return ReactionHistory(deg, joints, torque, motion.histories, meta,
                           singular_mask=bad if bad.any() else None, full_turn=motion.full_turn)


def _toggles(lk: Linkage, motion: LinkageState, deg: np.ndarray, joints: dict, torque: np.ndarray) -> np.ndarray:
    """The samples whose reactions are unbounded: a non-finite reaction or torque (of any linkage:
    an applied force can grow without bound, e.g. a compressor's gas without clearance) and, for a
    change-point four-bar (the one closed-form linkage that has toggles), the builder's
    transmission-angle criterion and the sample nearest each change point the samples pass."""
    bad = ~np.isfinite(torque) | np.any([~np.isfinite(j.force_N).all(1) for j in joints.values()], 0)
    L = lk.meta.get("lengths_mm") or {}
    if not change_point_turn(L, motion.kind):
        return bad
    if lk.meta.get("singular_fn") is not None:
        bad |= lk.meta["singular_fn"](deg, motion.histories)
    for c in change_points_deg(L["b2"], L["b3"], L["b4"], L["d"]):
        off = np.abs((deg - c + 180.0) % 360.0 - 180.0)
        step = np.max(np.diff(np.sort(deg))) if deg.size > 1 else 0.0
        if off.min() <= step:
            bad[np.argmin(off)] = True
    return bad
