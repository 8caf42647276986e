"""A configuration's part cases by superposition of the sweep's unit bases (:mod:`rigfem.sweep.bases`):
the peak von Mises over the crank cycle, exact but evaluated only at the nodes whose bound can
reach it, its crank angle, the error band at the peak node and the free body's balance: what the
check's verdict stage judges (:func:`case_outcome`).

Units: mm, N, MPa, deg.
"""

from __future__ import annotations

import numpy as np

from rigfem.errors import InputError
from rigfem.fe.partcase import imbalance
from rigfem.fe.stress import error_band_pct, patch, patch_error
from rigfem.tensors import von_mises
from rigfem.loads.cases import PartCase, UnitLoad
from rigfem.sweep.bases import UnitBasis
from rigfem.sweep.configs import BOUND_GROUPS, ROW_CHUNK
from rigfem.verdict.part import Outcome

__all__ = ["case_peak", "case_outcome", "superposed_peaks"]


def _columns(b: UnitBasis, u: UnitLoad, mass_ratio: float) -> list[tuple[int, float]]:
    """Basis columns and weights that reproduce unit load ``u`` (direction split if needed)."""
    if u.kind == "inertia":
        return [(b.inertia[(u.component, tuple(u.direction))], mass_ratio)]
    ang, cols = b.groups[u.group]
    a = np.mod(np.arctan2(u.direction[1], u.direction[0]), 2 * np.pi)
    diff = np.abs((ang - a + np.pi) % (2 * np.pi) - np.pi)
    i = int(np.argmin(diff))
    if diff[i] < 1e-9:
        return [(int(cols[i]), 1.0)]
    lo = int(np.searchsorted(ang, a)) - 1
    i0, i1 = lo % len(ang), (lo + 1) % len(ang)
    e0, e1 = np.array([np.cos(ang[i0]), np.sin(ang[i0])]), np.array([np.cos(ang[i1]), np.sin(ang[i1])])
    w = np.linalg.solve(np.c_[e0, e1], [np.cos(a), np.sin(a)])
    if (w < -1e-12).any() or (diff[i0] + diff[i1]) > np.pi / 2 + 1e-9:
        raise InputError(f"bearing direction on {u.group} is not between two basis directions")
    return [(int(cols[i0]), float(w[0])), (int(cols[i1]), float(w[1]))]


def _row_peaks(C: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Peak von Mises of every row of coefficients C (n, k) over the nodes of S (k, P, 6)."""
    return np.concatenate([von_mises(np.tensordot(C[s:s + ROW_CHUNK], S, 1)).max(axis=1)
                           for s in range(0, len(C), ROW_CHUNK)])


def case_peak(b: UnitBasis, case: PartCase, exact: bool = False) -> tuple[float, float]:
    """Peak von Mises (MPa) of a case over all rows, and its crank angle (deg): exact, by bounds.

    Von Mises is a norm of the stress deviator, so at node p and any row of coefficients c,
    vm(Σ c_k σ_k) ≤ Σ |c_k| vm(σ_k).  The rows are split into :data:`BOUND_GROUPS` groups,
    each bounded per node with its largest |c_k|; the combination is evaluated at the
    :data:`TOP_NODES` highest nodes of every unit field it uses (a lower bound of the peak),
    then only at the nodes whose bound reaches that lower bound, group by group.  No node that
    can hold the peak is skipped; ``exact=True`` evaluates every node (the tests' reference).
    """
    C, used = _combination(b, case)
    if used.size == 0:
        return 0.0, float(case.rows[0])
    rows_peak = superposed_peaks(b, C[:, used].astype(np.float32), used, exact)
    r = int(np.argmax(rows_peak))
    return float(rows_peak[r]), float(case.rows[r])


def _combination(b: UnitBasis, case: PartCase) -> tuple[np.ndarray, np.ndarray]:
    """A case's weights on the basis's unit loads (rows, k), and the columns it uses."""
    M = np.zeros((len(case.loads), len(b.loads)))
    for i, u in enumerate(case.loads):
        ratio = case.mass_kg / b.fe_mass if (u.kind == "inertia" and case.mass_kg) else 1.0
        for j, w in _columns(b, u, ratio):
            M[i, j] += w
    C = case.coef @ M
    return C, np.flatnonzero(np.abs(C).max(axis=0) > 0)


def case_outcome(b: UnitBasis, case: PartCase, mode: str) -> Outcome:
    """What the FE says of a case, by superposition (what :func:`rigfem.verdict.part.judge` judges,
    as it judges a check's :attr:`rigfem.fe.partcase.CaseResult.outcome`): the peak (:func:`case_peak`)
    and its crank angle; the error band at the peak node, the calibrated ZZ estimate of the
    combination there (:func:`rigfem.fe.stress.patch_error`); the free body's balance
    (:func:`rigfem.fe.partcase.imbalance`); whether anything loads the case."""
    C, used = _combination(b, case)
    loaded = bool(np.any(case.coef != 0))
    if used.size == 0:
        return Outcome(case.name, case.part, mode, 0.0, 0.0, float(case.rows[0]), loaded=loaded)
    Cu = C[:, used].astype(np.float32)
    rows_peak = superposed_peaks(b, Cu, used)
    r = int(np.argmax(rows_peak))
    c = Cu[r].astype(float)
    bound = np.abs(c) @ b.vm[used]  # no node below it can hold the row's peak
    near = np.flatnonzero(bound >= rows_peak[r] * (1 - 1e-4))
    node = int(near[np.argmax(von_mises(np.tensordot(c, b.S[np.ix_(used, near)], 1)))])
    _, nodes, _ = patch(b.mesh, node)
    u = np.tensordot(c, b.U[np.ix_(used, nodes)], 1)
    s = np.tensordot(c, b.S[np.ix_(used, nodes)], 1)
    err = error_band_pct(patch_error(b.mesh, *b.material, node, u, s), b.mesh.order)
    imb = imbalance(C, b.R, b.scale, b.lever) if b.R is not None else (0.0, 0.0)
    return Outcome(case.name, case.part, mode, float(rows_peak[r]), err, float(case.rows[r]), imb, loaded)


def superposed_peaks(b: UnitBasis, C: np.ndarray, used: np.ndarray, exact: bool = False) -> np.ndarray:
    """Peak von Mises of each row of ``C`` (rows, len(used)) over the basis fields ``used``;
    with bounds (see :func:`case_peak`) only the largest row's value is guaranteed exact."""
    if exact:
        return _row_peaks(C, b.S[used])
    cand = np.unique(b.top[used])
    rows_peak = _row_peaks(C, b.S[np.ix_(used, cand)])
    floor = rows_peak.max() * (1 - 1e-4)  # float32 round-off margin
    edges = np.linspace(0, len(C), min(BOUND_GROUPS, len(C)) + 1).astype(int)
    cmax = np.stack([np.abs(C[a:e]).max(axis=0) for a, e in zip(edges[:-1], edges[1:])])
    bound = cmax @ b.vm[used]  # (groups, N)
    for g, (a, e) in enumerate(zip(edges[:-1], edges[1:])):
        more = np.setdiff1d(np.flatnonzero(bound[g] >= floor), cand, assume_unique=True)
        if more.size:
            rows_peak[a:e] = np.maximum(rows_peak[a:e], _row_peaks(C[a:e], b.S[np.ix_(used, more)]))
    return rows_peak
