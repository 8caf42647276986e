"""Joint reactions and driver torque of a planar linkage over a crank turn.

A toggle-free rig four-bar or slider-crank is solved in closed form (``rigfem.dynamics.closed``);
any other linkage is moved by the general planar solver (:mod:`rigfem.linkage.general`) and
its reactions follow from the inverse dynamics Phi_q^T lambda = Q_ext - Q_inertia
(Newton–Euler about the centre of mass of every body, point masses as particles).
The public interface is in mm, N, N·m, degrees (see ``rigfem.dynamics.history``).
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.closed import closed_form
from rigfem.dynamics.forces import applied, inertia_load
from rigfem.dynamics.history import JointHistory, ReactionHistory, merge_ranges, singular_ranges
from rigfem.linkage.constraints import dot
from rigfem.linkage.general import RCOND_SINGULAR, Trace, body_motion, conditioning, positions, rates, trace
from rigfem.linkage.model import CrankDriver, Linkage, Revolute, SliderDriver, cross, perp

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
    fast = None if general else closed_form(lk, deg, speed_hz)
    if fast is not None:
        return fast
    tr = trace(lk, deg, tol_mm, check_closure)
    h = _evaluate(lk, tr, deg, speed_hz)
    # a toggle narrower than the sampling still shows at the continuation points, which are
    # locally denser than the samples wherever the continuation had to shorten its steps
    theta = np.radians(deg)
    if tr.theta.size > 1 and deg.size > 1 and np.min(np.abs(np.diff(tr.theta))) < abs(theta[1] - theta[0]):
        qd_c, qdd_c, J_c, Jinv_c = rates(tr.model, tr.q, tr.theta, 2 * np.pi * speed_hz)
        probe = _dynamics(lk, tr, np.degrees(tr.theta), tr.q, qd_c, qdd_c, J_c, Jinv_c, speed_hz)
        h.meta["singular"] = merge_ranges(h.meta["singular"], probe.meta["singular"])
    return h


def _evaluate(lk: Linkage, tr: Trace, deg: np.ndarray, speed_hz: float) -> ReactionHistory:
    return _dynamics(lk, tr, deg, *positions(tr, deg, speed_hz), speed_hz)


def _dynamics(lk: Linkage, tr: Trace, deg, q, qd, qdd, J, Jinv, speed_hz) -> ReactionHistory:
    """Newton–Euler at solved motion: Phi_q^T lambda = Q gives every joint reaction and the
    driver torque (or force); toggles where the Jacobian is ill-conditioned or lambda not finite."""
    model = tr.model
    n = q.shape[0]
    g = np.asarray(lk.gravity_mm_s2, float) / 1000
    Q = np.zeros((n, model.m))
    for b in lk.bodies:
        i = 3 * model.index[b.name]
        f, mo = inertia_load(b, q[:, i + 2], qd[:, i + 2], qdd[:, i + 2], qdd[:, i:i + 2], g)
        Q[:, i:i + 2] += f
        Q[:, i + 2] += mo
    for ld in lk.loads:
        i = 3 * model.index[ld.body]
        f, mo = applied(ld, np.radians(deg), q[:, i:i + 2], q[:, i + 2], q, qd)
        Q[:, i:i + 2] += f
        Q[:, i + 2] += mo
    lam = np.einsum("nji,nj->ni", Jinv, Q)               # Phi_q^T lambda = Q
    joints: dict[str, JointHistory] = {}
    fr = model.frame(q)
    for j, r in zip(lk.joints, model.rows):
        # force by a on b = (dPhi/dr_a)^T lambda  (equal and opposite to the force on a)
        if isinstance(j, Revolute):
            fab = lam[:, r:r + 2]
            rb, _ = model.pose(q, j.body_b)
            pos = rb + fr[j.name][1]
            mom = None
        else:
            rb, _ = model.pose(q, j.body_b)
            sa, sb, u, nn, d = fr[j.name]
            fab = -nn * lam[:, r][:, None]
            pos = rb + sb
            # moment on b about its sliding point: -(dPhi/dphi_b)^T lambda - sb x F_on_b
            m_origin = -(lam[:, r] * dot(nn, perp(sb)) + lam[:, r + 1])
            mom = m_origin - cross(sb, fab)
        pos = np.broadcast_to(pos, (n, 2)) * 1000
        joints[j.name] = JointHistory(j.name, j.body_a, j.body_b, fab, pos, mom,
                                      "revolute" if isinstance(j, Revolute) else "prismatic")
    bodies_out = body_motion(model, q, qd, qdd)
    dv = lk.driver
    # motor torque on the crank (N·m), or actuator force on the slider along its axis (N)
    drive = -lam[:, model.drow]
    if isinstance(dv, SliderDriver):
        # the actuator pushes along the slide: part of that joint's force by body_a on body_b
        joints[dv.joint].force_N = joints[dv.joint].force_N + fr[dv.joint][2] * drive[:, None]
    rcond = conditioning(model, J, Jinv)
    bad = ~np.isfinite(lam).all(1) | (rcond < RCOND_SINGULAR)
    meta = dict(lk.meta)
    meta.update(speed_hz=speed_hz, driver_unit="N·m" if isinstance(dv, CrankDriver) else "N",
                rcond_min=float(rcond.min()), solver="general")
    if tr.warnings:
        meta["warnings"] = list(tr.warnings)
    extra = lk.meta.get("singular_fn")
    if extra is not None:
        meta.pop("singular_fn")
        bad |= extra(deg, bodies_out)
    # values inside a flagged range stay (finite) for plotting the approach to the toggle;
    # non-finite ones (exactly at the toggle) become 0; peaks() refuses both
    for jh in joints.values():
        jh.force_N = np.where(np.isfinite(jh.force_N), jh.force_N, 0.0)
    drive = np.where(np.isfinite(drive), drive, 0.0)
    meta["singular"] = singular_ranges(deg, bad)
    h = ReactionHistory(deg, joints, drive, bodies_out, meta, singular_mask=bad if bad.any() else None)

    def evaluator(angles: np.ndarray) -> ReactionHistory:
        return _evaluate(lk, tr, np.atleast_1d(np.asarray(angles, float)), speed_hz)

    h.evaluator = evaluator
    return h
