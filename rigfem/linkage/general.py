"""The general planar solver's motion: positions, velocities and accelerations of any
one-degree-of-freedom linkage (:mod:`rigfem.linkage.model`) at given driver phases.

* positions: Newton on Phi(q, theta) = 0.  A sequential continuation in crank angle
  theta (third-order predictor, step halving, sign of det(Phi_q) kept) follows one
  assembly branch through the turn; all samples are then solved at once by Newton
  from a quintic Hermite predictor through the continuation points, and checked to be
  on the same branch;
* velocities: Phi_q qdot = -Phi_t;  accelerations: Phi_q qddot = gamma.

Every stage after the continuation pass is vectorised over crank angles.  The forces
(inverse dynamics) build on this in :mod:`rigfem.dynamics.solver`, which gets the whole
motion in one call (:func:`rigfem.linkage.state.linkage_state`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigfem.errors import ComputeError
from rigfem.linkage.constraints import Constraints
from rigfem.linkage.loops import is_full_turn
from rigfem.linkage.model import (
    AssemblyError,
    BodyHistory,
    CrankDriver,
    GeneralState,
    Linkage,
    LinkageState,
    Revolute,
    SliderDriver,
    state_of,
)

__all__ = ["RCOND_SINGULAR", "STEP_CORRECTION", "SAMPLE_CORRECTION", "MIN_STEP", "Trace", "trace", "positions",
           "rates", "conditioning", "general_motion", "move"]

#: 1-norm reciprocal condition number of the length-scaled Jacobian below which a sample is
#: flagged as a toggle (for the rig four-bar about mu within 0.6 deg of 0 or 180; the four-bar
#: builder adds its own mu criterion, kinematics.MU_TOGGLE_DEG)
RCOND_SINGULAR = 2e-3


def _newton(model: Constraints, q: np.ndarray, theta: np.ndarray, tol: float, maxit: int = 25):
    """Vectorised Newton; returns (q, converged mask)."""
    q = q.copy()
    ok = np.zeros(q.shape[0], bool)
    for _ in range(maxit):
        fr = model.frame(q)
        res = model.residual(q, theta, fr)
        err = np.max(np.abs(res), axis=1)
        ok = err < tol
        if ok.all():
            break
        J = model.jacobian(q, fr)
        try:
            dq = np.linalg.solve(J, res[..., None])[..., 0]
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(dq)):
            break
        q -= dq
        # constraint functions have second derivatives bounded by ~scale, so after a step
        # this small the residual is below ~scale·|dq|^2 < tol: converged without re-evaluating
        if np.max(np.abs(dq)) < np.sqrt(0.1 * tol / model.scale):
            ok[:] = True
            break
    return q, ok


def rates(model: Constraints, q: np.ndarray, theta: np.ndarray, omega: float):
    """Velocities, accelerations and the inverse constraint Jacobian at solved positions."""
    fr = model.frame(q)
    J = model.jacobian(q, fr)
    _, d1, d2 = model.drive(theta)
    with np.errstate(all="ignore"):
        try:
            Jinv = np.linalg.inv(J)
        except np.linalg.LinAlgError:       # an exactly singular sample: solve one by one
            Jinv = np.stack([np.linalg.pinv(x) for x in J])
    # the rates by the phase (dq/dtheta, d2q/dtheta2: the linkage's geometry), then by time at a
    # constant ``omega`` (gamma is quadratic in the rates: d2q/dt2 = omega² d2q/dtheta2)
    q1 = Jinv[:, :, model.drow] * d1[:, None]
    q2 = np.einsum("nij,nj->ni", Jinv, model.gamma(q, q1, d2, fr))
    return omega * q1, omega**2 * q2, J, Jinv


def _guess_vector(model: Constraints) -> np.ndarray:
    q = np.zeros(model.m)
    for b in model.lk.bodies:
        if b.name not in model.lk.guess:
            raise ComputeError(f"no initial pose for body {b.name!r}")
        x, y, p = model.lk.guess[b.name]
        i = 3 * model.index[b.name]
        q[i:i + 3] = x / 1000, y / 1000, p
    return q


def _guess_phase(lk: Linkage) -> float:
    """Driver phase (rad) at which ``lk.guess`` is given: the crank body's guessed angle, or 0
    for a driven slider (its guess is at s = mean)."""
    d = lk.driver
    return float(lk.guess[d.body][2] - d.offset_rad) if isinstance(d, CrankDriver) else 0.0


#: continuation step acceptance: the corrector may move a body by at most this fraction of the
#: linkage size (or this many radians) away from the prediction, so it cannot reach the other
#: assembly branch unless the two are closer than that (i.e. at a flagged toggle)
STEP_CORRECTION = 0.05


#: largest corrector move (fraction of the linkage size, or rad) from the Hermite prediction
#: accepted for a sample before falling back to sequential continuation through the samples
SAMPLE_CORRECTION = 1e-3


#: steps below this (rad) are accepted as they come: the linkage passes (through) a toggle
MIN_STEP = 1e-6


def _scaled(model: Constraints) -> np.ndarray:
    """Weights making q dimensionless: positions / linkage size, angles as they are."""
    sc = np.ones(model.m)
    sc[0::3] = sc[1::3] = 1.0 / model.scale
    return sc


def _continuation(model: Constraints, theta_nodes: np.ndarray, q0: np.ndarray, tol: float,
                  warnings: list[str] | None = None):
    """Sequential continuation through ``theta_nodes`` (rad, in order).

    Third-order predictor (q, q', q'' and q''' estimated from the previous step), Newton
    corrector.  A step is accepted only if the corrector stays within ``STEP_CORRECTION``
    of the prediction (position, and velocity times step) and the sign of det(Phi_q) is
    unchanged — two assembly branches meet only where det(Phi_q) = 0, so a sign change
    means a jump.  Otherwise the step is halved; steps below ``MIN_STEP`` mean the linkage
    passes an exact toggle: the step is taken and a warning recorded.

    Returns every accepted point (theta, q, q', q'') — derivatives per unit theta — and the
    indices of ``theta_nodes`` among them.  AssemblyError where the loop cannot close.
    """
    sc = _scaled(model)
    q, ok = _newton(model, q0[None], theta_nodes[:1], tol)
    if not ok[0]:
        raise AssemblyError(f"linkage cannot be assembled at crank angle {np.degrees(theta_nodes[0]):.2f} deg")
    q = q[0]
    qd, qdd, J, _ = (x[0] for x in rates(model, q[None], theta_nodes[:1], 1.0))
    sign = np.sign(np.linalg.det(J))
    q3 = np.zeros(model.m)
    th = theta_nodes[0]
    out_th, out_q, out_qd, out_qdd, node_idx = [th], [q], [qd], [qdd], [0]
    for k in range(1, theta_nodes.size):
        target = theta_nodes[k]
        while th != target:
            h = target - th
            while True:
                pred = q + h * (qd + h * (qdd / 2 + h * q3 / 6))
                qn, okn = _newton(model, pred[None], np.array([th + h]), tol)
                if okn[0]:
                    qdn, qddn, Jn, _ = (x[0] for x in rates(model, qn, np.array([th + h]), 1.0))
                    sgn = np.sign(np.linalg.det(Jn))
                    dv = np.max(np.abs((qdn - qd - h * (qdd + h * q3 / 2)) * sc)) * abs(h)
                    dp = np.max(np.abs((qn[0] - pred) * sc))
                    if abs(h) < MIN_STEP or (dp <= STEP_CORRECTION and dv <= STEP_CORRECTION and sgn == sign):
                        break
                elif abs(h) < MIN_STEP:
                    raise AssemblyError(
                        f"linkage cannot be assembled beyond crank angle {np.degrees(th):.2f} deg "
                        f"(before {np.degrees(target):.2f} deg)")
                h *= 0.5
            if abs(h) < MIN_STEP:
                sign = sgn
                if warnings is not None:
                    warnings.append(f"the linkage passes a toggle near crank angle {np.degrees(th):.2f} deg")
            q3 = (qddn - qdd) / h
            q, qd, qdd = qn[0], qdn, qddn
            th = th + h if abs(target - th - h) > 1e-15 else target
            out_th.append(th)
            out_q.append(q)
            out_qd.append(qd)
            out_qdd.append(qdd)
        node_idx.append(len(out_th) - 1)
    return (np.array(out_th), np.array(out_q), np.array(out_qd), np.array(out_qdd), np.array(node_idx))


def _predict(nodes, qc, qdc, qddc, theta):
    """Position predictor at ``theta`` from the coarse continuation nodes: quintic Hermite
    between the bracketing nodes (q, q', q'' at both ends), second-order Taylor outside."""
    k = np.clip(np.searchsorted(nodes, theta, side="right") - 1, 0, nodes.size - 2)
    h = nodes[k + 1] - nodes[k]
    h = np.where(h == 0.0, 1.0, h)          # a one-angle solve has coincident nodes
    s = ((theta - nodes[k]) / h)[:, None]
    hh = h[:, None]
    s3, s4, s5 = s**3, s**4, s**5
    herm = ((1 - 10 * s3 + 15 * s4 - 6 * s5) * qc[k] + (s - 6 * s3 + 8 * s4 - 3 * s5) * hh * qdc[k]
            + (0.5 * s**2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * hh**2 * qddc[k]
            + (10 * s3 - 15 * s4 + 6 * s5) * qc[k + 1] + (-4 * s3 + 7 * s4 - 3 * s5) * hh * qdc[k + 1]
            + (0.5 * s3 - s4 + 0.5 * s5) * hh**2 * qddc[k + 1])
    near = np.where(s[:, 0] < 0.5, k, k + 1)
    d = (theta - nodes[near])[:, None]
    taylor = qc[near] + qdc[near] * d + 0.5 * qddc[near] * d * d
    inside = ((s >= 0) & (s <= 1))
    return np.where(inside, herm, taylor), near, d


@dataclass
class Trace:
    """One assembly branch followed through the turn: the continuation points (theta rad,
    q, q', q'' per unit theta) every later solve predicts from, and what the pass noticed."""

    model: Constraints
    theta: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    warnings: list[str]
    tol: float


def trace(lk: Linkage, crank_deg: np.ndarray, tol_mm: float = 1e-9, check_closure: bool = True) -> Trace:
    """Follow ``lk``'s assembly branch (chosen by ``lk.guess``) over the increasing angles
    ``crank_deg``: coarse continuation at <= 20 deg steps; over a full turn of a crank, the
    loop is closed back to the start (a branch change becomes a warning)."""
    deg = np.asarray(crank_deg, float)
    model = Constraints(lk)
    theta = np.radians(deg)
    tol = tol_mm / 1000
    span = theta[-1] - theta[0]
    n_c = max(2, int(np.ceil(abs(span) / np.radians(20.0))) + 1)
    nodes = np.linspace(theta[0], theta[-1], n_c)
    q0 = _guess_vector(model)
    th_guess = _guess_phase(lk)
    if abs(th_guess - theta[0]) > 1e-12:
        # the guess describes the linkage at its own phase: continue from there to theta[0]
        q0 = _continuation(model, np.array([th_guess, theta[0]]), q0, tol)[1][-1]
    warnings: list[str] = []
    th_c, qc, qdc, qddc, _ = _continuation(model, nodes, q0, tol, warnings)
    if check_closure and is_full_turn(deg) and isinstance(lk.driver, CrankDriver):
        qend = _continuation(model, np.array([theta[-1], theta[0] + 2 * np.pi]), qc[-1], tol)[1][-1]
        diff = qend - qc[0]
        diff[2::3] = np.angle(np.exp(1j * diff[2::3]))
        if np.max(np.abs(diff)) > 1e3 * tol + 1e-6 * model.scale:
            warnings.append("the linkage does not return to its starting configuration after one "
                            "turn (branch change at a toggle)")
    return Trace(model, th_c, qc, qdc, qddc, warnings, tol)


def positions(tr: Trace, crank_deg: np.ndarray, speed_hz: float):
    """(q, qd, qdd, J, Jinv) at ``crank_deg`` on the traced branch, the driver at ``speed_hz``."""
    model, nodes, qc, qdc, qddc = tr.model, tr.theta, tr.q, tr.qd, tr.qdd
    theta = np.radians(np.asarray(crank_deg, float))
    pred, near, _ = _predict(nodes, qc, qdc, qddc, theta)
    q, ok = _newton(model, pred, theta, tr.tol)
    omega = 2 * np.pi * speed_hz
    qd, qdd, J, Jinv = rates(model, q, theta, omega)
    # same branch as the continuation points: the Hermite predictor is accurate to ~1e-5 of
    # the linkage size, so a corrector moving further than SAMPLE_CORRECTION is suspect
    far = np.max(np.abs((q - pred) * _scaled(model)), axis=1) > SAMPLE_CORRECTION
    if not ok.all() or far.any():
        # fall back to strict continuation through the samples (in order of angle)
        order = np.argsort(theta)
        ext = np.concatenate([[nodes[near[order[0]]]], theta[order]])
        res = _continuation(model, ext, qc[near[order[0]]], tr.tol)
        q[order] = res[1][res[4][1:]]
        qd, qdd, J, Jinv = rates(model, q, theta, omega)
    return q, qd, qdd, J, Jinv


def conditioning(model: Constraints, J: np.ndarray, Jinv: np.ndarray) -> np.ndarray:
    """1-norm reciprocal condition number of the length-scaled Jacobian per sample (0 where
    it is not finite): below ``RCOND_SINGULAR`` the linkage is at a toggle."""
    lk = model.lk
    S = np.ones(model.m)
    S[0::3] = S[1::3] = model.scale
    rowscale = np.ones(model.m)
    for j, r in zip(lk.joints, model.rows):
        rowscale[r] = 1 / model.scale
        if isinstance(j, Revolute):
            rowscale[r + 1] = 1 / model.scale
    if isinstance(lk.driver, SliderDriver):
        rowscale[model.drow] = 1 / model.scale
    # scaled J = R J S  ->  inverse = S^-1 J^-1 R^-1
    # (column sums by a matrix product: much faster than a reduction over a length-9 axis)
    ones = np.ones(model.m)
    norm = (ones @ np.abs(J * (rowscale[:, None] * S[None, :]))).max(1)
    inv_norm = (ones @ np.abs(Jinv / (S[:, None] * rowscale[None, :]))).max(1)
    with np.errstate(all="ignore"):
        rcond = 1.0 / (norm * inv_norm)
    return np.where(np.isfinite(rcond), rcond, 0.0)


def _state(tr: Trace, deg: np.ndarray, q, qd, qdd, J, Jinv, probe: tuple | None = None) -> LinkageState:
    """The whole motion at solved coordinates: bodies, joints' geometry, conditioning; ``probe``
    (deg, q, qd, qdd, J, Jinv) the coordinates at the continuation points (the state's ``probe``)."""
    sub = None if probe is None else _state(tr, *probe)
    model, lk = tr.model, tr.model.lk
    fr = model.frame(q)
    frames = {}
    for j in lk.joints:
        rb, _ = model.pose(q, j.body_b)
        sb = fr[j.name][1]
        frames[j.name] = (np.broadcast_to(rb + sb, (q.shape[0], 2)), sb,
                          *((None, None) if isinstance(j, Revolute) else fr[j.name][2:4]))
    motion = {}
    for b in lk.bodies:
        i = 3 * model.index[b.name]
        motion[b.name] = (q[:, i + 2], qd[:, i + 2], qdd[:, i + 2], q[:, i:i + 2], qd[:, i:i + 2], qdd[:, i:i + 2])
    gen = GeneralState(model.m, dict(model.index), list(model.rows), model.drow, Jinv,
                       conditioning(model, J, Jinv), frames, list(tr.warnings))
    st = state_of(lk, np.radians(deg), motion, {n: f[0] for n, f in frames.items()}, "general", gen, q, qd)
    st.probe = sub
    return st


def _on_branch(tr: Trace, deg: np.ndarray, speed_hz: float, probe: tuple | None = None) -> LinkageState:
    """The motion at ``deg`` on the traced branch; ``probe``: (deg, q, qd, qdd, J, Jinv) at the
    continuation points, whose motion becomes the state's ``probe``."""
    def at(angles: np.ndarray) -> LinkageState:
        return _on_branch(tr, np.atleast_1d(np.asarray(angles, float)), speed_hz)

    q, qd, qdd, J, Jinv = positions(tr, deg, speed_hz)
    st = _state(tr, deg, q, qd, qdd, J, Jinv, probe)
    st.at = at
    return st


def general_motion(lk: Linkage, crank_deg: np.ndarray, speed_hz: float = 1.0, tol_mm: float = 1e-9,
                   check_closure: bool = True) -> LinkageState:
    """``lk``'s whole motion at the increasing driver phases ``crank_deg`` (deg) at ``speed_hz``,
    in one piece: traced, solved, with the motion at the continuation points as ``probe`` where
    they are denser than the samples (a toggle narrower than the sampling shows there)."""
    deg = np.asarray(crank_deg, float)
    tr = trace(lk, deg, tol_mm, check_closure)
    theta = np.radians(deg)
    probe = None
    if tr.theta.size > 1 and deg.size > 1 and np.min(np.abs(np.diff(tr.theta))) < abs(theta[1] - theta[0]):
        probe = (np.degrees(tr.theta), tr.q, *rates(tr.model, tr.q, tr.theta, 2 * np.pi * speed_hz))
    return _on_branch(tr, deg, speed_hz, probe)


def move(lk: Linkage, crank_deg: np.ndarray, speed_hz: float = 1.0) -> dict[str, BodyHistory]:
    """Every body's motion at the increasing driver phases ``crank_deg`` (deg) at ``speed_hz``."""
    tr = trace(lk, crank_deg)
    return _state(tr, np.asarray(crank_deg, float), *positions(tr, crank_deg, speed_hz)).histories
