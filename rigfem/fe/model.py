"""Facade of the FE core: part mesh + material -> model -> supports + load cases -> Solution.

>>> import numpy as np
>>> from skfem import MeshTet
>>> from rigfem.mesh import PartMesh
>>> from rigfem.material import get_material
>>> from rigfem.fe import Fixed, SurfaceForce
>>> m = MeshTet.init_tensor(np.linspace(0, 100, 11), np.linspace(0, 10, 3), np.linspace(0, 10, 3))
>>> f = m.boundary_facets()
>>> x = m.p[:, m.facets[:, f]].mean(1)
>>> part = PartMesh("bar", m.p.T, m.t.T, surfaces={"root": m.facets[:, f[x[0] < 1e-9]].T,
...                                                  "tip": m.facets[:, f[x[0] > 100 - 1e-9]].T})
>>> model = build_model(part, get_material("rig_steel"), order=2)
>>> sol = solve(model, [Fixed("root")], [SurfaceForce("tip", (0, 0, -10)), SurfaceForce("tip", (0, 10, 0))])
>>> sol.U.shape[1], bool(sol.equilibrium_error.max() < 1e-7)
(2, True)
>>> peak = sol.peak(np.array([1.0, 0.5]))   # superposed case: σ = 1·σ_0 + 0.5·σ_1
>>> bool(peak.value > 0 and peak.error_pct >= 0)
True
>>> problem = StaticProblem(model, [Fixed("root")])   # factorise once ...
>>> more = problem.solve([SurfaceForce("tip", (5, 0, 0))])   # ... solve later batches on the same factors
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from rigfem.cache import NO_CACHE, Cache
from rigfem.fe.assembly import FEMesh, fe_mesh, stiffness, volume
from rigfem.fe.inputs import check_cases, check_load
from rigfem.fe.forces import body_basis, body_coefficients, nodal_vector
from rigfem.fe.solution import Solution
from rigfem.fe.solver import LinearSolver, default_method
from rigfem.fe.stress import nodal_stress
from rigfem.fe.supports import FreeBody, constraints, rigid_modes
from rigfem.material import Material
from rigfem.mesh.partmesh import PartMesh


@dataclass
class Model:
    """A part ready to solve: P1/P2 mesh, material, and its stiffness (assembled on first use,
    so a model whose unit solutions come from the cache never assembles it)."""

    part: PartMesh
    material: Material
    mesh: FEMesh
    volume: float  #: of the (curved) mesh, mm³: the part's FE mass is volume × density
    assembly_time: float = 0.0  #: s, P1/P2 mesh plus stiffness assembly
    _K: sp.csr_matrix | None = field(default=None, repr=False)

    @property
    def K(self) -> sp.csr_matrix:
        """Global stiffness matrix (assembled once, on first use)."""
        if self._K is None:
            t0 = time.perf_counter()
            self._K = stiffness(self.mesh, self.material.E, self.material.nu)
            self.assembly_time += time.perf_counter() - t0
        return self._K

    def release(self) -> None:
        """Drop the stiffness matrix and the mesh's quadrature caches once a part's solutions are
        taken (a later use assembles them again), so they are not held while later parts solve."""
        self._K = None
        self.mesh.cache.clear()


#: Poisson's ratio from which linear tetrahedra lock (too stiff in near-incompressible strain)
LOCKING_NU = 0.45


def build_model(part: PartMesh, material: Material, order: int = 2, cache: Cache = NO_CACHE) -> Model:
    """Build the P1/P2 mesh of ``part`` (through ``cache``: :func:`rigfem.fe.assembly.fe_mesh`);
    its stiffness is assembled once, when first needed.

    Warns when linear elements meet a nearly incompressible material: they lock and
    under-predict deflection and stress (use order 2).
    """
    if order == 1 and material.nu >= LOCKING_NU:
        warnings.warn(f"material {material.name!r}: nu = {material.nu:g} >= {LOCKING_NU} with linear (P1) "
                      f"tetrahedra: volumetric locking under-predicts deflection and stress; use order 2",
                      UserWarning, stacklevel=2)
    t0 = time.perf_counter()
    fm = fe_mesh(part, order, cache)
    return Model(part, material, fm, volume(fm), time.perf_counter() - t0)


def load_matrix(model: Model, cases: list) -> np.ndarray:
    """Load matrix (ndof, ncases); each case is one load or a list of loads (summed).

    Body forces (gravity, inertia) are combinations of :func:`body_basis`'s 12 vectors,
    assembled once per model; other loads are assembled one by one.  Every load is checked
    first (:func:`rigfem.fe.inputs.check_load`: a user's script builds them)."""
    check_cases(cases)
    fm, rho = model.mesh, model.material.density
    F = np.zeros((fm.ndof, len(cases)))
    C = np.zeros((12, len(cases)))
    centroid = fm.nodes.mean(0)
    for k, case in enumerate(cases):
        for load in case if isinstance(case, (list, tuple)) else [case]:
            check_load(fm, model.part.holes, load)
            w = body_coefficients(load, centroid)
            if w is None:
                F[:, k] += nodal_vector(fm, model.part.holes, rho, load)
            else:
                C[:, k] += w
    if C.any():
        F += body_basis(fm, rho)[0] @ C
    return F


@dataclass
class ExportData:
    """The model as plain arrays for another FE code (CalculiX): 0-based, C3D10/C3D4 node order."""

    nodes: np.ndarray  #: (N, 3)
    elements: np.ndarray  #: (M, 10) C3D10 or (M, 4) C3D4 order
    element_type: str  #: "C3D10" or "C3D4"
    fixed_dofs: np.ndarray  #: global DOF 3*node + component, prescribed zero
    springs: sp.coo_matrix | None  #: support spring stiffness (ShaftInHole), DOF-indexed, or None
    loads: np.ndarray  #: (3N, ncases) nodal forces
    E: float
    nu: float


def export_data(model: Model, supports: list, cases: list) -> ExportData:
    """Nodes, elements, fixed DOFs, support springs and nodal loads of a model."""
    fm = model.mesh
    fixed, springs, _ = constraints(fm, model.part.holes, supports, model.material.E)
    return ExportData(fm.nodes, fm.elements, "C3D10" if fm.order == 2 else "C3D4", fixed,
                      None if springs is None else springs.tocoo(), load_matrix(model, cases),
                      model.material.E, model.material.nu)


def supported_stiffness(model: Model, supports: list) -> tuple[sp.csr_matrix, np.ndarray, dict]:
    """The stiffness with the supports' springs (``K`` itself when there are none), the DOFs the
    supports fix, and each support's DOFs (:func:`rigfem.fe.supports.constraints`)."""
    fixed, springs, support_dofs = constraints(model.mesh, model.part.holes, supports, model.material.E)
    return (model.K if springs is None else (model.K + springs).tocsr()), fixed, support_dofs


def free_block(A: sp.csr_matrix, fixed: np.ndarray) -> sp.csr_matrix:
    """``A`` on the DOFs not in ``fixed``: a copy, or ``A`` itself when nothing is fixed (supports by
    springs alone, whose ``A`` is ``K`` + springs, a matrix of its own)."""
    if not len(fixed):
        return A
    free = np.setdiff1d(np.arange(A.shape[0]), fixed)
    return A[free][:, free]


class StaticProblem:
    """A model with its supports, factorised once; :meth:`solve` takes any number of load cases."""

    def __init__(self, model: Model, supports: list, solver: str = "auto", rtol: float = 1e-10) -> None:
        fm = model.mesh
        self.model = model
        A, self.fixed, self.support_dofs = supported_stiffness(model, supports)
        self.free_body = any(isinstance(s, FreeBody) for s in supports)
        self.free = np.setdiff1d(np.arange(fm.ndof), self.fixed)
        self._R = rigid_modes(fm.nodes)
        self._amg = (default_method(len(self.free)) if solver == "auto" else solver) == "amg"
        if self._amg:
            # keep every node's 3 DOFs for aggregation: fixed DOFs become decoupled (scaled) identity rows
            d = np.ones(fm.ndof)
            d[self.fixed] = 0.0
            D = sp.diags(d)
            A = (D @ A @ D + sp.diags((1 - d) * A.diagonal().mean())).tocsr()
            self.linear_solver = LinearSolver(A, "amg", near_null=self._R, rtol=rtol)
        else:
            A = free_block(A, self.fixed)  # (the supported stiffness is freed before the factorisation)
            self.linear_solver = LinearSolver(A, solver, rtol=rtol)

    def solve(self, cases: list, last: bool = False) -> Solution:
        """Displacements, reactions and recovered stresses of every load case (one factorisation).

        With ``last`` the factorisation is freed before the stresses are recovered (the two are a
        part's largest arrays) and this problem solves no more."""
        model, ls = self.model, self.linear_solver
        F = load_matrix(model, cases)
        U = np.zeros_like(F)
        t_solve = ls.solve_time
        if self._amg:
            keep = np.ones(len(F), bool)
            keep[self.fixed] = False
            U[:] = ls.solve(F * keep[:, None])
        else:
            U[self.free] = ls.solve(F[self.free])
        reactions = model.K @ U - F
        if self.free_body:
            U -= self._R @ np.linalg.lstsq(self._R, U, rcond=None)[0]
        if last:
            ls.release()
        t0 = time.perf_counter()
        S = nodal_stress(model.mesh, model.material.E, model.material.nu, U)
        return Solution(model=model, F=F, U=U, reactions=reactions, nodal_stress=S, support_dofs=self.support_dofs,
                        residuals=ls.residuals, backward_errors=ls.backward_errors, method=ls.method,
                        free_body=self.free_body,
                        times={"assembly": model.assembly_time, "factorise": ls.setup_time,
                               "solve": ls.solve_time - t_solve, "stress": time.perf_counter() - t0})


def solve(model: Model, supports: list, cases: list, solver: str = "auto", rtol: float = 1e-10) -> Solution:
    """Solve all load cases with one factorisation: ``StaticProblem(model, supports).solve(cases, last=True)``."""
    return StaticProblem(model, supports, solver, rtol).solve(cases, last=True)
