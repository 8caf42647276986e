"""Joint reactions and driver torque of a planar linkage over a crank turn.

A toggle-free rig four-bar or slider-crank is solved in closed form (``rigfem.dynamics.closed``);
any other linkage is moved by the general planar solver (:mod:`rigfem.linkage.general`) and
its reactions follow from the inverse dynamics Phi_q^T lambda = Q_ext - Q_inertia
(Newton–Euler about the centre of mass of every body, point masses as particles).
The public interface is in mm, N, N·m, degrees (see ``rigfem.dynamics.history``).
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.closed import closed_reactions
from rigfem.dynamics.forces import applied, cross, inertia_load
from rigfem.dynamics.history import JointHistory, ReactionHistory, merge_ranges, singular_ranges
from rigfem.linkage.general import RCOND_SINGULAR
from rigfem.linkage.model import CrankDriver, Linkage, LinkageState, Revolute, SliderDriver
from rigfem.linkage.state import linkage_state

__all__ = ["solve"]


def solve(lk: Linkage, crank_deg: np.ndarray, speed_hz: float = 1.0, tol_mm: float = 1e-9,
          check_closure: bool = True, general: bool = False) -> ReactionHistory:
    """Positions, velocities, accelerations and reactions at the driver phases ``crank_deg``.

    A toggle-free rig four-bar or slider-crank is solved in closed form
    (``rigfem.dynamics.closed``, ``meta["solver"] = "closed form"``); ``general=True`` forces
    the general solver (the reference the closed forms are tested against).

    ``crank_deg`` must be increasing (an evenly spaced full turn for a crank); the driver
    turns at ``speed_hz`` (negative = clockwise).  Returns a ReactionHistory whose
    ``singular_mask`` flags toggle samples and whose ``evaluator`` re-solves at any angle.
    """
    deg = np.asarray(crank_deg, float)
    motion = linkage_state(lk, deg, speed_hz, tol_mm, check_closure, general)
    if motion.general is None:
        return closed_reactions(lk, motion, deg, speed_hz)
    h = _dynamics(lk, motion, deg, speed_hz)
    if motion.probe is not None:  # toggles between the samples, seen at the continuation points
        probe = _dynamics(lk, motion.probe, np.degrees(motion.probe.theta), speed_hz)
        h.meta["singular"] = merge_ranges(h.meta["singular"], probe.meta["singular"])
    return h


def _dynamics(lk: Linkage, motion: LinkageState, deg: np.ndarray, speed_hz: float) -> ReactionHistory:
    """Newton–Euler on the solved motion: Phi_q^T lambda = Q gives every joint reaction and the
    driver torque (or force); toggles where the Jacobian is ill-conditioned or lambda not finite."""
    gen = motion.general
    n = deg.size
    g = np.asarray(lk.gravity_mm_s2, float) / 1000
    Q = np.zeros((n, gen.n_coords))
    for b in lk.bodies:
        i = 3 * gen.index[b.name]
        f, mo = inertia_load(motion.bodies[b.name], g)
        Q[:, i:i + 2] += f
        Q[:, i + 2] += mo
    for ld, arm in zip(lk.loads, motion.load_arms):
        i = 3 * gen.index[ld.body]
        f, mo = applied(ld, arm, motion)
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
    meta["singular"] = singular_ranges(deg, bad)
    h = ReactionHistory(deg, joints, drive, motion.histories, meta, singular_mask=bad if bad.any() else None)

    def evaluator(angles: np.ndarray) -> ReactionHistory:
        a = np.atleast_1d(np.asarray(angles, float))
        return _dynamics(lk, motion.at(a), a, speed_hz)

    h.evaluator = evaluator
    return h
