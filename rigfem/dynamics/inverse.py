"""General planar inverse dynamics: Phi_q^T lambda = Q_ext - Q_inertia on the motion the general
solver (:mod:`rigfem.linkage.general`) hands over, for any one-degree-of-freedom linkage.

Newton–Euler about every body's frame origin (the body loads of
:func:`rigfem.dynamics.forces.body_loads`); the multipliers lambda are the joint reactions and
the driver's torque (or force).  Toggles: where the scaled constraint Jacobian is
ill-conditioned or lambda is not finite.  SI inside; the history in mm, N, N·m, degrees.
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.forces import cross
from rigfem.dynamics.history import JointHistory, ReactionHistory, merge_ranges
from rigfem.linkage.general import RCOND_SINGULAR
from rigfem.linkage.loops import singular_ranges
from rigfem.linkage.model import (
    CrankDriver,
    Linkage,
    LinkageState,
    Revolute,
    SliderDriver,
)

__all__ = ["general_reactions"]


def general_reactions(lk: Linkage, motion: LinkageState, loads: dict, deg: np.ndarray, speed_hz: float,
                      probe: tuple[LinkageState, dict] | None = None) -> ReactionHistory:
    """Every joint reaction and the driver torque (or force) balancing the bodies' ``loads`` on the
    general solver's ``motion`` at ``deg``; ``probe`` (the motion at the solver's continuation
    points and its loads) adds the toggles met between the samples to ``meta["singular"]``."""
    gen = motion.general
    Q = np.zeros((deg.size, gen.n_coords))
    for name, (f, mo) in loads.items():
        i = 3 * gen.index[name]
        Q[:, i:i + 2] += f
        Q[:, i + 2] += mo
    lam = np.einsum("nji,nj->ni", gen.Jinv, Q)               # Phi_q^T lambda = Q
    joints: dict[str, JointHistory] = {}
    for j, r in zip(lk.joints, gen.rows):
        # force by a on b = (dPhi/dr_a)^T lambda  (equal and opposite to the force on a)
        pos, sb, _, nn = gen.frames[j.name]
        if isinstance(j, Revolute):
            fab = lam[:, r:r + 2]
            mom = None
        else:
            fab = -nn * lam[:, r][:, None]
            # moment on b about its sliding point: -(dPhi/dphi_b)^T lambda - sb x F_on_b
            m_origin = -(lam[:, r] * cross(sb, nn) + lam[:, r + 1])
            mom = m_origin - cross(sb, fab)
        joints[j.name] = JointHistory(j.name, j.body_a, j.body_b, fab, pos * 1000, mom,
                                      "revolute" if isinstance(j, Revolute) else "prismatic")
    dv = lk.driver
    # motor torque on the crank (N·m), or actuator force on the slider along its axis (N)
    drive = -lam[:, gen.drow]
    if isinstance(dv, SliderDriver):
        # the actuator pushes along the slide: part of that joint's force by body_a on body_b
        joints[dv.joint].force_N = joints[dv.joint].force_N + gen.frames[dv.joint][2] * drive[:, None]
    rcond = gen.rcond
    bad = ~np.isfinite(lam).all(1) | (rcond < RCOND_SINGULAR)
    meta = dict(lk.meta)
    meta.update(speed_hz=speed_hz, driver_unit="N·m" if isinstance(dv, CrankDriver) else "N",
                rcond_min=float(rcond.min()), solver="general")
    if gen.warnings:
        meta["warnings"] = list(gen.warnings)
    extra = lk.meta.get("singular_fn")
    if extra is not None:
        meta.pop("singular_fn")
        bad |= extra(deg, motion.histories)
    # values inside a flagged range stay (finite) for plotting the approach to the toggle;
    # non-finite ones (exactly at the toggle) become 0; peaks() refuses both
    for jh in joints.values():
        jh.force_N = np.where(np.isfinite(jh.force_N), jh.force_N, 0.0)
    drive = np.where(np.isfinite(drive), drive, 0.0)
    seen = None
    if probe is not None:  # toggles between the samples, seen at the continuation points
        seen = general_reactions(lk, probe[0], probe[1], np.degrees(probe[0].theta), speed_hz).meta["singular"]
    meta["singular"] = merge_ranges(singular_ranges(deg, bad), seen)
    return ReactionHistory(deg, joints, drive, motion.histories, meta, singular_mask=bad if bad.any() else None,
                           full_turn=motion.full_turn)
