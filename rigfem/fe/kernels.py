"""The compiled (numba) kernels of the stiffness assembly, in their own module so that only a
run that assembles a matrix imports numba (a warm check, which loads its solutions, does not)."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["block_pattern", "add_elastic_blocks"]


@numba.njit(cache=True)
def block_pattern(el, n):  # pragma: no cover - compiled
    """CSR pattern of the node graph and each element pair's position in it.  Plain loops only:
    numba compiles numpy's generic sort, search and cumsum in seconds, these in about one."""
    m, k = el.shape
    eptr = np.zeros(n + 1, np.int64)  # node -> elements (counting sort)
    for e in range(m):
        for a in range(k):
            eptr[el[e, a] + 1] += 1
    for r in range(n):
        eptr[r + 1] += eptr[r]
    elist = np.empty(eptr[n], np.int64)
    fill = np.empty(n, np.int64)
    for r in range(n):
        fill[r] = eptr[r]
    for e in range(m):
        for a in range(k):
            elist[fill[el[e, a]]] = e
            fill[el[e, a]] += 1
    mark = np.empty(n, np.int64)
    for r in range(n):
        mark[r] = -1
    indptr = np.zeros(n + 1, np.int64)
    for r in range(n):  # count distinct neighbours
        c = 0
        for p in range(eptr[r], eptr[r + 1]):
            for b in range(k):
                j = el[elist[p], b]
                if mark[j] != r:
                    mark[j] = r
                    c += 1
        indptr[r + 1] = indptr[r] + c
    indices = np.empty(indptr[n], np.int32)
    for r in range(n):
        mark[r] = -1
    for r in range(n):
        c = indptr[r]
        for p in range(eptr[r], eptr[r + 1]):
            for b in range(k):
                j = el[elist[p], b]
                if mark[j] != r:
                    mark[j] = r
                    i = c  # insertion into the row's sorted columns
                    while i > indptr[r] and indices[i - 1] > j:
                        indices[i] = indices[i - 1]
                        i -= 1
                    indices[i] = j
                    c += 1
    pos = np.empty((m, k, k), np.int64)
    for e in range(m):
        for a in range(k):
            r = el[e, a]
            for b in range(k):
                j = el[e, b]
                lo, hi = indptr[r], indptr[r + 1]
                while lo < hi:  # binary search of column j in row r
                    mid = (lo + hi) // 2
                    if indices[mid] < j:
                        lo = mid + 1
                    else:
                        hi = mid
                pos[e, a, b] = lo
    return indptr, indices, pos


@numba.njit(cache=True)
def add_elastic_blocks(dN, w, lam, mu, pos, data):  # pragma: no cover - compiled
    """data[pos[e, a, b]] += ∫ (λ ∇N_a ⊗ ∇N_b + μ ∇N_b ⊗ ∇N_a + μ (∇N_a·∇N_b) I) for every element e."""
    m, nq, nloc, _ = dN.shape
    G = np.empty((3, 3))
    for e in range(m):
        for a in range(nloc):
            for b in range(a, nloc):  # block (b, a) is the transpose of block (a, b)
                G[:, :] = 0.0  # G[i, j] = Σ_q w ∂_i N_a ∂_j N_b
                for q in range(nq):
                    wq = w[e, q]
                    for i in range(3):
                        gi = wq * dN[e, q, a, i]
                        for j in range(3):
                            G[i, j] += gi * dN[e, q, b, j]
                tr = mu * (G[0, 0] + G[1, 1] + G[2, 2])
                p = pos[e, a, b]
                pt = pos[e, b, a]
                for i in range(3):
                    for j in range(3):
                        v = lam * G[i, j] + mu * G[j, i]
                        data[p, i, j] += v
                        if b != a:
                            data[pt, j, i] += v
                    data[p, i, i] += tr
                    if b != a:
                        data[pt, i, i] += tr
