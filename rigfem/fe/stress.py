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
import scipy.sparse as sp

from rigfem.fe.assembly import (
    NODE_BARY,
    FEMesh,
    geometry,
    points_at,
    tet_quadrature,
)
from rigfem.tensors import von_mises
from rigfem.material import lame


def _gradient_operator(fm: FEMesh, L: np.ndarray, elems) -> np.ndarray:
    """(m, nq·3, nloc) of elements ``elems``: row 3q + j takes ∂/∂x_j at barycentric point q of L
    (nq, 4) from an element's nodal values."""
    dN, _ = geometry(fm, L, elems)  # (m, nq, nloc, 3)
    m, nq, nloc, _ = dN.shape
    return np.ascontiguousarray(dN.transpose(0, 1, 3, 2)).reshape(m, nq * 3, nloc)


def _voigt_stress(G: np.ndarray, el: np.ndarray, U: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Stress (m, nq, 6, k) at the points of ``G`` (:func:`_gradient_operator`) of elements ``el``
    for U (ndof, k): Hooke's law on the displacement gradients of every load column at once."""
    m, k = len(el), U.shape[1]
    H = (G @ U.reshape(-1, 3 * k)[el]).reshape(m, -1, 3, 3, k)  # H[:, q, j, i] = ∂u_i/∂x_j
    tr = lam * (H[:, :, 0, 0] + H[:, :, 1, 1] + H[:, :, 2, 2])
    s = np.empty((m, H.shape[1], 6, k))
    for v, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))):
        s[:, :, v] = tr + 2 * mu * H[:, :, i, i] if i == j else mu * (H[:, :, i, j] + H[:, :, j, i])
    return s


def _stress_at(fm: FEMesh, E: float, nu: float, U: np.ndarray, L: np.ndarray, elems) -> np.ndarray:
    """Stress (m, nq, k, 6) at barycentric points L (nq, 4) of elements ``elems`` for U (ndof, k)."""
    lam, mu = lame(E, nu)
    return np.moveaxis(_voigt_stress(_gradient_operator(fm, L, elems), fm.elements[elems], U, lam, mu), 2, 3)


def _extrapolation(fm: FEMesh) -> tuple[np.ndarray, np.ndarray]:
    """The stiffness's quadrature points L (nq, 4) and the linear fit X (nloc, nq) through them
    to each element's own nodes."""
    L, _ = tet_quadrature(2 * (fm.order - 1))
    return L, NODE_BARY[: fm.elements.shape[1]] @ np.linalg.pinv(L)


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
    L, X = _extrapolation(fm)
    return np.einsum("aq,mqkc->makc", X, _stress_at(fm, E, nu, U.reshape(fm.ndof, -1), L, elems), optimize=True)


def nodal_stress(fm: FEMesh, E: float, nu: float, U: np.ndarray, chunk: int = 16384,
                 mem: float = 16e6) -> np.ndarray:
    """Recovered nodal stresses (k, N, 6): average of element values at each node.

    The element values at a node are the linear extrapolation of the quadrature-point stresses
    (:func:`element_node_stress`), so extrapolation and averaging are one sparse matrix applied to
    the quadrature stresses of every load column at once (``chunk`` elements and ``mem`` bytes of
    gradients at a time; the temporaries are a few times ``mem``)."""
    U = U.reshape(fm.ndof, -1)
    k, N = U.shape[1], len(fm.nodes)
    lam, mu = lame(E, nu)
    L, X = _extrapolation(fm)
    nloc, nq = X.shape
    count = np.bincount(fm.elements.ravel(), minlength=N)
    out = np.zeros((k, N, 6))
    for e0 in range(0, len(fm.elements), chunk):
        el = fm.elements[e0:e0 + chunk]
        m = len(el)
        # (node, quadrature point) weights: extrapolation to the node over the node's element count
        P = sp.csr_matrix(((X[None] / count[el][:, :, None]).ravel(),
                           (np.repeat(el.ravel(), nq), np.tile(np.arange(m * nq).reshape(m, 1, nq), (1, nloc, 1)).ravel())),
                          shape=(N, m * nq))
        G = _gradient_operator(fm, L, slice(e0, e0 + m))
        kc = max(1, int(mem // (m * nq * 9 * 8)))
        for k0 in range(0, k, kc):
            s = _voigt_stress(G, el, U[:, k0:k0 + kc], lam, mu)
            c = s.shape[-1]
            out[k0:k0 + c] += (P @ s.reshape(m * nq, 6 * c)).reshape(N, 6, c).transpose(2, 0, 1)
    return out


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


def patch(fm: FEMesh, node: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The patch of ``node``: the elements sharing it, their nodes (sorted), and each element's
    nodes as indices into those (m, nloc)."""
    if "node_elements" not in fm.cache:  # node -> the elements around it (CSR), once per mesh
        order = np.argsort(fm.elements.ravel(), kind="stable")
        start = np.searchsorted(fm.elements.ravel()[order], np.arange(len(fm.nodes) + 1))
        fm.cache["node_elements"] = (order // fm.elements.shape[1], start)
    around, start = fm.cache["node_elements"]
    elems = np.unique(around[start[node]:start[node + 1]])
    nodes, local = np.unique(fm.elements[elems], return_inverse=True)
    return elems, nodes, local.reshape(len(elems), -1)


def patch_error(fm: FEMesh, E: float, nu: float, node: int, u_patch: np.ndarray, s_patch: np.ndarray) -> float:
    """ZZ-type relative error of the recovered stress at ``node`` from the displacement (n, 3) and
    recovered stress (n, 6) at its patch's nodes (:func:`patch`): the largest von Mises norm of
    (raw element stress − recovered nodal stress) at the patch's nodes, divided by the recovered
    von Mises stress at ``node``.  Only the patch is touched (the sweep evaluates it for every
    configuration's peak)."""
    elems, nodes, local = patch(fm, node)
    lam, mu = lame(E, nu)
    L, X = _extrapolation(fm)
    raw = _voigt_stress(_gradient_operator(fm, L, elems), local, np.asarray(u_patch, float).reshape(-1, 1), lam, mu)
    Se = np.einsum("aq,mqc->mac", X, raw[..., 0], optimize=True)
    ref = von_mises(s_patch[np.searchsorted(nodes, node)])
    return float(von_mises(Se - s_patch[local]).max() / ref) if ref > 0 else 0.0


def zz_error(fm: FEMesh, E: float, nu: float, u: np.ndarray, node: int, s_nodes: np.ndarray) -> float:
    """ZZ-type relative error of the recovered stress at ``node`` (:func:`patch_error`) from the
    displacement ``u`` (3N,) and the recovered nodal stress ``s_nodes`` (N, 6) of the whole mesh."""
    _, nodes, _ = patch(fm, node)
    return patch_error(fm, E, nu, node, np.asarray(u).reshape(-1, 3)[nodes], s_nodes[nodes])
