"""Stresses from displacements: tensors, von Mises, principal stresses, nodal recovery, ZZ error.

Tensor components in Voigt order ``xx, yy, zz, xy, yz, xz`` (ParaView's order for
6-component symmetric tensors).  Nodal stresses are recovered by averaging the
element stress fields, extrapolated to each node from the quadrature points, over the
elements sharing it; the
error estimate of a nodal value is the Zienkiewicz–Zhu-type discrepancy between
the recovered and the raw element stresses on the patch of elements around
it: ``max_{e ∋ node, j ∈ e} vm(σ_e(x_j) − σ*(x_j)) / vm(σ*(node))``.  It is an *estimate*, not a
bound: the band a peak is reported with, ``peak·(1 ± error_pct/100)``, is that estimate times a
per-order factor (:data:`BAND_FACTOR`) calibrated so the band covers the converged value
(:func:`error_band_pct`).
"""

from __future__ import annotations

import numpy as np

from rigfem.fe.assembly import (
    NODE_BARY,
    FEMesh,
    element_dofs,
    geometry,
    points_at,
    tet_quadrature,
)
from rigfem.fe.tensors import von_mises
from rigfem.material import lame


def _stress_at(fm: FEMesh, E: float, nu: float, U: np.ndarray, L: np.ndarray, elems) -> np.ndarray:
    """Stress (m, nq, k, 6) at barycentric points L (nq, 4) of elements ``elems`` for U (ndof, k)."""
    lam, mu = lame(E, nu)
    dN, _ = geometry(fm, L, elems)
    el = fm.elements[elems]
    Ue = U[element_dofs(el)].reshape(len(el), el.shape[1], 3, -1)
    H = np.einsum("maik,mqaj->mqkij", Ue, dN, optimize=True)
    e = 0.5 * (H + np.swapaxes(H, -1, -2))
    tr = np.trace(e, axis1=-2, axis2=-1)
    s = 2 * mu * e
    s[..., [0, 1, 2], [0, 1, 2]] += (lam * tr)[..., None]
    return np.stack([s[..., 0, 0], s[..., 1, 1], s[..., 2, 2], s[..., 0, 1], s[..., 1, 2], s[..., 0, 2]], -1)


def quadrature_stress(fm: FEMesh, E: float, nu: float, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stress (M, nq, k, 6) at the stiffness quadrature points and their coordinates (M, nq, 3)."""
    U = U.reshape(fm.ndof, -1)
    L, _ = tet_quadrature(2 * (fm.order - 1))
    return _stress_at(fm, E, nu, U, L, slice(None)), points_at(fm, L)


def element_node_stress(fm: FEMesh, E: float, nu: float, U: np.ndarray, elems=slice(None)) -> np.ndarray:
    """Raw element stresses (m, nloc, k, 6) at each element's own nodes, extrapolated linearly
    from the stiffness's quadrature points (as CalculiX does for C3D10).  Exact on straight P2
    elements, whose stress is linear; on curved ones it is the robust choice (no evaluation at
    a corner where the mapping is most distorted)."""
    L, _ = tet_quadrature(2 * (fm.order - 1))
    X = NODE_BARY[: fm.elements.shape[1]] @ np.linalg.pinv(L)  # (nloc, nq): linear fit through the points
    return np.einsum("aq,mqkc->makc", X, _stress_at(fm, E, nu, U.reshape(fm.ndof, -1), L, elems), optimize=True)


def nodal_stress(fm: FEMesh, E: float, nu: float, U: np.ndarray, chunk: int = 2048) -> np.ndarray:
    """Recovered nodal stresses (k, N, 6): average of element values at each node."""
    U = U.reshape(fm.ndof, -1)
    k = U.shape[1]
    acc = np.zeros((len(fm.nodes), k * 6))
    for s in range(0, len(fm.elements), chunk):
        sl = slice(s, s + chunk)
        idx = fm.elements[sl].ravel()
        Se = np.ascontiguousarray(element_node_stress(fm, E, nu, U, sl)).reshape(len(idx), k * 6)
        for c in range(k * 6):
            acc[:, c] += np.bincount(idx, Se[:, c], minlength=len(fm.nodes))
    count = np.bincount(fm.elements.ravel(), minlength=len(fm.nodes))
    # contiguous (k, N, 6): every superposition over the cases reads it whole
    return np.ascontiguousarray((acc / count[:, None]).reshape(len(fm.nodes), k, 6).transpose(1, 0, 2))


#: Factor on the ZZ estimate per element order, so that ``peak·(1 ± factor·zz_error)`` covers the
#: converged peak: the smallest multiple of 0.05 (at least 1) covering every calibration case of that
#: order.  Source: results/convergence/band_coverage.json ("calibration"), written by
#: ``python benchmarks/band_coverage.py`` (closed forms at non-preset sizes, and the reference parts'
#: h-sequence levels; coverage is measured on the other cases).  Linear tetrahedra under-predict
#: bending stress so badly that their recovered peak and their ZZ discrepancy are both low: hence
#: the larger P1 factor.
BAND_FACTOR = {1: 2.05, 2: 1.0}


def error_band_pct(zz: float, order: int) -> float:
    """Half-width of a peak's error band, in % of the peak: the calibrated ZZ estimate (an estimate, not a bound)."""
    return 100.0 * BAND_FACTOR[order] * zz


def zz_error(fm: FEMesh, E: float, nu: float, u: np.ndarray, node: int, s_nodes: np.ndarray) -> float:
    """ZZ-type relative error of the recovered stress at ``node``.

    Over the patch of elements sharing ``node``: the largest von Mises norm of
    (raw element stress − recovered nodal stress ``s_nodes`` (N, 6)) at the
    patch's nodes, divided by the recovered von Mises stress at ``node``.
    """
    elems = np.nonzero((fm.elements == node).any(1))[0]
    Se = element_node_stress(fm, E, nu, u, elems)[:, :, 0]
    ref = von_mises(s_nodes[node])
    return float(von_mises(Se - s_nodes[fm.elements[elems]]).max() / ref) if ref > 0 else 0.0
