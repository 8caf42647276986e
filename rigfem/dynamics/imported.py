"""The reactions stage with an external reaction history (``[check] reactions_csv``, read by
:func:`rigfem.io.reactions_csv.read_csv`) on the scene's linkage.

The history gives the joint forces and the driver torque; the linkage gives the joint positions and
the bodies' motion at the CSV's crank angles (to place the loads on the parts and, in cycle mode,
for the inertia loads).  Peaks are refined on a spline of the CSV.  A CSV whose forces do not
balance the linkage's inertia shows up as the force and moment imbalance of each free part
(above the tolerance the part is undecided).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rigfem.dynamics.history import (
    DynamicsOptions,
    JointHistory,
    ReactionHistory,
    Reactions,
    reactions_of,
    spline_evaluator,
)
from rigfem.dynamics.solver import reactions
from rigfem.errors import ComputeError
from rigfem.linkage.model import Linkage, LinkageState

__all__ = ["react"]


def react(lk: Linkage, motion: LinkageState, ext: ReactionHistory, options: DynamicsOptions) -> Reactions:
    """The reactions of the external history ``ext`` (read from ``options.reactions_csv``) on ``lk``,
    moving as ``motion`` says."""
    kin = reactions(lk, motion.at(ext.crank_deg), ext.crank_deg, options.speed_hz)
    missing = [n for n in kin.joints if n not in ext.joints]
    if missing:  # read_csv refuses such a CSV, given the linkage's joints (rigfem.pipeline does)
        raise ComputeError(f"reactions CSV {options.reactions_csv.name} lacks joint(s) {', '.join(missing)}; "
                           f"the linkage has {', '.join(kin.joints)}")
    sign = {n: -1.0 if (ext.joints[n].body_a, ext.joints[n].body_b) == (j.body_b, j.body_a) else 1.0
            for n, j in kin.joints.items()}
    forces = spline_evaluator(ext)
    meta = dict(kin.meta, model=f"imported from {options.reactions_csv.name}", singular=ext.meta["singular"],
                assumed=ext.meta["assumed"])

    def combine(f: ReactionHistory, k: ReactionHistory) -> ReactionHistory:
        joints = {n: JointHistory(n, j.body_a, j.body_b, sign[n] * f.joints[n].force_N, j.position_mm)
                  for n, j in k.joints.items()}
        return ReactionHistory(f.crank_deg, joints, f.torque_Nm, k.bodies, meta, evaluator=at,
                               full_turn=f.full_turn)

    def at(deg) -> ReactionHistory:
        d = np.atleast_1d(np.asarray(deg, float))
        order = np.argsort(d)  # the solver wants increasing angles; answer in the order asked
        k = kin.evaluator(d[order])  # the linkage's motion there, on the same branch
        back = np.argsort(order)
        for j in k.joints.values():
            j.position_mm = j.position_mm[back]
        k.bodies = {n: dataclasses.replace(b, angle_rad=b.angle_rad[back], omega_rad_s=b.omega_rad_s[back],
                                           alpha_rad_s2=b.alpha_rad_s2[back], origin_mm=b.origin_mm[back],
                                           origin_acc_mm_s2=b.origin_acc_mm_s2[back])
                    for n, b in k.bodies.items()}
        return combine(forces(d), k)

    return reactions_of(combine(ext, kin))
