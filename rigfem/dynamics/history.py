"""Reaction histories over one crank turn: the load source of every stress check.

Units at this interface: crank angle in degrees, forces in N, torque in N·m, positions
in mm, accelerations in mm/s², inertia in kg·mm².  A history comes from the linkage
solver (``rigfem.dynamics.cycle.simulate``) or from an external CSV (``read_csv``).

``peaks`` refines around each sampled maximum (on the solver itself, or on a periodic
cubic spline for an imported CSV) so the peak does not depend on sampling.
When the history has a toggle (``meta["singular"]``: reactions grow without bound there)
no peak is reported as a plain number: ``force_N`` is ``None`` and ``singular`` is ``True``.
A driven slider's history carries the driver force (N) in ``torque_Nm``; ``meta["driver_unit"]``
says which.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.interpolate import CubicSpline

from rigfem.errors import InputError
from rigfem.linkage.model import BodyHistory
from rigfem.rig.rules import rules_for


@dataclass
class JointHistory:
    """Reaction of one joint: force exerted BY ``body_a`` ON ``body_b`` (global frame, N)."""

    name: str
    body_a: str
    body_b: str
    force_N: np.ndarray
    position_mm: np.ndarray | None = None
    #: prismatic joints only: constraint moment on body_b about its sliding point (N·m)
    moment_Nm: np.ndarray | None = None
    kind: str = "revolute"


@dataclass
class ReactionHistory:
    """Joint reactions and driver torque (or force) sampled over one crank turn."""

    crank_deg: np.ndarray
    joints: dict[str, JointHistory]
    torque_Nm: np.ndarray
    bodies: dict[str, BodyHistory] | None
    meta: dict
    #: per-sample toggle flag (True where the Jacobian is ill-conditioned / mu near 0 or 180)
    singular_mask: np.ndarray | None = None
    #: re-evaluates the same linkage at arbitrary crank angles (deg); used by ``peaks``
    evaluator: Callable[[np.ndarray], "ReactionHistory"] | None = field(default=None, repr=False)
    #: ``crank_deg`` is an evenly spaced full turn (:func:`rigfem.linkage.loops.is_full_turn`, said by
    #: whoever sampled it): peaks and splines wrap round the turn
    full_turn: bool = False


@dataclass(frozen=True)
class DynamicsOptions:
    """How a check gets its reactions: the crank angles of a turn, the mass model, the crank speed,
    or an external reaction history (a CSV beside the scene, and the values stated for its missing
    columns)."""

    samples: int = 360
    mass_model: str = "rigid-body"
    speed_hz: float = 1.0
    reactions_csv: Path | None = None
    csv_missing: dict | None = None

    def __post_init__(self) -> None:
        """The samples (a whole number in [8, 1000000]), the mass model (one of MODELS) and the
        speed (non-zero, within ±100 Hz), checked once as the options are made (the scene's
        [check] and [linkage] tables are narrower; a script's :func:`rigfem.dynamics.cycle.simulate`
        call makes one too)."""
        from rigfem.settings import MODELS

        if self.mass_model not in MODELS:
            raise InputError(f"model = {self.mass_model!r} must be one of {', '.join(MODELS)}")
        try:
            whole = int(self.samples) == self.samples and 8 <= self.samples <= 1_000_000
        except (TypeError, ValueError, OverflowError):
            whole = False
        if not whole:
            raise InputError(f"samples = {self.samples!r} must be a whole number in [8, 1000000]")
        try:
            ok = bool(np.isfinite(self.speed_hz)) and self.speed_hz != 0 and abs(self.speed_hz) <= 100
        except TypeError:
            ok = False
        if not ok:
            raise InputError(f"speed_hz = {self.speed_hz!r} must be non-zero and within [-100, 100] Hz")


@dataclass(frozen=True)
class Reactions:
    """The reactions stage's product: a turn's reaction history, its refined peaks and the
    summary the report shows (:func:`summary`)."""

    history: ReactionHistory
    peaks: dict
    summary: dict

    @property
    def singular(self) -> list | None:
        """The toggle crank-angle ranges, where reactions grow without bound (None if none)."""
        return self.history.meta.get("singular")


def reactions_of(h: ReactionHistory) -> Reactions:
    """A history with its peaks (refined once) and summary."""
    pk = peaks(h)
    return Reactions(h, pk, summary(h, pk))


#: refined peaks within this relative distance of the largest count as equal (``equal_peaks_deg``)
TIE_RTOL = 1e-9


def merge_ranges(*lists: list[list[float]] | None) -> list[list[float]] | None:
    """Union of crank-angle range lists (deg), overlapping ranges merged; None if empty."""
    rs = sorted([list(r) for lst in lists if lst for r in lst])
    out: list[list[float]] = []
    for a, b in rs:
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return out or None


def _zoom_max(ev: Callable[[np.ndarray], "ReactionHistory"], names: list[str], lo: np.ndarray,
              hi: np.ndarray, xatol: float = 1e-7, k: int = 17):
    """Maximise |F| of joint ``names[c]`` (or |torque|) on each bracket [lo[c], hi[c]] (deg).

    All brackets are searched together: each round evaluates ``k`` evenly spaced angles per
    bracket in one vectorised solver call and keeps the two spacings around the best, so
    the bracket shrinks by (k - 1) / 2 per round down to ``xatol``.  Returns (x, f, toggle),
    toggle = the first angle met where the solver flags a toggle, or None.
    """
    t = np.linspace(0.0, 1.0, k)
    rows = np.arange(lo.size)
    while True:
        xs = lo[:, None] + (hi - lo)[:, None] * t
        r = ev(xs.ravel())
        if r.singular_mask is not None and r.singular_mask.any():
            return None, None, float(xs.ravel()[np.argmax(r.singular_mask)])
        ser = _series(r)
        vals = np.stack([ser[n].reshape(xs.shape)[c] for c, n in enumerate(names)])
        j = np.argmax(vals, axis=1)
        if np.max(hi - lo) < xatol:
            return xs[rows, j], vals[rows, j], None
        lo, hi = xs[rows, np.maximum(j - 1, 0)], xs[rows, np.minimum(j + 1, k - 1)]


def _candidates(vals: np.ndarray, periodic: bool) -> list[int]:
    """Indices of sampled local maxima close enough to the global maximum to win after refinement."""
    prev = np.roll(vals, 1) if periodic else np.r_[-np.inf, vals[:-1]]
    nxt = np.roll(vals, -1) if periodic else np.r_[vals[1:], -np.inf]
    loc = np.flatnonzero((vals >= prev) & (vals >= nxt))
    top = vals.max()
    near_top = [int(i) for i in loc if vals[i] >= 0.97 * top]
    return near_top or [int(np.argmax(vals))]


def _distinct(xs: list[float], periodic: bool, tol: float = 1e-4) -> list[float]:
    """Sorted angles (deg) with those within ``tol`` of each other (round the turn if periodic) merged."""
    out: list[float] = []
    for x in xs:
        if not out or x - out[-1] > tol:
            out.append(x)
    if periodic and len(out) > 1 and out[0] + 360.0 - out[-1] <= tol:
        out.pop()
    return out


def _series(h: ReactionHistory) -> dict[str, np.ndarray]:
    out = {name: np.hypot(j.force_N[:, 0], j.force_N[:, 1]) for name, j in h.joints.items()}
    out["torque"] = np.abs(h.torque_Nm)
    return out


def spline_evaluator(h: ReactionHistory) -> Callable[[np.ndarray], ReactionHistory]:
    """Periodic (full turn) or not-a-knot cubic spline through an imported history."""
    deg = h.crank_deg
    periodic = h.full_turn
    x = np.r_[deg, deg[-1] + (deg[1] - deg[0])] if periodic else deg
    bc = "periodic" if periodic else "not-a-knot"

    def close(a):
        return np.concatenate([a, a[:1]]) if periodic else a

    splines = {n: CubicSpline(x, close(j.force_N), bc_type=bc) for n, j in h.joints.items()}
    tq = CubicSpline(x, close(h.torque_Nm), bc_type=bc)

    def ev(angles: np.ndarray) -> ReactionHistory:
        a = np.atleast_1d(np.asarray(angles, float))
        if periodic:
            a = x[0] + np.mod(a - x[0], 360.0)
        joints = {n: JointHistory(n, j.body_a, j.body_b, splines[n](a)) for n, j in h.joints.items()}
        return ReactionHistory(a, joints, tq(a), None, dict(h.meta))

    return ev


def peaks(h: ReactionHistory, refine: bool = True) -> dict:
    """Peak reaction magnitude of every joint and the peak |torque|.

    Returns ``{joint: {force_N, crank_deg, fx_N, fy_N, singular}, ..., "torque":
    {peak, value, crank_deg, singular}}`` (N, deg, N·m; ``value`` is the signed torque).
    With ``refine`` every sampled local maximum near the top is refined on the history's
    evaluator (the solver itself, or a cubic spline of imported samples) down to 1e-7 deg,
    so the result does not depend on the sampling.  Local maxima equal to the largest (within
    :data:`TIE_RTOL`, e.g. the mirrored peaks of a symmetric linkage) are all listed in
    ``equal_peaks_deg`` and the smallest angle is the peak's.  If the history has a toggle
    (``meta["singular"]``, a flagged sample, or one met while refining) the peaks are
    unbounded: ``force_N``/``peak`` = None, ``singular`` = True.
    """
    deg = np.asarray(h.crank_deg, float)
    periodic = h.full_turn
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(deg.size, bool)
    toggle = h.meta.get("singular")[0][0] if h.meta.get("singular") else None
    if toggle is None and mask.any():
        toggle = float(deg[np.argmax(mask)])
    ev = h.evaluator if h.evaluator is not None else (spline_evaluator(h) if deg.size >= 4 else None)
    step = abs(deg[1] - deg[0]) if deg.size > 1 else 0.0
    series = _series(h)
    best = {n: (float(deg[int(np.argmax(v))]), float(np.max(v))) for n, v in series.items()}
    found: dict[str, list[tuple[float, float]]] = {n: [] for n in series}  # refined local maxima
    if toggle is None and refine and ev is not None and step > 0.0:
        cand = [(n, i) for n, v in series.items() for i in _candidates(v, periodic)
                if periodic or 0 < i < deg.size - 1]
        if cand:
            names = [n for n, _ in cand]
            centre = np.array([deg[i] for _, i in cand])
            xs, fs, toggle = _zoom_max(ev, names, centre - step, centre + step)
            if toggle is None:
                for n, x, f in zip(names, xs, fs):
                    found[n].append((float(np.mod(x, 360.0)) if periodic else float(x), float(f)))
                    if f > best[n][1]:
                        best[n] = (float(x), float(f))
    # equal peaks (a symmetric linkage peaks at mirrored crank angles): which one the floats
    # crown is a knife edge, so all are reported and the smallest angle is the peak's
    ties = {n: _distinct(sorted(x for x, f in found[n] if f >= best[n][1] * (1 - TIE_RTOL)), periodic)
            for n in series}
    for n, t in ties.items():
        if len(t) > 1:
            best[n] = (t[0], best[n][1])
    out: dict = {}
    if toggle is not None:
        for n in series:
            none = dict(peak=None, value=None) if n == "torque" else dict(force_N=None, fx_N=None, fy_N=None)
            out[n] = {"crank_deg": toggle, "singular": True, **none}
        return out
    at = np.array([best[n][0] for n in series])
    if refine and ev is not None:
        r = ev(at)
        vecs = {n: r.joints[n].force_N[k] for k, n in enumerate(series) if n != "torque"}
        tq = float(r.torque_Nm[list(series).index("torque")])
    else:
        idx = {n: int(np.argmax(v)) for n, v in series.items()}
        vecs = {n: h.joints[n].force_N[idx[n]] for n in series if n != "torque"}
        tq = float(h.torque_Nm[idx["torque"]])
    for n, (x, f) in best.items():
        crank = float(np.mod(x, 360.0)) if periodic else x
        if n == "torque":
            out[n] = {"peak": f, "value": tq, "crank_deg": crank, "singular": False}
        else:
            out[n] = {"force_N": f, "crank_deg": crank, "fx_N": float(vecs[n][0]), "fy_N": float(vecs[n][1]),
                      "singular": False}
        if len(ties[n]) > 1:
            out[n]["equal_peaks_deg"] = ties[n]
    return out


def summary(h: ReactionHistory, pk: dict | None = None) -> dict:
    """The JSON result: rules, transmission angle, peaks, torque, singular ranges (finite only);
    ``pk`` the history's :func:`peaks` where they are known already (they are not refined twice)."""
    p = dict(pk if pk is not None else peaks(h))
    tq = p.pop("torque")
    mu = h.meta.get("mu_deg")
    unit = h.meta.get("driver_unit", "N·m")
    return {
        "linkage": h.meta.get("type"), "lengths_mm": h.meta.get("lengths_mm"), "model": h.meta.get("model"),
        "textbook": bool(h.meta.get("textbook", False)),
        "speed_hz": h.meta.get("speed_hz"), "samples": int(h.crank_deg.size),
        "rules": [{k: r.as_dict()[k] for k in ("name", "value", "limit", "ok", "relation", "unit")}
                  for r in rules_for(h.meta)],
        "transmission_angle_deg": None if mu is None else {"min": mu["min"], "max": mu["max"]},
        "peaks": p,
        "torque_Nm" if unit == "N·m" else "driver_force_N": {"peak": tq["peak"], "crank_deg": tq["crank_deg"],
                                                             "singular": tq["singular"]},
        "singular": h.meta.get("singular"),
        "warnings": h.meta.get("warnings", []),
    }
