"""General planar linkage solver: constraints, Newton closure, continuation over the turn, Newton–Euler inverse dynamics."""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.closed import closed_form
from rigfem.dynamics.history import (
    BodyHistory,
    JointHistory,
    ReactionHistory,
    is_full_turn,
    merge_ranges,
    singular_ranges,
)
from rigfem.dynamics.linkage import (
    GROUND,
    AssemblyError,
    CrankDriver,
    Linkage,
    Prismatic,
    Revolute,
    SliderDriver,
    cross,
    perp,
)
from rigfem.errors import InputError

_ZERO2, _ZERO1 = np.zeros((1, 2)), np.zeros(1)        # the ground's pose, broadcast over samples


#: 1-norm reciprocal condition number of the length-scaled Jacobian below which a sample is
#: flagged as a toggle (for the rig four-bar about mu within 0.6 deg of 0 or 180; the four-bar
#: builder adds its own mu criterion, kinematics.MU_TOGGLE_DEG)
RCOND_SINGULAR = 2e-3


# ----------------------------------------------------------------------------- helpers
def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


class _Model:
    """Index bookkeeping and vectorised constraint evaluation for one Linkage (SI units)."""

    def __init__(self, lk: Linkage):
        self.lk = lk
        names = [b.name for b in lk.bodies]
        if GROUND in names or len(set(names)) != len(names):
            raise InputError("body names must be unique and not 'ground'")
        self.index = {n: i for i, n in enumerate(names)}
        self.nb = len(names)
        self.m = 3 * self.nb
        rows, r = [], 0
        for j in lk.joints:
            for b in (j.body_a, j.body_b):
                if b != GROUND and b not in self.index:
                    raise InputError(f"joint {j.name}: unknown body {b!r}")
            rows.append(r)
            r += 2
        self.rows = rows
        self.drow = r
        if r + 1 != self.m:
            raise InputError(f"linkage has {self.nb} bodies and {r} joint constraints + 1 driver: "
                             f"not a one-degree-of-freedom linkage")
        self.jidx = {j.name: k for k, j in enumerate(lk.joints)}
        self.loc = {j.name: (np.asarray(j.local_a_mm, float) / 1000, np.asarray(j.local_b_mm, float) / 1000)
                    for j in lk.joints}
        if isinstance(lk.driver, SliderDriver):
            if lk.driver.joint not in self.jidx or not isinstance(lk.joints[self.jidx[lk.driver.joint]], Prismatic):
                raise InputError(f"slider driver: {lk.driver.joint!r} is not a prismatic joint")
        elif lk.driver.body not in self.index:
            raise InputError(f"crank driver: unknown body {lk.driver.body!r}")
        pts = [np.asarray(p, float) for j in lk.joints for p in (j.local_a_mm, j.local_b_mm)]
        self.scale = max(1e-3, max((np.hypot(*p) for p in pts), default=1.0) / 1000, *(
            np.hypot(g[0], g[1]) / 1000 for g in lk.guess.values()))

    # -- pose access
    def pose(self, q: np.ndarray, body: str):
        """(r (n,2), phi (n,)) of a body; ground -> zeros of shape (1, 2), (1,) (broadcasting)."""
        if body == GROUND:
            return _ZERO2, _ZERO1
        i = 3 * self.index[body]
        return q[:, i:i + 2], q[:, i + 2]

    def cols(self, body: str):
        return None if body == GROUND else 3 * self.index[body]

    # -- driver target
    def drive(self, theta: np.ndarray, omega: float):
        """Driver value, rate and second rate at phase theta (rad; SI)."""
        d = self.lk.driver
        if isinstance(d, CrankDriver):
            return theta + d.offset_rad, np.full_like(theta, omega), np.zeros_like(theta)
        a = d.amplitude_mm / 1000
        return (d.mean_mm / 1000 + a * np.sin(theta), a * omega * np.cos(theta),
                -a * omega**2 * np.sin(theta))

    def frame(self, q: np.ndarray) -> dict:
        """Per-joint rotated local vectors (and prismatic axis, normal, gap) at positions q."""
        n_s = q.shape[0]
        C, S = np.cos(q[:, 2::3]), np.sin(q[:, 2::3])

        def rot(body, s):
            if body == GROUND:
                return s[None, :]
            k = self.index[body]
            out = np.empty((n_s, 2))
            out[:, 0] = C[:, k] * s[0] - S[:, k] * s[1]
            out[:, 1] = S[:, k] * s[0] + C[:, k] * s[1]
            return out

        fr = {}
        for j in self.lk.joints:
            sa, sb = rot(j.body_a, self.loc[j.name][0]), rot(j.body_b, self.loc[j.name][1])
            if isinstance(j, Revolute):
                fr[j.name] = (sa, sb)
            else:
                ra, _ = self.pose(q, j.body_a)
                rb, _ = self.pose(q, j.body_b)
                ax = np.asarray(j.axis_a, float)
                u = rot(j.body_a, ax / np.hypot(*ax))
                fr[j.name] = (sa, sb, u, perp(u), rb + sb - ra - sa)
        return fr

    def residual(self, q: np.ndarray, theta: np.ndarray, fr: dict | None = None) -> np.ndarray:
        fr = fr if fr is not None else self.frame(q)
        n_s = q.shape[0]
        res = np.empty((n_s, self.m))
        for j, r in zip(self.lk.joints, self.rows):
            _, pa = self.pose(q, j.body_a)
            _, pb = self.pose(q, j.body_b)
            if isinstance(j, Revolute):
                ra, _ = self.pose(q, j.body_a)
                rb, _ = self.pose(q, j.body_b)
                sa, sb = fr[j.name]
                res[:, r:r + 2] = ra + sa - rb - sb
            else:
                _, _, _, n, d = fr[j.name]
                res[:, r] = _dot(n, d)
                res[:, r + 1] = pb - pa - j.rel_angle_rad
        target = self.drive(theta, 0.0)[0]
        dv = self.lk.driver
        if isinstance(dv, CrankDriver):
            res[:, self.drow] = self.pose(q, dv.body)[1] - target
        else:
            _, _, u, _, d = fr[dv.joint]
            res[:, self.drow] = _dot(u, d) - target
        return res

    def jacobian(self, q: np.ndarray, fr: dict | None = None) -> np.ndarray:
        fr = fr if fr is not None else self.frame(q)
        n_s = q.shape[0]
        J = np.zeros((n_s, self.m, self.m))
        for j, r in zip(self.lk.joints, self.rows):
            ca, cb = self.cols(j.body_a), self.cols(j.body_b)
            if isinstance(j, Revolute):
                sa, sb = fr[j.name]
                if ca is not None:
                    J[:, r, ca] = J[:, r + 1, ca + 1] = 1.0
                    J[:, r:r + 2, ca + 2] = perp(sa)
                if cb is not None:
                    J[:, r, cb] = J[:, r + 1, cb + 1] = -1.0
                    J[:, r:r + 2, cb + 2] = -perp(sb)
            else:
                self._prism_rows(J, r, fr[j.name], ca, cb, normal=True)
                if ca is not None:
                    J[:, r + 1, ca + 2] = -1.0
                if cb is not None:
                    J[:, r + 1, cb + 2] = 1.0
        dv = self.lk.driver
        if isinstance(dv, CrankDriver):
            J[:, self.drow, self.cols(dv.body) + 2] = 1.0
        else:
            j = self.lk.joints[self.jidx[dv.joint]]
            self._prism_rows(J, self.drow, fr[j.name], self.cols(j.body_a), self.cols(j.body_b), normal=False)
        return J

    @staticmethod
    def _prism_rows(J, r, terms, ca, cb, normal: bool):
        """Row of n·d (normal=True) or u·d (the sliding coordinate)."""
        sa, sb, u, n, d = terms
        v, dv = (n, -u) if normal else (u, n)      # d v / d phi_a
        if ca is not None:
            J[:, r, ca:ca + 2] = -v
            J[:, r, ca + 2] = _dot(dv, d) - _dot(v, perp(sa))
        if cb is not None:
            J[:, r, cb:cb + 2] = v
            J[:, r, cb + 2] = _dot(v, perp(sb))

    def gamma(self, q: np.ndarray, qd: np.ndarray, sdd: np.ndarray, fr: dict | None = None) -> np.ndarray:
        """Right-hand side of Phi_q qddot = gamma (quadratic velocity terms)."""
        fr = fr if fr is not None else self.frame(q)
        n_s = q.shape[0]
        g = np.zeros((n_s, self.m))
        for j, r in zip(self.lk.joints, self.rows):
            _, wa = self.pose(qd, j.body_a)
            _, wb = self.pose(qd, j.body_b)
            if isinstance(j, Revolute):
                sa, sb = fr[j.name]
                g[:, r:r + 2] = sa * (wa**2)[:, None] - sb * (wb**2)[:, None]
            else:
                g[:, r] = self._prism_gamma(qd, j, fr[j.name], normal=True)
        dv = self.lk.driver
        if isinstance(dv, CrankDriver):
            g[:, self.drow] = sdd
        else:
            j = self.lk.joints[self.jidx[dv.joint]]
            g[:, self.drow] = sdd + self._prism_gamma(qd, j, fr[j.name], normal=False)
        return g

    def _prism_gamma(self, qd, j, terms, normal: bool) -> np.ndarray:
        sa, sb, u, n, d = terms
        va, wa = self.pose(qd, j.body_a)
        vb, wb = self.pose(qd, j.body_b)
        dd = vb + perp(sb) * wb[:, None] - va - perp(sa) * wa[:, None]
        v, w = (n, u) if normal else (u, -n)        # v' = -w * wa   (n' = -u wa, u' = n wa)
        return (wa**2 * _dot(v, d) + 2 * wa * _dot(w, dd)
                + _dot(v, sb * (wb**2)[:, None] - sa * (wa**2)[:, None]))


# ----------------------------------------------------------------------------- solver
def _newton(model: _Model, q: np.ndarray, theta: np.ndarray, tol: float, maxit: int = 25):
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


def _rates(model: _Model, q: np.ndarray, theta: np.ndarray, omega: float):
    """Velocities, accelerations and the inverse constraint Jacobian at solved positions."""
    fr = model.frame(q)
    J = model.jacobian(q, fr)
    _, sd, sdd = model.drive(theta, omega)
    with np.errstate(all="ignore"):
        try:
            Jinv = np.linalg.inv(J)
        except np.linalg.LinAlgError:       # an exactly singular sample: solve one by one
            Jinv = np.stack([np.linalg.pinv(x) for x in J])
    qd = Jinv[:, :, model.drow] * sd[:, None]
    qdd = np.einsum("nij,nj->ni", Jinv, model.gamma(q, qd, sdd, fr))
    return qd, qdd, J, Jinv


def _guess_vector(model: _Model) -> np.ndarray:
    q = np.zeros(model.m)
    for b in model.lk.bodies:
        if b.name not in model.lk.guess:
            raise InputError(f"no initial pose for body {b.name!r}")
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


def _scaled(model: _Model) -> np.ndarray:
    """Weights making q dimensionless: positions / linkage size, angles as they are."""
    sc = np.ones(model.m)
    sc[0::3] = sc[1::3] = 1.0 / model.scale
    return sc


def _continuation(model: _Model, theta_nodes: np.ndarray, q0: np.ndarray, tol: float,
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
    qd, qdd, J, _ = (x[0] for x in _rates(model, q[None], theta_nodes[:1], 1.0))
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
                    qdn, qddn, Jn, _ = (x[0] for x in _rates(model, qn, np.array([th + h]), 1.0))
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
    model = _Model(lk)
    theta = np.radians(deg)
    tol = tol_mm / 1000
    # coarse continuation at <= 20 deg steps, then a vectorised Newton for all samples
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
        # close the loop over the last step back to theta0 + 2 pi: same branch required
        qend = _continuation(model, np.array([theta[-1], theta[0] + 2 * np.pi]), qc[-1], tol)[1][-1]
        diff = qend - qc[0]
        diff[2::3] = np.angle(np.exp(1j * diff[2::3]))
        if np.max(np.abs(diff)) > 1e3 * tol + 1e-6 * model.scale:
            warnings.append("the linkage does not return to its starting configuration after one "
                            "turn (branch change at a toggle)")
    # every accepted continuation point serves the predictor (dense where the motion is fast)
    state = (model, th_c, qc, qdc, qddc, warnings)
    h = _evaluate(lk, state, deg, speed_hz, tol)
    # a toggle narrower than the sampling still shows at the continuation points, which are
    # locally denser than the samples wherever the continuation had to shorten its steps
    if th_c.size > 1 and deg.size > 1 and np.min(np.abs(np.diff(th_c))) < abs(theta[1] - theta[0]):
        qd_c, qdd_c, J_c, Jinv_c = _rates(model, qc, th_c, 2 * np.pi * speed_hz)
        probe = _dynamics(lk, model, state, np.degrees(th_c), qc, qd_c, qdd_c, J_c, Jinv_c, speed_hz, tol)
        h.meta["singular"] = merge_ranges(h.meta["singular"], probe.meta["singular"])
    return h


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


def _evaluate(lk: Linkage, state, deg: np.ndarray, speed_hz: float, tol: float) -> ReactionHistory:
    model, nodes, qc, qdc, qddc, _ = state
    theta = np.radians(deg)
    pred, near, h = _predict(nodes, qc, qdc, qddc, theta)
    q, ok = _newton(model, pred, theta, tol)
    omega = 2 * np.pi * speed_hz
    qd, qdd, J, Jinv = _rates(model, q, theta, omega)
    # same branch as the continuation points: the Hermite predictor is accurate to ~1e-5 of
    # the linkage size, so a corrector moving further than SAMPLE_CORRECTION is suspect
    far = np.max(np.abs((q - pred) * _scaled(model)), axis=1) > SAMPLE_CORRECTION
    if not ok.all() or far.any():
        # fall back to strict continuation through the samples (in order of angle)
        order = np.argsort(theta)
        ext = np.concatenate([[nodes[near[order[0]]]], theta[order]])
        res = _continuation(model, ext, qc[near[order[0]]], tol)
        q[order] = res[1][res[4][1:]]
        qd, qdd, J, Jinv = _rates(model, q, theta, omega)
    return _dynamics(lk, model, state, deg, q, qd, qdd, J, Jinv, speed_hz, tol)


def _dynamics(lk, model, state, deg, q, qd, qdd, J, Jinv, speed_hz, tol) -> ReactionHistory:
    n = q.shape[0]
    g = np.asarray(lk.gravity_mm_s2, float) / 1000
    Q = np.zeros((n, model.m))
    bodies_out: dict[str, BodyHistory] = {}
    for b in lk.bodies:
        i = 3 * model.index[b.name]
        r, phi = q[:, i:i + 2], q[:, i + 2]
        a, w, al = qdd[:, i:i + 2], qd[:, i + 2], qdd[:, i + 2]
        f, mo = b.inertia_load(phi, w, al, a, g)
        Q[:, i:i + 2] += f
        Q[:, i + 2] += mo
        bodies_out[b.name] = b.history(phi, w, al, r, qd[:, i:i + 2], a)
    for ld in lk.loads:
        i = 3 * model.index[ld.body]
        f, mo = ld.applied(np.radians(deg), q[:, i:i + 2], q[:, i + 2], q, qd)
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
            m_origin = -(lam[:, r] * _dot(nn, perp(sb)) + lam[:, r + 1])
            mom = m_origin - cross(sb, fab)
        pos = np.broadcast_to(pos, (n, 2)) * 1000
        joints[j.name] = JointHistory(j.name, j.body_a, j.body_b, fab, pos, mom,
                                      "revolute" if isinstance(j, Revolute) else "prismatic")
    lk.record_joint_points(bodies_out)
    dv = lk.driver
    # motor torque on the crank (N·m), or actuator force on the slider along its axis (N)
    drive = -lam[:, model.drow]
    if isinstance(dv, SliderDriver):
        # the actuator pushes along the slide: part of that joint's force by body_a on body_b
        joints[dv.joint].force_N = joints[dv.joint].force_N + fr[dv.joint][2] * drive[:, None]
    # toggle detection: reciprocal condition number of the length-scaled Jacobian
    S = np.ones(model.m)
    S[0::3] = S[1::3] = model.scale
    rowscale = np.ones(model.m)
    for j, r in zip(lk.joints, model.rows):
        rowscale[r] = 1 / model.scale
        if isinstance(j, Revolute):
            rowscale[r + 1] = 1 / model.scale
    if isinstance(dv, SliderDriver):
        rowscale[model.drow] = 1 / model.scale
    # scaled J = R J S  ->  inverse = S^-1 J^-1 R^-1
    # (column sums by a matrix product: much faster than a reduction over a length-9 axis)
    ones = np.ones(model.m)
    norm = (ones @ np.abs(J * (rowscale[:, None] * S[None, :]))).max(1)
    inv_norm = (ones @ np.abs(Jinv / (S[:, None] * rowscale[None, :]))).max(1)
    with np.errstate(all="ignore"):
        rcond = 1.0 / (norm * inv_norm)
    rcond = np.where(np.isfinite(rcond), rcond, 0.0)
    bad = ~np.isfinite(lam).all(1) | (rcond < RCOND_SINGULAR)
    meta = dict(lk.meta)
    meta.update(speed_hz=speed_hz, driver_unit="N·m" if isinstance(dv, CrankDriver) else "N",
                rcond_min=float(rcond.min()), solver="general")
    if state[5]:
        meta["warnings"] = list(state[5])
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
        return _evaluate(lk, state, np.atleast_1d(np.asarray(angles, float)), speed_hz, tol)

    h.evaluator = evaluator
    return h
