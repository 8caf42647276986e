"""Function generation with a four-bar: Freudenstein's equation at Chebyshev precision points.

The crank angle θ2 stands for x and the rocker angle θ4 for y = f(x), both linearly:
θ2 = θ2s + (x − x0)/(x1 − x0)·Δθ2, θ4 = θ4s + (y − y0)/(y1 − y0)·Δθ4 (deg, counter-clockwise
from the ground line O2→O4, O4 at (d, 0)).  The loop a e2 + b e3 = d + c e4 squared gives
Freudenstein's equation  K1 cos θ4 − K2 cos θ2 + K3 = cos(θ2 − θ4),
K1 = d/a, K2 = d/c, K3 = (a² − b² + c² + d²)/(2ac), linear in K at each precision point.
The generated function is then computed by the closed-form kinematics
(:mod:`rigfem.linkage.kinematics`), independently of these equations.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigfem.linkage.kinematics import fourbar_motion, fourbar_turn
from rigfem.linkage.loops import change_points_passed
from rigfem.errors import ComputeError, InfeasibleError, InputError
from rigfem.linkage.expression import check_interval, parse_function

#: a structural error above this share of the output range (%) is flagged as a defect
USEFUL_ERROR_PCT = 10.0
#: longest link the synthesis accepts, in ground lengths: beyond it the precision points are (nearly)
#: those of a linear map, which only a four-bar with infinite links generates
MAX_LINK_RATIO = 1000.0

def chebyshev_points(x0: float, x1: float, n: int) -> np.ndarray:
    """Chebyshev spacing of ``n`` precision points on [x0, x1]: x_j = m − h cos((2j − 1)π/(2n))."""
    j = np.arange(1, n + 1)
    return (x0 + x1) / 2 - (x1 - x0) / 2 * np.cos((2 * j - 1) * np.pi / (2 * n))


@dataclass(frozen=True)
class FunctionTask:
    """The inputs of :func:`synthesize_function`, checked once as they are made (a script's or
    the CLI's raw numbers and function text): each finite, X1 > X0, the ground positive, three
    precision points, the angle ranges non-zero within ±360 deg, and the function finite and
    continuous on [X0, X1] (:func:`rigfem.linkage.expression.check_interval`) with f(X0) ≠ f(X1).
    Each refusal is one InputError line naming the option, the value and what is allowed."""

    expr: str
    x0: float
    x1: float
    in_start: float
    in_range: float
    out_start: float
    out_range: float
    d: float
    points: int = 3
    samples: int = 2001
    f: object = field(init=False, repr=False, compare=False)  #: the parsed function
    xs: np.ndarray = field(init=False, repr=False, compare=False)  #: samples of [x0, x1]
    ys: np.ndarray = field(init=False, repr=False, compare=False)  #: f at xs

    def __post_init__(self) -> None:
        f = parse_function(self.expr)
        for name, v in (("--x X0", self.x0), ("--x X1", self.x1), ("--input START", self.in_start),
                        ("--input RANGE", self.in_range), ("--output START", self.out_start),
                        ("--output RANGE", self.out_range), ("--ground", self.d)):
            if not np.isfinite(v):
                raise InputError(f"{name} = {v!r} must be a finite number")
        if not self.x1 > self.x0:
            raise InputError(f"--x X0 X1 = {self.x0:g} {self.x1:g}: X1 must be greater than X0")
        if self.d <= 0:
            raise InputError(f"--ground = {self.d:g} must be a positive length")
        if int(self.points) != 3:
            raise InputError(f"--points = {self.points!r}: Freudenstein's equation has three unknowns, allowed 3")
        for name, v in (("--input RANGE", self.in_range), ("--output RANGE", self.out_range)):
            if v == 0 or abs(v) >= 360:
                raise InputError(f"{name} = {v:g} deg must be non-zero and within (-360, 360) deg")
        xs, ys = check_interval(f, self.expr, self.x0, self.x1, self.samples)
        if ys[-1] == ys[0]:
            raise InputError(f"EXPR = {self.expr!r} has f(X0) = f(X1) = {float(ys[0]):g}: the output range "
                             f"would be zero")
        for k, v in (("f", f), ("xs", xs), ("ys", ys)):
            object.__setattr__(self, k, v)

    @property
    def y0(self) -> float:
        return float(self.ys[0])

    @property
    def y1(self) -> float:
        return float(self.ys[-1])


def synthesize_function(expr: str, x0: float, x1: float, in_start: float, in_range: float, out_start: float,
                        out_range: float, d: float, points: int = 3, samples: int = 2001) -> dict:
    """Four-bar generating y = f(x) on [x0, x1] (angles deg, lengths in the unit of ``d``).

    Returns the link lengths a (input crank), b (coupler), c (output rocker), d; the precision
    points; the branch; the generated output over the range (by the closed-form kinematics)
    and its structural error (largest |generated − ideal| in y and in % of |y1 − y0|); the
    defects found (branch: precision points on different assembly branches; order: a dead
    point of the crank inside the input range, so the points are not reached in one sweep).
    A negative a or c means that link points the other way: its length is given positive and
    its angle offset by 180° (``input_offset_deg``/``output_offset_deg``).
    """
    t = FunctionTask(expr, x0, x1, in_start, in_range, out_start, out_range, d, points, samples)
    f, xs, ys, y0, y1 = t.f, t.xs, t.ys, t.y0, t.y1

    def th2(x):
        return in_start + (np.asarray(x) - x0) / (x1 - x0) * in_range

    def th4(y):
        return out_start + (np.asarray(y) - y0) / (y1 - y0) * out_range

    xp = chebyshev_points(x0, x1, 3)
    yp = f(xp)
    t2, t4 = np.radians(th2(xp)), np.radians(th4(yp))
    M = np.stack([np.cos(t4), -np.cos(t2), np.ones(3)], -1)
    linear = (f"--x X0 X1 = {x0:.10g} {x1:.10g}: over this range the precision points ask for a linear map of "
              f"the input angle to the output angle, which needs links longer than {MAX_LINK_RATIO:g} × --ground "
              f"(allowed ≤ {MAX_LINK_RATIO:g} ×); widen --x where f is not linear, or change --input/--output RANGE")
    try:
        K1, K2, K3 = np.linalg.solve(M, np.cos(t2 - t4))
    except np.linalg.LinAlgError:
        raise InfeasibleError(linear) from None
    if not (abs(K1) * MAX_LINK_RATIO > 1 and abs(K2) * MAX_LINK_RATIO > 1):
        raise InfeasibleError(linear)
    a, c = d / K1, d / K2
    b2_sq = a * a + c * c + d * d - 2 * a * c * K3
    if not b2_sq > 0:
        raise ComputeError(f"Freudenstein's solution has no real coupler (b² = {b2_sq:.4g})")
    b = float(np.sqrt(b2_sq))
    if b > MAX_LINK_RATIO * d:
        raise InfeasibleError(linear)
    off_in, off_out = (180.0 if a < 0 else 0.0), (180.0 if c < 0 else 0.0)
    a, c = abs(a), abs(c)
    res = dict(expression=expr, x_range=[x0, x1], y_range=[y0, y1], ground=d,
               input_deg=dict(start=in_start, range=in_range), output_deg=dict(start=out_start, range=out_range),
               freudenstein=dict(K1=float(K1), K2=float(K2), K3=float(K3)),
               lengths=dict(a=float(a), b=b, c=float(c), d=float(d)),
               input_offset_deg=off_in, output_offset_deg=off_out)
    defects = []
    arc = _reachable(a, b, c, d)
    sweep = th2(xs) + off_in
    if arc is not None:
        inside = ((sweep - arc[0]) % 360.0) <= (arc[1] - arc[0])
        if not inside.all():
            defects.append(f"order defect: the crank meets a dead point inside the input range "
                           f"(it can only move {arc[0]:.3f} to {arc[1]:.3f} deg)")
    res["precision_points"] = [dict(x=float(x), y=float(y), input_deg=float(p), output_deg=float(q))
                               for x, y, p, q in zip(xp, yp, th2(xp), th4(yp))]
    # which assembly branch passes through each precision point (computed by the kinematics)
    on = {}
    for br in ("open", "crossed"):
        try:
            m = fourbar_motion(a, b, c, d, th2(xp) + off_in, branch=br)
        except InputError:
            continue
        got = m.links["rocker"]["angle_deg"] - off_out
        on[br] = np.abs(((got - th4(yp)) + 180.0) % 360.0 - 180.0) < 1e-6
    branch = next((br for br, ok in on.items() if ok.all()), None)
    passed = change_points_passed(a, b, c, d, sweep[0], sweep[-1] - sweep[0])
    if passed:
        defects.append(f"branch defect: the crank passes the change point at {passed[0]:g} deg in the input "
                       f"range (every link in line): there the linkage may leave on either branch")
    if branch is None:
        defects.append("branch defect: the precision points lie on different assembly branches")
        res.update(branch=None, defects=defects)
        return res
    res["branch"] = branch
    if defects:
        res["defects"] = defects
        return res
    m = fourbar_motion(a, b, c, d, sweep, branch=branch)
    psi = m.links["rocker"]["angle_deg"] - off_out
    psi = th4(y0) + ((psi - th4(y0) + 180.0) % 360.0 - 180.0)
    y_gen = y0 + (psi - out_start) / out_range * (y1 - y0)
    err = y_gen - ys
    i = int(np.argmax(np.abs(err)))
    pct = float(100 * abs(err[i]) / abs(y1 - y0))
    if pct > USEFUL_ERROR_PCT:
        defects.append(f"accuracy defect: structural error {pct:.4g} % of the output range, far beyond any useful "
                       f"accuracy (> {USEFUL_ERROR_PCT:g} %): this four-bar does not generate the function")
    res.update(defects=defects, generated=dict(x=xs, y_ideal=ys, y_generated=y_gen, error=err),
               structural_error=dict(max_abs=float(abs(err[i])), at_x=float(xs[i]),
                                     percent_of_range=pct),
               transmission_deg=dict(min=float(m.transmission_deg.min()), max=float(m.transmission_deg.max())))
    return res


def _reachable(a, b, c, d):
    """Crank arc (deg, start < end) the synthesised four-bar can reach; None = a full turn."""
    try:
        arc = fourbar_turn(a, b, c, d)["crank_range_deg"]
    except InputError:
        raise ComputeError(f"the synthesised four-bar a={a:.4g} b={b:.4g} c={c:.4g} d={d:.4g} cannot be assembled") from None
    return None if arc is None else tuple(arc)


def _dyad(delta: np.ndarray, rot_link: np.ndarray, rot_coupler: np.ndarray) -> tuple[complex, complex]:
    """Standard-form dyad W, Z (complex, first position) with W(e^{iβk} − 1) + Z(e^{iαk} − 1) = δk, k = 2, 3."""
    M = np.array([[np.exp(1j * rot_link[k]) - 1, np.exp(1j * rot_coupler[k]) - 1] for k in range(2)])
    if abs(np.linalg.det(M)) < 1e-12:
        raise InfeasibleError("the chosen rotations make the dyad equations singular; change --alpha/--beta/--gamma")
    W, Z = np.linalg.solve(M, delta)
    return complex(W), complex(Z)


@dataclass(frozen=True)
class Positions:
    """The three coupler positions (x, y) of a motion synthesis, checked once as they are made:
    three finite points, no two coincident (the CLI's --points reads them so, a script's list is
    checked here).  Each refusal is one InputError line."""

    points: object  #: (3, 2) array-like
    xy: np.ndarray = field(init=False, repr=False, compare=False)  #: the points as a (3, 2) float array

    def __post_init__(self) -> None:
        try:
            P = np.asarray(self.points, float)
        except (TypeError, ValueError):
            P = np.full(1, np.nan)
        if P.shape != (3, 2) or not np.all(np.isfinite(P)):
            raise InputError("--points needs three finite positions X,Y")
        z = P[:, 0] + 1j * P[:, 1]
        delta = z[1:] - z[0]
        if np.min(np.abs(np.r_[delta, z[2] - z[1]])) < 1e-9 * (np.abs(delta).max() + 1):
            raise InputError("--points: the three positions must be distinct")
        object.__setattr__(self, "xy", P)


def three_position(points: np.ndarray, alpha_deg, beta_deg, gamma_deg) -> dict:
    """Four-bar whose coupler point passes through three positions (x, y) in order.

    Free choices (deg, position 2 and 3 relative to 1): the coupler rotations ``alpha_deg``, the
    crank rotations ``beta_deg`` and the rocker rotations ``gamma_deg``.  Each side is a dyad in
    standard form W(e^{iβk} − 1) + Z(e^{iαk} − 1) = Pk − P1 (a linear complex 2×2 system).
    Returns the ground pivots O2, O4, the first-position pins A1, B1, the lengths b2, b3, b4, d,
    the coupler point (distance from A, angle from A→B) and the crank angle of each position in
    the linkage's own frame (O2 at the origin, O4 on +x).
    """
    P = Positions(points).xy
    z = P[:, 0] + 1j * P[:, 1]
    delta = z[1:] - z[0]
    a, b, g = (np.radians(np.asarray(v, float)) for v in (alpha_deg, beta_deg, gamma_deg))
    W, Z = _dyad(delta, b, a)
    U, S = _dyad(delta, g, a)
    O2, O4 = z[0] - Z - W, z[0] - S - U
    A1, B1 = O2 + W, O4 + U
    b2, b3, b4, d = abs(W), abs(B1 - A1), abs(U), abs(O4 - O2)
    if min(b2, b3, b4, d) < 1e-9 * (np.abs(delta).max()):
        raise InfeasibleError("the chosen rotations give a zero-length link; change --alpha/--beta/--gamma")
    th1 = np.angle(O4 - O2)
    crank = np.degrees(np.angle(W * np.exp(1j * np.r_[0.0, b])) - th1) % 360.0
    cp = (abs(z[0] - A1), float(np.degrees(np.angle((z[0] - A1) / (B1 - A1)))))
    c = lambda v: [float(v.real), float(v.imag)]      # noqa: E731
    return dict(points=P.tolist(), alpha_deg=list(map(float, alpha_deg)), beta_deg=list(map(float, beta_deg)),
                gamma_deg=list(map(float, gamma_deg)), O2=c(O2), O4=c(O4), A1=c(A1), B1=c(B1),
                ground_angle_deg=float(np.degrees(th1)),
                lengths=dict(b2=float(b2), b3=float(b3), b4=float(b4), d=float(d)),
                coupler_point=dict(distance=float(cp[0]), angle_deg=cp[1]), crank_deg=[float(x) for x in crank])


def crank_in_order(crank_deg) -> bool:
    """The crank reaches the three angles (deg) in order, turning one way (either way)."""
    c = crank_deg
    ccw = [(c[1] - c[0]) % 360, (c[2] - c[0]) % 360]
    return ccw[0] < ccw[1] or (360 - ccw[0]) % 360 < (360 - ccw[1]) % 360


def check_three_position(r: dict) -> dict:
    """Assembly branch through the first position, coupler-point positions generated by the
    closed-form kinematics at the three crank angles (global frame), their largest distance
    from the wanted points, defects (branch, order, crank cannot turn), and the transmission
    angle range over a turn."""
    from rigfem.linkage.kinematics import fourbar_turn, grashof_class

    L = r["lengths"]
    b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
    cp = (r["coupler_point"]["distance"], r["coupler_point"]["angle_deg"])
    O2, th1 = np.array(r["O2"]), np.radians(r["ground_angle_deg"])
    R = np.array([[np.cos(th1), -np.sin(th1)], [np.sin(th1), np.cos(th1)]])
    P = np.array(r["points"])
    best, defects = None, []
    for br in ("open", "crossed"):
        try:
            m = fourbar_motion(b2, b3, b4, d, r["crank_deg"], branch=br, coupler_point=cp)
        except InputError:
            continue
        got = O2 + m.points["P"]["position_mm"] @ R.T
        err = np.linalg.norm(got - P, axis=1)
        if err[0] < 1e-6 * (1 + np.abs(P).max()) and (best is None or err.max() < best[1].max()):
            best = (br, err, got)
    if best is None:
        return dict(branch=None, defects=["the linkage cannot be assembled at the first position"])
    br, err, got = best
    if err.max() > 1e-6 * (1 + np.abs(P).max()):
        defects.append("branch defect: not all three positions lie on the assembly branch of the first")
    if not crank_in_order(r["crank_deg"]):
        defects.append("order defect: the crank does not reach the positions in the order 1, 2, 3")
    c = r["crank_deg"]
    ccw = (c[1] - c[0]) % 360 < (c[2] - c[0]) % 360
    passed = change_points_passed(b2, b3, b4, d, c[0], (c[2] - c[0]) % 360 if ccw else -((c[0] - c[2]) % 360))
    if passed:
        defects.append(f"branch defect: the crank passes the change point at {passed[0]:g} deg on the way "
                       f"(every link in line): there the linkage may leave on either branch")
    t = fourbar_turn(b2, b3, b4, d, br)
    if t["crank_range_deg"] is not None:
        defects.append(f"the crank cannot turn fully ({t['grashof']})")
    mu = None
    if t["crank_range_deg"] is None:  # a full turn: the extremes with the crank along the ground line
        from rigfem.rig.rules import transmission_angle_range

        lo, hi = transmission_angle_range(b2, b3, b4, d)
        mu = dict(min=lo, max=hi)
    return dict(branch=br, grashof=grashof_class(b2, b3, b4, d), generated=got.tolist(),
                position_error=float(err.max()), defects=defects, transmission_deg=mu)


def optimise_three_position(points: np.ndarray, alpha_deg=None, seed: int = 0, maxiter: int = 60) -> dict:
    """Free choices (crank and rocker rotations; the coupler rotations too unless ``alpha_deg``
    is given) that maximise the smallest transmission angle min(μ_min, 180 − μ_max) over a
    full crank turn, for a defect-free four-bar whose crank turns fully: a crank-rocker or, the
    ground shortest, a double-crank (scipy differential evolution, seeded; the result's
    check_three_position names which)."""
    from scipy.optimize import differential_evolution

    from rigfem.rig.rules import transmission_angle_range

    P = np.asarray(points, float)
    span = float(np.ptp(P, axis=0).max())

    def design(v):
        al = alpha_deg if alpha_deg is not None else v[4:6]
        return three_position(P, al, v[0:2], v[2:4])

    def cost(v):
        try:
            r = design(v)
        except InputError:
            return 1e3
        L = r["lengths"]
        if max(L.values()) > 20 * span:
            return 1e3
        chk = check_three_position(r)
        if chk["branch"] is None or chk["defects"]:
            return 5e2
        lo, hi = transmission_angle_range(L["b2"], L["b3"], L["b4"], L["d"])
        return -min(lo, 180.0 - hi)

    bounds = [(-350, 350)] * 2 + [(-120, 120)] * 2 + ([(-120, 120)] * 2 if alpha_deg is None else [])
    res = differential_evolution(cost, bounds, seed=seed, maxiter=maxiter, popsize=15, tol=1e-8, polish=False)
    if res.fun >= 5e2:
        raise ComputeError("no defect-free four-bar whose crank turns fully found for these positions within the search bounds")
    return design(res.x)
