"""Factorise once, solve many right-hand sides; every solve checks its residual.

Methods: ``"pardiso"`` (MKL via pypardiso, SPD mode), ``"superlu"`` (scipy), and
``"amg"`` (conjugate gradients preconditioned by pyamg smoothed aggregation with
the rigid-body modes as near-null space).  ``"auto"`` picks a direct method up to
``DIRECT_MAX_DOF`` unknowns, AMG above.

>>> import scipy.sparse as sp, numpy as np
>>> A = sp.diags([-1, 2, -1], [-1, 0, 1], shape=(5, 5), format="csr", dtype=float)
>>> s = LinearSolver(A)
>>> x = s.solve(np.ones((5, 2)))
>>> bool(s.residuals.max() < 1e-12)
True
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from rigfem.errors import InputError

try:
    import pypardiso
except ImportError:  # pragma: no cover - platform without MKL
    pypardiso = None

DIRECT_MAX_DOF = 600_000
METHODS = ("auto", "pardiso", "superlu", "amg")


class SolverError(InputError):
    """The model as given has no trustworthy solution (singular or ill-conditioned)."""


def default_method(n: int) -> str:
    """The method ``"auto"`` resolves to for ``n`` unknowns."""
    if n > DIRECT_MAX_DOF:
        return "amg"
    return "pardiso" if pypardiso is not None else "superlu"


class LinearSolver:
    """Factorisation (or AMG hierarchy) of a symmetric positive definite matrix."""

    def __init__(self, A: sp.spmatrix, method: str = "auto", near_null: np.ndarray | None = None,
                 rtol: float = 1e-8) -> None:
        if method not in METHODS:
            raise InputError(f"solver = {method!r} must be one of {METHODS}")
        self.A = sp.csr_matrix(A)
        self.A.sort_indices()
        n = self.A.shape[0]
        self.method = default_method(n) if method == "auto" else method
        if self.method == "pardiso" and pypardiso is None:
            raise InputError("solver = 'pardiso' is not available here (pypardiso does not import)")
        self.rtol = rtol
        self.residuals = np.zeros(0)
        t0 = time.perf_counter()
        if self.method == "pardiso":
            self._ps = pypardiso.PyPardisoSolver(mtype=2)  # real SPD, upper triangle
            self._ps.set_iparm(11, 0)  # no scaling needed for SPD
            self._upper = sp.triu(self.A, format="csr")
            self._upper.sort_indices()
            self._ps.factorize(self._upper)
        elif self.method == "superlu":
            try:
                self._lu = spla.splu(self.A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                     options={"SymmetricMode": True})
            except RuntimeError as e:
                raise SolverError(f"stiffness matrix is singular ({e}): check supports and mesh connectivity") from None
        else:
            import pyamg
            B = None if near_null is None else np.asarray(near_null, dtype=float)
            self._ml = pyamg.smoothed_aggregation_solver(self.A, B=B, symmetry="hermitian", max_coarse=500)
        self.setup_time = time.perf_counter() - t0
        self.solve_time = 0.0

    def _raw(self, F: np.ndarray) -> np.ndarray:
        if self.method == "pardiso":
            return np.asarray(self._ps.solve(self._upper, F)).reshape(F.shape)
        if self.method == "superlu":
            return self._lu.solve(F)
        X = np.zeros_like(F)
        for k in range(F.shape[1]):
            if np.any(F[:, k]):
                X[:, k] = self._ml.solve(F[:, k], x0=np.zeros(len(F)), tol=self.rtol * 1e-2, accel="cg",
                                         maxiter=2000)
        return X

    def solve(self, F: np.ndarray) -> np.ndarray:
        """Solve A X = F for one (n,) or many (n, k) right-hand sides; residual-checked."""
        F = np.asarray(F, dtype=float)
        one = F.ndim == 1
        F2 = np.ascontiguousarray(F.reshape(len(F), -1))
        if not np.isfinite(F2).all():
            raise InputError("load vector contains NaN or inf")
        t0 = time.perf_counter()
        X = self._raw(F2) if F2.size else np.zeros_like(F2)
        self.solve_time += time.perf_counter() - t0
        fn = np.linalg.norm(F2, axis=0)
        rn = np.linalg.norm(self.A @ X - F2, axis=0)
        self.residuals = np.where(fn > 0, rn / np.where(fn > 0, fn, 1.0), rn)
        if not np.isfinite(X).all() or (self.residuals > self.rtol).any():
            raise SolverError(f"{self.method} solve failed: relative residual {np.nanmax(self.residuals):.3g} > "
                              f"{self.rtol:g}; the model is singular or ill-conditioned (check supports and "
                              f"mesh connectivity)")
        return X[:, 0] if one else X
