"""Reaction histories over one crank turn: the load source of every stress check.

Units at this interface: crank angle in degrees, forces in N, torque in N·m, positions
in mm, accelerations in mm/s², inertia in kg·mm².  A history comes from the linkage
solver (``rigfem.mechanisms.simulate``) or from an external CSV (``read_csv``).

``peaks`` refines around each sampled maximum (on the solver itself, or on a periodic
cubic spline for an imported CSV) so the peak does not depend on sampling.
When the history has a toggle (``meta["singular"]``: reactions grow without bound there)
no peak is reported as a plain number: ``force_N`` is ``None`` and ``singular`` is ``True``.
A driven slider's history carries the driver force (N) in ``torque_Nm``; ``meta["driver_unit"]``
says which.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.interpolate import CubicSpline

from rigfem.errors import InputError
from rigfem.rules import rules_for


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
class BodyHistory:
    """Motion and mass data of one moving body (frame origin at its first joint, a bar's x
    axis towards its second joint).  ``mass_kg``/``com_local_mm``/``inertia_com_kg_mm2`` are the
    body's own (e.g. the guide rail); ``point_masses`` the particles it carries."""

    name: str
    angle_rad: np.ndarray
    omega_rad_s: np.ndarray
    alpha_rad_s2: np.ndarray
    origin_mm: np.ndarray
    origin_acc_mm_s2: np.ndarray
    mass_kg: float
    com_local_mm: np.ndarray
    inertia_com_kg_mm2: float
    point_masses: list[tuple[str, float, np.ndarray]] = field(default_factory=list)
    joint_local_mm: dict[str, np.ndarray] = field(default_factory=dict)


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


def singular_ranges(crank_deg: np.ndarray, mask: np.ndarray | None) -> list[list[float]] | None:
    """Contiguous crank-angle ranges [start, end] (deg) where ``mask`` is True; None if none."""
    if mask is None or not np.any(mask):
        return None
    idx = np.flatnonzero(mask)
    ranges, start, prev = [], idx[0], idx[0]
    for i in idx[1:]:
        if i != prev + 1:
            ranges.append([float(crank_deg[start]), float(crank_deg[prev])])
            start = i
        prev = i
    ranges.append([float(crank_deg[start]), float(crank_deg[prev])])
    return ranges


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


def is_full_turn(deg: np.ndarray) -> bool:
    """True if ``deg`` is an evenly spaced full turn (360 deg excluded)."""
    if deg.size < 4:
        return False
    step = np.diff(deg)
    return bool(np.allclose(step, step[0], rtol=1e-6, atol=1e-9)
                and abs(abs(step[0]) * deg.size - 360.0) < 1e-6 * 360)


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


def _series(h: ReactionHistory) -> dict[str, np.ndarray]:
    out = {name: np.hypot(j.force_N[:, 0], j.force_N[:, 1]) for name, j in h.joints.items()}
    out["torque"] = np.abs(h.torque_Nm)
    return out


def spline_evaluator(h: ReactionHistory) -> Callable[[np.ndarray], ReactionHistory]:
    """Periodic (full turn) or not-a-knot cubic spline through an imported history."""
    deg = h.crank_deg
    periodic = is_full_turn(deg)
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
    so the result does not depend on the sampling.  If the history has a toggle
    (``meta["singular"]``, a flagged sample, or one met while refining) the peaks are
    unbounded: ``force_N``/``peak`` = None, ``singular`` = True.
    """
    deg = np.asarray(h.crank_deg, float)
    periodic = is_full_turn(deg)
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(deg.size, bool)
    toggle = h.meta.get("singular")[0][0] if h.meta.get("singular") else None
    if toggle is None and mask.any():
        toggle = float(deg[np.argmax(mask)])
    ev = h.evaluator if h.evaluator is not None else (spline_evaluator(h) if deg.size >= 4 else None)
    step = abs(deg[1] - deg[0]) if deg.size > 1 else 0.0
    series = _series(h)
    best = {n: (float(deg[int(np.argmax(v))]), float(np.max(v))) for n, v in series.items()}
    if toggle is None and refine and ev is not None and step > 0.0:
        cand = [(n, i) for n, v in series.items() for i in _candidates(v, periodic)
                if periodic or 0 < i < deg.size - 1]
        if cand:
            names = [n for n, _ in cand]
            centre = np.array([deg[i] for _, i in cand])
            xs, fs, toggle = _zoom_max(ev, names, centre - step, centre + step)
            if toggle is None:
                for n, x, f in zip(names, xs, fs):
                    if f > best[n][1]:
                        best[n] = (float(x), float(f))
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
    return out


# ----------------------------------------------------------------------------- CSV
_TORQUE_COLS = ("torque_Nm", "torque", "M2", "driver")
_ANGLE_COLS = ("crank_deg", "theta_deg", "angle_deg", "theta", "angle", "crank_rad", "theta_rad", "angle_rad")


def write_csv(h: ReactionHistory, path: str | Path) -> None:
    """Write the history: crank_deg, <joint>_fx_N, <joint>_fy_N, <joint>_F_N ..., torque_Nm, singular.

    Rows inside a singular range keep the crank angle but leave the force cells empty,
    so a toggle's unbounded numbers never reach a file.  Header comments (``#``) carry
    the body pairs of each joint so ``read_csv`` restores them.
    """
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(h.crank_deg.size, bool)
    names = list(h.joints)
    unit = h.meta.get("driver_unit", "N·m")
    tcol = "torque_Nm" if unit == "N·m" else "driver_force_N"
    with open(path, "w", newline="") as fh:
        for n in names:
            j = h.joints[n]
            fh.write(f"# joint {n}: force by {j.body_a} on {j.body_b}\n")
        w = csv.writer(fh)
        head = ["crank_deg"]
        for n in names:
            head += [f"{n}_fx_N", f"{n}_fy_N", f"{n}_F_N"]
        w.writerow(head + [tcol, "singular"])
        for i, a in enumerate(h.crank_deg):
            row = [f"{a:.10g}"]
            for n in names:
                fx, fy = h.joints[n].force_N[i]
                row += ["", "", ""] if mask[i] else [f"{fx:.10g}", f"{fy:.10g}", f"{np.hypot(fx, fy):.10g}"]
            row.append("" if mask[i] else f"{h.torque_Nm[i]:.10g}")
            row.append("1" if mask[i] else "0")
            w.writerow(row)


def read_csv(path: str | Path) -> ReactionHistory:
    """Import a reaction history (rigfem's own CSV or an external one, e.g. from MATLAB).

    Needed columns (names case-insensitive): a crank-angle column in degrees (``crank_deg``,
    ``theta_deg``, ``angle_deg``, ``theta``, ``angle``) or radians (``crank_rad``, ``theta_rad``,
    ``angle_rad``), and per joint ``<J>_fx_N``/``<J>_fy_N`` (also ``<J>_fx``/``<J>_fy`` or
    ``<J>x``/``<J>y``) in N; optional torque column in N·m (``torque_Nm``, ``torque``, ``M2``).
    Lines starting with ``#`` are comments.  Raises InputError naming the problem.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"reaction CSV {str(p)!r} does not exist")
    pairs: dict[str, tuple[str, str]] = {}
    lines = []
    for line in p.read_text().splitlines():
        s = line.strip()
        if s.startswith("#"):
            parts = s[1:].split()
            if len(parts) >= 7 and parts[0] == "joint" and parts[2] == "force" and parts[3] == "by":
                pairs[parts[1].rstrip(":")] = (parts[4], parts[6])
        elif s:
            lines.append(line)
    if len(lines) < 2:
        raise InputError(f"reaction CSV {str(p)!r} has no data rows")
    rows = list(csv.reader(lines))
    head = [c.strip() for c in rows[0]]
    lower = [c.lower() for c in head]
    ang = next((lower.index(c) for c in _ANGLE_COLS if c in lower), None)
    if ang is None:
        raise InputError(f"reaction CSV {str(p)!r}: no crank-angle column ({', '.join(_ANGLE_COLS)})")
    data = []
    for k, r in enumerate(rows[1:], start=2):
        try:
            data.append([float(c) if c.strip() else np.nan for c in r])
        except ValueError:
            raise InputError(f"reaction CSV {str(p)!r} line {k}: non-numeric value") from None
    arr = np.array(data, float)
    if arr.ndim != 2 or arr.shape[1] != len(head):
        raise InputError(f"reaction CSV {str(p)!r}: rows do not all have {len(head)} columns")
    joints: dict[str, JointHistory] = {}
    for i, c in enumerate(lower):
        for sx, sy in (("_fx_n", "_fy_n"), ("_fx", "_fy"), ("x", "y")):
            if c.endswith(sx) and len(c) > len(sx):
                jn = head[i][: -len(sx)]
                cy = c[: -len(sx)] + sy
                if cy in lower and jn not in joints:
                    ba, bb = pairs.get(jn, ("?", "?"))
                    joints[jn] = JointHistory(jn, ba, bb, np.stack([arr[:, i], arr[:, lower.index(cy)]], -1))
                break
    if not joints:
        raise InputError(f"reaction CSV {str(p)!r}: no joint force columns (<joint>_fx_N, <joint>_fy_N)")
    tcol = next((lower.index(c.lower()) for c in _TORQUE_COLS + ("driver_force_N",) if c.lower() in lower), None)
    torque = arr[:, tcol] if tcol is not None else np.zeros(arr.shape[0])
    sing = arr[:, lower.index("singular")] > 0.5 if "singular" in lower else np.zeros(arr.shape[0], bool)
    bad = ~sing & (~np.isfinite(torque) | np.any([~np.isfinite(j.force_N).all(1) for j in joints.values()], 0))
    if np.any(bad):
        raise InputError(f"reaction CSV {str(p)!r}: empty or non-finite values at crank angle "
                         f"{arr[np.argmax(bad), ang]:g} deg")
    deg = np.degrees(arr[:, ang]) if lower[ang].endswith("_rad") else arr[:, ang]
    if not np.all(np.isfinite(deg)):
        raise InputError(f"reaction CSV {str(p)!r}: empty or non-finite crank angle")
    if np.any(np.diff(deg) <= 0):
        raise InputError(f"reaction CSV {str(p)!r}: crank angles must increase strictly")
    for j in joints.values():
        j.force_N = np.where(np.isfinite(j.force_N), j.force_N, 0.0)        # blank singular rows
    meta = {"source": str(p), "model": "imported"}
    if "driver_force_N" in head:
        meta["driver_unit"] = "N"
    h = ReactionHistory(deg, joints, np.where(np.isfinite(torque), torque, 0.0), None, meta,
                        singular_mask=sing if sing.any() else None)
    h.meta["singular"] = singular_ranges(deg, h.singular_mask)
    return h


def summary(h: ReactionHistory) -> dict:
    """The JSON result: rules, transmission angle, peaks, torque, singular ranges (finite only)."""
    p = peaks(h)
    tq = p.pop("torque")
    mu = h.meta.get("mu_deg")
    unit = h.meta.get("driver_unit", "N·m")
    return {
        "linkage": h.meta.get("type"), "lengths_mm": h.meta.get("lengths_mm"), "model": h.meta.get("model"),
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
