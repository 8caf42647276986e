"""From a synthesised four-bar to the nearest buildable rig configurations, each checked.

A synthesised linkage (``rigfem.linkage.synthesis``) has any lengths; the rig builds only
lengths on the 60 mm hole grid that obey every rig rule (geometry/RIG.md §2).  This module ranks the
rig's four-bars by how well they do the wanted job and attaches each one's rule table and
stress verdict (the sweep's superposed unit solutions, ``rigfem.sweep.run.evaluate``):

* function generation (:func:`snap_function`): the structural error does not depend on the
  scale, so *every* rig four-bar that assembles and meets the rig rules is evaluated (both assembly branches,
  vectorised closed-form kinematics) and ranked by its structural error in % of the output
  range;
* motion generation (:func:`snap_motion`): the design is scaled (``scale`` rig mm per unit
  of the positions, or a range of scales that fit the rails), each link rounded down and up
  to the hole grid, and for each result that meets the rig rules the coupler point is re-fitted: the ground
  pivot O2 and the ground line stay where the design put them, the coupler point (a marker
  fixed to the coupler, not on the hole grid, carrying no load) and the three crank angles
  are chosen by least squares; the motion error is the largest distance from a wanted
  position, in rig mm and in % of the positions' span.  ``off_rail_mm`` says how far the
  marker sits from the coupler rail (the arm it needs; the rig has none, geometry/RIG.md is silent).

Units: mm, deg (the positions in their own unit, ``scale`` converts).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from rigfem.context import Context, default_context
from rigfem.errors import ComputeError, InfeasibleError
from rigfem.linkage.expression import parse_function
from rigfem.linkage.kinematics import fourbar_motion
from rigfem.linkage.loops import BRANCHES, fourbar_angles
from rigfem.linkage.synthesis import crank_in_order
from rigfem.rig.rules import HOLE_PITCH_MM, fourbar_rules
from rigfem.sweep.run import evaluate
from rigfem.sweep.bases import build_bases
from rigfem.sweep.configs import SweepParams, enumerate_configs

__all__ = ["rig_fourbars", "snap_function", "snap_motion", "rule_table", "stress_verdicts"]

LENGTH_KEYS = ("b2", "b3", "b4", "d")


def rig_fourbars(p: SweepParams | None = None) -> np.ndarray:
    """Every four-bar of the rig that meets the rig rules (so it assembles): (n, 4) b2, b3, b4, d (mm)."""
    p = p or SweepParams()
    rows = [[c[k] for k in LENGTH_KEYS] for c in enumerate_configs(p)]
    return np.array([r for r in rows if all(x.ok for x in fourbar_rules(*r))], float).reshape(-1, 4)


def rule_table(lengths: dict) -> list[dict]:
    """The rig rules of a four-bar: name, value, relation, limit, unit, ok."""
    return [{k: r.as_dict()[k] for k in ("name", "value", "relation", "limit", "unit", "ok")}
            for r in fourbar_rules(*(lengths[k] for k in LENGTH_KEYS))]


def _wrap(deg: np.ndarray) -> np.ndarray:
    return (deg + 180.0) % 360.0 - 180.0


def _function_error(L: np.ndarray, sgn: int, start_deg: np.ndarray, rel_in: np.ndarray,
                    rel_out: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Largest |output rotation − wanted rotation| (deg) of four-bars ``L`` (n, 4) whose crank
    turns by ``rel_in`` from ``start_deg`` (n, S); and the rocker angle at the start (deg)."""
    b2, b3, b4, d = (L[:, i, None, None] for i in range(4))
    th2 = np.radians(start_deg[..., None] + rel_in)
    with np.errstate(all="ignore"):
        psi = np.degrees(fourbar_angles(b2, b3, b4, d, th2, 1.0, 0.0, sgn)["theta4"])
    err = np.abs(_wrap(psi - psi[..., :1]) - rel_out).max(axis=-1)
    return np.where(np.isfinite(err), err, np.inf), psi[..., 0]


def snap_function(r: dict, top: int = 5, p: SweepParams | None = None) -> list[dict]:
    """The ``top`` rig four-bars that generate ``r``'s function best (``r`` from
    :func:`rigfem.linkage.synthesis.synthesize_function`), each with its branch, the crank and
    rocker angles at X0 (where the input and output scales start), its structural error
    (largest |generated − ideal| in y and in % of the output range) and its rule table.

    A function generator relates the output's rotation to the input's, so the scales' zeros
    are free: for every rig four-bar and branch the input start is searched (4° grid, then
    refined) with the input and output ranges of ``r``.
    """
    from scipy.optimize import minimize_scalar

    f = parse_function(r["expression"])
    (x0, x1), (y0, y1) = r["x_range"], r["y_range"]
    ins, outs = r["input_deg"]["range"], r["output_deg"]["range"]

    def rel(n):
        xs = np.linspace(x0, x1, n)
        return (xs - x0) / (x1 - x0) * ins, (f(xs) - y0) / (y1 - y0) * outs

    L = rig_fourbars(p)
    if L.size == 0:
        raise InfeasibleError("the rig's rails allow no four-bar that obeys every rig rule")
    coarse_in, coarse_out = rel(41)
    starts = np.arange(0.0, 360.0, 4.0)
    found = []  # (error deg, row, branch, start)
    for br, sgn in BRANCHES.items():
        for c in range(0, len(L), 128):
            err, _ = _function_error(L[c:c + 128], sgn, np.broadcast_to(starts, (len(L[c:c + 128]), starts.size)),
                                     coarse_in, coarse_out)
            j = np.argmin(err, axis=1)
            found += [(float(err[i, j[i]]), c + i, br, float(starts[j[i]])) for i in range(len(j))]
    found.sort()
    fine_in, fine_out = rel(241)
    out = []
    for e0, i, br, s0 in found[:4 * top]:
        if not np.isfinite(e0):
            break

        def cost(s, i=i, br=br):
            return float(_function_error(L[i:i + 1], BRANCHES[br], np.array([[s]]), fine_in, fine_out)[0][0, 0])

        res = minimize_scalar(cost, bounds=(s0 - 4.0, s0 + 4.0), method="bounded", options={"xatol": 1e-4})
        s = float(res.x) if res.fun <= cost(s0) else s0
        err, psi0 = _function_error(L[i:i + 1], BRANCHES[br], np.array([[s]]), fine_in, fine_out)
        lengths = dict(zip(LENGTH_KEYS, map(float, L[i])))
        e = float(err[0, 0]) / abs(outs) * abs(y1 - y0)
        out.append(dict(lengths_mm=lengths, branch=br, input_start_deg=s % 360.0,
                        output_start_deg=float(psi0[0, 0]) % 360.0, error=e,
                        error_pct=100 * e / abs(y1 - y0), rules=rule_table(lengths)))
    out.sort(key=lambda c: (c["error"], c["branch"] != "open"))
    # the crossed branch is the open one's mirror image (angles read the other way round):
    # keep each set of lengths once
    uniq = {tuple(c["lengths_mm"].values()): c for c in reversed(out)}
    return sorted(uniq.values(), key=lambda c: (c["error"], c["branch"] != "open"))[:top]


def _grid_neighbours(x: float) -> list[float]:
    lo = np.floor(x / HOLE_PITCH_MM) * HOLE_PITCH_MM
    return [v for v in (lo, lo + HOLE_PITCH_MM) if v > 0]


def _fit_coupler_point(lengths: dict, branch: str, O2: np.ndarray, ground_deg: float, targets: np.ndarray,
                       cp0: tuple[float, float], crank0: np.ndarray):
    """Coupler point (distance mm, angle deg) and crank angles (deg) that bring the coupler point
    closest to ``targets`` (rig mm, global), O2 and the ground line fixed; least squares, with the
    Jacobian from the linkage's own motion (a crank angle moves its point by the point's velocity
    over the crank's, the coupler point's distance and angle move it along and across the line
    from A), one kinematics call per Jacobian instead of a finite difference's five."""
    from scipy.optimize import least_squares

    L = [lengths[k] for k in LENGTH_KEYS]
    c, s = np.cos(np.radians(ground_deg)), np.sin(np.radians(ground_deg))
    R = np.array([[c, -s], [s, c]])
    rad = np.pi / 180.0

    def motion(v):  # a rig four-bar is a crank-rocker: it closes at every crank angle
        return fourbar_motion(*L, v[2:], branch=branch, coupler_point=(v[0], v[1]))

    def residual(v):
        return (O2 + motion(v).points["P"]["position_mm"] @ R.T - targets).ravel()

    def jacobian(v):
        m = motion(v)
        th = np.radians(m.links["coupler"]["angle_deg"] + v[1])
        along, across = np.stack([np.cos(th), np.sin(th)], -1), np.stack([-np.sin(th), np.cos(th)], -1)
        J = np.zeros((len(th), 2, len(v)))
        J[:, :, 0] = along @ R.T
        J[:, :, 1] = v[0] * rad * across @ R.T
        J[np.arange(len(th)), :, 2 + np.arange(len(th))] = m.points["P"]["velocity_mm_s"] @ R.T * (rad / m.omega_rad_s)
        return J.reshape(-1, len(v))

    x0 = np.r_[cp0, crank0]
    res = least_squares(residual, x0, jac=jacobian, x_scale=np.r_[max(cp0[0], 1.0), 10.0, 10.0, 10.0, 10.0],
                        method="lm")
    v = res.x
    return (float(v[0]), float(v[1])), np.mod(v[2:], 360.0), np.linalg.norm(residual(v).reshape(-1, 2), axis=1)


def _off_rail(cp: tuple[float, float], p: SweepParams | None) -> float:
    """Distance (mm) from the coupler point to the coupler rail's line segment: the arm a
    marker needs beyond the rail (0 on the rail)."""
    from rigfem.rig.catalogue import RIG_MASSES

    rail = (p or SweepParams()).rails[1]
    behind = RIG_MASSES.rail_behind_mm
    x, y = cp[0] * np.cos(np.radians(cp[1])), cp[0] * np.sin(np.radians(cp[1]))
    return float(np.hypot(x - np.clip(x, -behind, rail - behind), y))


def snap_motion(r: dict, top: int = 5, scale: float | None = None, p: SweepParams | None = None) -> list[dict]:
    """The ``top`` rig four-bars nearest the three-position design ``r`` (from
    :func:`rigfem.linkage.synthesis.three_position` and ``check_three_position``), ranked by
    motion error; ``scale`` = rig mm per unit of the positions (None: every scale that fits)."""
    P = np.asarray(r["points"], float)
    span = float(np.max(np.linalg.norm(P[:, None] - P[None], axis=2)))
    Ld = np.array([r["lengths"][k] for k in LENGTH_KEYS])
    allowed = rig_fourbars(p)
    if allowed.size == 0:
        raise InfeasibleError("the rig's rails allow no four-bar that obeys every rig rule")
    ok = {tuple(x) for x in allowed}
    if scale is None:
        lo = float(np.max(allowed.min(axis=0) / Ld))
        hi = float(np.min(allowed.max(axis=0) / Ld))
        if not lo <= hi:
            raise InfeasibleError(f"the design's proportions (b2:b3:b4:d = {':'.join(f'{x:.3g}' for x in Ld / Ld[0])}) "
                                  f"do not fit the rig's rails at any one scale; give --scale")
        scales = np.geomspace(lo, hi, 24) if hi > lo else np.array([lo])
    else:
        scales = np.array([scale])
    out = []
    for s in scales:
        for combo in np.stack(np.meshgrid(*[_grid_neighbours(x) for x in s * Ld], indexing="ij"), -1).reshape(-1, 4):
            key = tuple(map(float, combo))
            if key not in ok:
                continue
            lengths = dict(zip(LENGTH_KEYS, key))
            cp0 = (s * r["coupler_point"]["distance"], r["coupler_point"]["angle_deg"])
            best = None
            for br in BRANCHES:
                cp, crank, dist = _fit_coupler_point(lengths, br, s * np.asarray(r["O2"]), r["ground_angle_deg"],
                                                     s * P, cp0, np.asarray(r["crank_deg"], float))
                if crank_in_order(crank) and (best is None or dist.max() < best[2].max()):
                    best = (br, cp, dist, crank)
            if best is None:
                continue
            br, cp, dist, crank = best
            out.append(dict(lengths_mm=lengths, branch=br, scale=float(s),
                            coupler_point=dict(distance_mm=cp[0], angle_deg=cp[1], off_rail_mm=_off_rail(cp, p)),
                            crank_deg=[float(c) for c in crank], error_mm=float(dist.max()),
                            error_pct=float(100 * dist.max() / (s * span)), rules=rule_table(lengths)))
    if not out:
        raise ComputeError("no rig four-bar near the design that meets the rig rules reaches the positions in order")
    out.sort(key=lambda c: c["error_pct"])
    uniq, keys = [], set()
    for c in out:  # the same lengths at several scales: keep the best
        k = (tuple(c["lengths_mm"].values()), c["branch"])
        if k not in keys:
            keys.add(k)
            uniq.append(c)
    return uniq[:top]


def stress_verdicts(candidates: list[dict], p: SweepParams | None = None, ctx: Context | None = None) -> None:
    """Add each candidate's stress check (``stress``: verdict, worst utilisation and part, per-part
    utilisation and error band) from the sweep's unit solutions (built once, cached on disk) and the
    check's verdict stage (:func:`rigfem.sweep.run.evaluate`); ``p`` the sweep parameters (default
    draft fidelity)."""
    p = p or SweepParams(fidelity="draft")
    ctx = default_context(ctx)
    ctx.observer.stage(f"unit solutions at {p.fidelity} (cached after the first run)")
    with tempfile.TemporaryDirectory(prefix="rigfem-bases-") as folder:  # the bases mapped, not held
        bases = build_bases(p, ctx.solver, folder=Path(folder), cache=ctx.cache)
        for k, c in enumerate(candidates):
            ctx.observer.stage(f"stress verdict {k + 1} of {len(candidates)}")
            row = evaluate(dict(c["lengths_mm"], branch=c["branch"]), p, bases)
            if row.get("status") != "ok":
                c["stress"] = {"verdict": "undecided", "note": row.get("note") or row.get("status")}
                continue
            parts = {k[:-len("_util_pct")]: float(v) for k, v in row.items() if k.endswith("_util_pct")}
            bands = {k[:-len("_band_pct")]: float(v) for k, v in row.items() if k.endswith("_band_pct")}
            c["stress"] = {"verdict": row["verdict"], "max_util_pct": float(row["max_util_pct"]),
                           "limiting_part": row["limiting_part"], "fidelity": p.fidelity,
                           "parts_util_pct": parts, "parts_band_pct": bands,
                           "peak_torque_Nm": float(row["peak_torque_Nm"])}
