"""Factorise once, solve many right-hand sides; every solve checks its residual.

Every solve reports the relative residual ‖AX − F‖₂/‖F‖₂ and checks the normwise
backward error ‖AX − F‖∞ / (‖A‖∞‖X‖∞ + ‖F‖∞) ≤ ``rtol`` (a stable solve gives
~1e-16; the plain relative residual of a slender, bending-dominated part can
be ~1e-7 from round-off alone).  Direct solves get up to two steps of iterative
refinement with the same factors; a solve that still misses ``rtol`` raises
:class:`SolverError`.

Methods: ``"pardiso"`` (MKL via pypardiso, SPD mode), ``"superlu"`` (scipy), and
``"amg"``: conjugate gradients (scipy's, relative residual :data:`AMG_RTOL`) preconditioned
by one V-cycle of pyamg smoothed aggregation set up as the textbook does for elasticity:
the matrix in 3×3 node blocks (a node's three displacements aggregate together, so every
aggregate can carry the six rigid-body modes given as near-null space; aggregating single
unknowns split nodes and left that to a rounding-dependent rank cut-off), Jacobi-smoothed
prolongation, symmetric Gauss–Seidel smoothing and an exact (sparse LU) coarsest solve, not a
pseudo-inverse that truncates.  A solve that misses the backward error gets up to two
restarts on its residual, then raises :class:`SolverError`.  ``"auto"`` picks a direct method up to
``DIRECT_MAX_DOF`` unknowns, AMG above (every rig part is solved directly).

>>> import scipy.sparse as sp, numpy as np
>>> A = sp.diags([-1, 2, -1], [-1, 0, 1], shape=(5, 5), format="csr", dtype=float)
>>> s = LinearSolver(A)
>>> x = s.solve(np.ones((5, 2)))
>>> bool(s.residuals.max() < 1e-12 and s.backward_errors.max() < 1e-14)
True
"""

from __future__ import annotations

import functools
import os
import time
import weakref

import numpy as np
import scipy.sparse as sp

from rigfem.errors import ComputeError
from rigfem.fe.inputs import METHODS as _METHODS, check_solver, pardiso_missing


def _mkl_rt() -> str | None:
    """MKL's runtime library where the ``mkl`` wheel installed it, or None.  Told it, pypardiso
    does not search the whole environment for it when imported (a process's first solve:
    0.29 -> 0.15 s, measured in issue 26)."""
    from importlib import metadata

    try:
        found = sorted((f for f in metadata.files("mkl") or () if f.name.startswith("libmkl_rt")),
                       key=lambda f: len(f.name))
    except metadata.PackageNotFoundError:
        return None
    return next((str(p) for p in (f.locate().resolve() for f in found) if p.is_file()), None)


@functools.lru_cache(maxsize=None)
def pardiso():
    """pypardiso, imported on first use (loading MKL takes a tenth of a second a warm check,
    which solves nothing, does not need), or None on a platform without MKL."""
    if "PYPARDISO_MKL_RT" not in os.environ and (path := _mkl_rt()):
        os.environ["PYPARDISO_MKL_RT"] = path
    try:
        import pypardiso
    except ImportError:  # pragma: no cover - platform without MKL
        return None
    # pypardiso searches the whole prefix for libmkl_rt on every new solver unless told where it is
    os.environ.setdefault("PYPARDISO_MKL_RT", pypardiso.ps.libmkl._name)
    return pypardiso


DIRECT_MAX_DOF = 600_000

#: PARDISO's settings (pypardiso's 1-based iparm numbers): our own values, not MKL's defaults (1);
#: parallel nested dissection ordering (2); no iterative refinement inside PARDISO (8), since
#: :meth:`LinearSolver.solve` checks every solve's backward error and refines only where needed:
#: MKL's default of 2 steps on every solve made a rail's many-load solve several times slower, at
#: the same residuals (``python benchmarks/bench_pardiso.py``); no scaling, an SPD
#: matrix needs none (11); the matrix stored internally in variable-size blocks where 80 % of
#: neighbouring rows share their pattern (37 = -80): a node's three displacement rows do.  The
#: blocks trade a faster analysis for a slower numeric factorisation and solve; on the draft
#: 1000 mm rail analysis + factorisation take 13 % less time and the process 11 % less memory,
#: a solve of 60 loads 23 % more time, at the same residuals (same benchmark).
PARDISO_IPARM = {1: 1, 2: 3, 8: 0, 11: 0, 37: -80}


METHODS = _METHODS  #: (rigfem.fe.inputs.METHODS)
#: relative residual ‖Ax − b‖₂/‖b‖₂ at which CG stops (the backward error then checked is far smaller)
AMG_RTOL = 1e-12
#: unknowns below which pyamg solves the coarsest level directly
AMG_MAX_COARSE = 500


class SolverError(ComputeError):
    """The model as given has no trustworthy solution (singular or ill-conditioned)."""


def default_method(n: int) -> str:
    """The method ``"auto"`` resolves to for ``n`` unknowns."""
    if n > DIRECT_MAX_DOF:
        return "amg"
    return "pardiso" if pardiso() is not None else "superlu"


def amg_hierarchy(A: sp.csr_matrix, near_null: np.ndarray | None):
    """pyamg's smoothed-aggregation hierarchy of the SPD elasticity matrix ``A`` (3 unknowns a
    node) with the rigid-body modes ``near_null`` (n, 6) as near-null space (see the module's
    docstring for why each setting)."""
    import pyamg

    B = None if near_null is None else np.asarray(near_null, dtype=float)
    blocked = A.tobsr(blocksize=(3, 3)) if A.shape[0] % 3 == 0 else A
    return pyamg.smoothed_aggregation_solver(blocked, B=B, symmetry="hermitian", strength="symmetric",
                                             smooth=("jacobi", {"weighting": "local"}),
                                             presmoother=("block_gauss_seidel", {"sweep": "symmetric"}),
                                             postsmoother=("block_gauss_seidel", {"sweep": "symmetric"}),
                                             max_coarse=AMG_MAX_COARSE, coarse_solver="splu")


class LinearSolver:
    """Factorisation (or AMG hierarchy) of a symmetric positive definite matrix."""

    def __init__(self, A: sp.spmatrix, method: str = "auto", near_null: np.ndarray | None = None,
                 rtol: float = 1e-10, maxiter: int = 2000) -> None:
        check_solver(method)  # a script names it (rigfem.fe.inputs)
        self.A = sp.csr_matrix(A)
        self.A.sort_indices()
        n = self.A.shape[0]
        self.method = default_method(n) if method == "auto" else method
        if self.method == "pardiso" and pardiso() is None:
            pardiso_missing()
        self.rtol = rtol
        self.maxiter = maxiter
        self.iterations = 0  #: CG iterations of the last AMG solve (all right-hand sides and restarts)
        self.residuals = np.zeros(0)  #: relative residuals ‖AX − F‖₂/‖F‖₂ of the last solve
        self.backward_errors = np.zeros(0)  #: normwise backward errors of the last solve (checked ≤ rtol)
        self._norm_A = float(abs(self.A).sum(1).max()) if self.A.nnz else 0.0
        t0 = time.perf_counter()
        if self.method == "pardiso":
            self._ps = pardiso().PyPardisoSolver(mtype=2)  # real SPD, upper triangle
            # MKL keeps the factors outside Python: release them with this solver, or a long run
            # (a sweep, a convergence study, the test suite) accumulates every factorisation
            weakref.finalize(self, self._ps.free_memory, True)
            for i, v in PARDISO_IPARM.items():
                self._ps.set_iparm(i, v)
            self._upper = sp.triu(self.A, format="csr")
            self._upper.sort_indices()
            self._ps.factorize(self._upper)
            if isinstance(self._ps.factorized_A, sp.csr_matrix):  # pypardiso keeps a copy to know
                self._upper = self._ps.factorized_A  # its matrix again: solve with that, hold one
        elif self.method == "superlu":
            import scipy.sparse.linalg as spla

            try:
                self._lu = spla.splu(self.A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                     options={"SymmetricMode": True})
            except RuntimeError as e:
                raise SolverError(f"stiffness matrix is singular ({e}): check supports and mesh connectivity") from None
        else:
            self._ml = amg_hierarchy(self.A, near_null)
        self.setup_time = time.perf_counter() - t0
        self.solve_time = 0.0

    def release(self) -> None:
        """Free the factors (or hierarchy) and the matrix now, not when this solver is collected;
        it solves no more."""
        if self.method == "pardiso":
            self._ps.free_memory(True)
        self.A = self._upper = self._lu = self._ml = None

    def _raw(self, F: np.ndarray) -> np.ndarray:
        if self.method == "pardiso":
            return np.asarray(self._ps.solve(self._upper, F)).reshape(F.shape)
        if self.method == "superlu":
            return self._lu.solve(F)
        import scipy.sparse.linalg as spla

        X = np.zeros_like(F)
        M = self._ml.aspreconditioner(cycle="V")
        count = [0]

        def step(xk) -> None:
            count[0] += 1

        for k in range(F.shape[1]):
            if np.any(F[:, k]):
                X[:, k] = spla.cg(self.A, F[:, k], rtol=AMG_RTOL, atol=0.0, maxiter=self.maxiter, M=M,
                                  callback=step)[0]
        self.iterations += count[0]
        return X

    def _backward(self, R: np.ndarray, X: np.ndarray, F: np.ndarray) -> np.ndarray:
        """Normwise backward error ‖R‖∞ / (‖A‖∞‖X‖∞ + ‖F‖∞) per column of the residual R = AX − F
        (0 for F = 0)."""
        den = self._norm_A * np.abs(X).max(0) + np.abs(F).max(0)
        r = np.abs(R).max(0)
        return np.where(den > 0, r / np.where(den > 0, den, 1.0), np.where(r > 0, np.inf, 0.0))

    def solve(self, F: np.ndarray) -> np.ndarray:
        """Solve A X = F for one (n,) or many (n, k) right-hand sides; residual-checked.

        One product A·X per pass gives the residual that decides the refinement, the reported
        relative residual and the checked backward error of the returned X."""
        if self.A is None:
            raise RuntimeError("this solver's factors were released: it solves no more")
        F = np.asarray(F, dtype=float)
        one = F.ndim == 1
        F2 = F.reshape(len(F), -1)
        # PARDISO reads the right-hand sides column by column: handed so, pypardiso copies none
        F2 = np.asfortranarray(F2) if self.method == "pardiso" else np.ascontiguousarray(F2)
        if not np.isfinite(F2).all():
            raise ComputeError("load vector contains NaN or inf")
        t0 = time.perf_counter()
        self.iterations = 0
        X = self._raw(F2) if F2.size else np.zeros_like(F2)
        for step in range(3):  # up to 2 refinements on the same factors (AMG: restarts on the residual)
            R = self.A @ X - F2
            be = self._backward(R, X, F2)
            if step == 2 or not (be > (1e-13 if self.method != "amg" else self.rtol)).any():
                break
            X -= self._raw(R)
        self.solve_time += time.perf_counter() - t0
        fn = np.linalg.norm(F2, axis=0)
        self.residuals = np.linalg.norm(R, axis=0) / np.where(fn > 0, fn, 1.0)
        self.backward_errors = be
        if not np.isfinite(X).all() or (self.backward_errors > self.rtol).any():
            raise SolverError(f"{self.method} solve failed: backward error {np.nanmax(self.backward_errors):.3g} > "
                              f"{self.rtol:g}; the model is singular or ill-conditioned (check supports and "
                              f"mesh connectivity)")
        return X[:, 0] if one else X
