"""Stress tensor invariants: von Mises and principal stresses (no FE machinery, so the verdict can use them cheaply)."""

from __future__ import annotations

import numpy as np


def von_mises(s: np.ndarray) -> np.ndarray:
    """Von Mises stress of Voigt tensors (..., 6)."""
    xx, yy, zz, xy, yz, xz = np.moveaxis(s, -1, 0)
    return np.sqrt(np.maximum(0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2)
                              + 3 * (xy ** 2 + yz ** 2 + xz ** 2), 0.0))


def principal(s: np.ndarray) -> np.ndarray:
    """Principal stresses (..., 3), descending, of Voigt tensors (..., 6)."""
    xx, yy, zz, xy, yz, xz = np.moveaxis(s, -1, 0)
    T = np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)], -2)
    return np.linalg.eigvalsh(T)[..., ::-1]


def peak_von_mises(C: np.ndarray, S: np.ndarray, unit_vm: np.ndarray | None = None,
                   chunk: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Largest von Mises stress over the nodes, and its node, of every combination row of C.

    ``C`` (n, k) weights the unit stress fields ``S`` (k, N, 6).  Exact, but cheap: von Mises
    is a seminorm, so for every row r of a chunk of neighbouring rows (crank angles)
    ``vm_r(n) ≤ B(n) = Σ_k max_r |c_rk| vm(σ_k(n))``, from the unit fields' own von Mises
    ``unit_vm`` (k, N).  The chunk is evaluated exactly at the nodes of highest B, which gives
    a lower bound L of every row's peak, then at every node with B(n) ≥ L: no other node can
    hold a peak of the chunk.
    """
    C = np.atleast_2d(C)
    k, N = S.shape[:2]
    if unit_vm is None:
        unit_vm = von_mises(S)
    slack = 1 + 10 * k * np.finfo(S.dtype).eps  # rounding of the bound itself (float32 or float64)
    vals, nodes = np.zeros(len(C)), np.zeros(len(C), dtype=np.int64)
    used = np.flatnonzero(np.abs(C).max(axis=0) > 0)
    if used.size == 0:
        return vals, nodes
    C, V = C[:, used], unit_vm[used]
    for s in range(0, len(C), chunk):
        c = C[s:s + chunk]
        bound = np.abs(c).max(axis=0).astype(V.dtype) @ V  # (N,)
        first = np.argpartition(bound, -16)[-16:] if N > 16 else np.arange(N)
        lower = von_mises(np.tensordot(c, S[np.ix_(used, first)], 1)).max(axis=1).min()
        cand = np.flatnonzero(bound * slack >= lower)
        vm = von_mises(np.tensordot(c, S[np.ix_(used, cand)], 1))
        i = vm.argmax(axis=1)
        vals[s:s + chunk], nodes[s:s + chunk] = vm[np.arange(len(c)), i], cand[i]
    return vals, nodes
