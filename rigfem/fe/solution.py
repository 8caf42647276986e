"""The result of a linear FE solve: displacements, reactions, stresses per load case.

Stresses are linear in the loads, so a combination of the cases with
coefficients c (e.g. the load factors of one crank angle) is
``σ(c) = Σ_k c_k σ_k``: :meth:`Solution.stress` is one tensordot.  Once the
combinations a report needs are known, :meth:`Solution.kept` holds just those
(a part's unit solutions are most of a check's memory).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np

from rigfem.fe.stress import error_band_pct, zz_error
from rigfem.tensors import peak_von_mises, principal, von_mises


@dataclass(frozen=True)
class Peak:
    """Peak von Mises stress with its location and discretisation-error estimate.

    ``error_pct`` is the band every report shows, ``peak·(1 ± error_pct/100)``: an estimate of the
    discretisation error (calibrated ZZ recovery), not a bound; ``zz_error`` is the raw estimator it is
    calibrated from (a fraction)."""

    value: float  #: MPa
    node: int
    xyz: tuple[float, float, float]
    surface: str  #: named surface (a hole first), "(unnamed boundary)" or "(interior)"
    surfaces: tuple[str, ...]  #: every named surface the node lies on
    zz_error: float  #: raw ZZ estimate, a fraction of ``value`` (recovered vs raw stress on the node's patch)
    error_pct: float  #: the error band's half-width, % of ``value``: ``zz_error`` × the order's calibrated factor


@dataclass
class Solution:
    """Displacements U (3N, k) and recovered nodal stresses (k, N, 6) of k load cases."""

    model: object  #: the rigfem.fe.model.Model solved (not imported: the model module builds Solutions)
    F: np.ndarray  #: (3N, k) applied nodal loads
    U: np.ndarray  #: (3N, k) displacements
    reactions: np.ndarray  #: (3N, k) support forces on the part, K u − f
    nodal_stress: np.ndarray  #: (k, N, 6) Voigt xx, yy, zz, xy, yz, xz
    support_dofs: dict[str, np.ndarray]  #: support name -> its DOFs
    residuals: np.ndarray  #: (k,) relative residual ‖Ku − f‖/‖f‖ of each solve (free DOFs)
    backward_errors: np.ndarray  #: (k,) normwise backward error of each solve (checked ≤ rtol)
    method: str
    free_body: bool
    times: dict[str, float] = field(default_factory=dict)
    key: str = ""  #: the key of its cache entry (rigfem.fe.cache), "" if it has none
    #: (m, k) after :meth:`kept`: its m cases are these combinations of the k load cases solved
    #: (None: the solved cases themselves); combinations are still given over the k solved cases
    basis: np.ndarray | None = None
    _unit_vm: np.ndarray | None = field(default=None, repr=False)  #: (k, N) von Mises of each case

    @property
    def cases(self) -> int:
        """How many load cases were solved (k): the length of every combination c."""
        return self.U.shape[1] if self.basis is None else self.basis.shape[1]

    def _coef(self, c) -> np.ndarray | int:
        """c checked: its coefficients, or for a kept solution the index of the case that is c."""
        k = self.cases
        c = np.eye(k)[0] if c is None and k == 1 else np.asarray(c, dtype=float)
        if c.shape != (k,) or not np.isfinite(c).all():
            from rigfem.errors import InputError
            raise InputError(f"combination coefficients must be {k} finite numbers")
        if self.basis is None:
            return c
        hit = np.flatnonzero((self.basis == c).all(1))
        if not hit.size:  # a combination the reduction dropped: no numbers rather than wrong ones
            raise ValueError(f"this solution kept {len(self.basis)} combinations of its {k} load cases, not this one")
        return int(hit[0])

    def _combine(self, A: np.ndarray, c, axis: int) -> np.ndarray:
        w = self._coef(c)
        return np.take(A, w, axis) if isinstance(w, int) else np.tensordot(A, w, (axis, 0))

    def kept(self, C: np.ndarray) -> Solution:
        """A solution that holds only the combinations C (m, k) of the load cases, as its m cases.

        Everything this class answers for a kept combination is the same number as before (a
        kept case is a copy or the same product), and a combination not kept raises.  The solves'
        own checks (residuals, backward and equilibrium errors) are those of the k cases solved."""
        C = np.unique(np.atleast_2d(np.asarray(C, dtype=float)), axis=0)
        w = [self._coef(c) for c in C]
        if self.basis is None:
            out = dataclasses.replace(self, F=self.F @ C.T, U=self.U @ C.T, reactions=self.reactions @ C.T,
                                      nodal_stress=np.tensordot(C, self.nodal_stress, 1), basis=C, _unit_vm=None)
        else:  # already kept: the cases are copied
            out = dataclasses.replace(self, F=self.F[:, w], U=self.U[:, w], reactions=self.reactions[:, w],
                                      nodal_stress=self.nodal_stress[w], basis=C, _unit_vm=None)
        out.__dict__["equilibrium_error"] = self.equilibrium_error  # cached_property: the k solves'
        return out

    def displacement(self, c=None) -> np.ndarray:
        """Nodal displacement (N, 3) of the combination c (default: the only case)."""
        return self._combine(self.U, c, 1).reshape(-1, 3)

    def loads(self, c=None) -> np.ndarray:
        """Applied nodal loads (3N,) of the combination c."""
        return self._combine(self.F, c, 1)

    def reaction(self, c=None) -> np.ndarray:
        """Support forces on the part (3N,) of the combination c."""
        return self._combine(self.reactions, c, 1)

    def stress(self, c=None) -> np.ndarray:
        """Recovered nodal stress (N, 6) of the combination c."""
        return self._combine(self.nodal_stress, c, 0)

    def von_mises(self, c=None) -> np.ndarray:
        """Nodal von Mises stress (N,) of the combination c."""
        return von_mises(self.stress(c))

    def peak_sweep(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Peak nodal von Mises (n,) and its node (n,) for each row of combinations C (n, k).

        The cheap path for a sweep over crank angles (exact: :func:`rigfem.tensors.peak_von_mises`);
        call :meth:`peak` on the worst row for location, surface and error estimate.
        """
        C = np.atleast_2d(np.asarray(C, dtype=float))
        if C.shape[1] != self.cases or not np.isfinite(C).all():
            from rigfem.errors import InputError
            raise InputError(f"combination matrix must be (n, {self.cases}) and finite, got {C.shape}")
        if self.basis is not None:  # as combinations of the kept cases
            C = np.eye(len(self.basis))[[self._coef(c) for c in C]]
        if self._unit_vm is None:
            self._unit_vm = von_mises(self.nodal_stress)
        return peak_von_mises(C, self.nodal_stress, self._unit_vm)

    def principal(self, c=None) -> np.ndarray:
        """Nodal principal stresses (N, 3), descending, of the combination c."""
        return principal(self.stress(c))

    def peak(self, c=None) -> Peak:
        """Peak nodal von Mises of the combination c, where it is and its error estimate."""
        s = self.stress(c)
        vm = von_mises(s)
        n = int(np.argmax(vm))
        fm, mat = self.model.mesh, self.model.material
        err = zz_error(fm, mat.E, mat.nu, self.displacement(c).ravel(), n, s)
        names = self.surfaces_of(n)
        where = names[0] if names else "(unnamed boundary)" if n in self._boundary_nodes() else "(interior)"
        return Peak(float(vm[n]), n, tuple(float(v) for v in fm.nodes[n]), where, names, err,
                    error_band_pct(err, fm.order))

    def surfaces_of(self, node: int) -> tuple[str, ...]:
        """Named surfaces containing ``node``, holes first."""
        names = [nm for nm, tri in self.model.mesh.surfaces.items() if (tri == node).any()]
        return tuple(sorted(names, key=lambda nm: nm not in self.model.part.holes))

    def _boundary_nodes(self) -> set[int]:
        t = self.model.mesh.elements[:, :4]
        faces = np.sort(np.vstack([t[:, [0, 1, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 3]], t[:, [1, 2, 3]]]), 1)
        u, cnt = np.unique(faces, axis=0, return_counts=True)
        b = set(u[cnt == 1].ravel().tolist())
        el = self.model.mesh.elements
        if el.shape[1] == 10:  # a mid-edge node is on the boundary if both its corners are (sufficient here)
            from rigfem.fe.assembly import TET_EDGES
            for a, (i, j) in enumerate(TET_EDGES):
                m = np.isin(el[:, i], list(b)) & np.isin(el[:, j], list(b))
                b.update(el[m, 4 + a].tolist())
        return b

    def resultants(self, dofs: np.ndarray, vec: np.ndarray) -> np.ndarray:
        """Force and moment about the origin (k, 6) of nodal vectors ``vec`` (3N, k) over ``dofs``."""
        x, dofs = self.model.mesh.nodes, np.asarray(dofs)
        if len(dofs) == len(vec) and np.array_equal(dofs, np.arange(len(vec))):  # every DOF: no gather
            return _force_moment(x, vec.reshape(len(x), 3, -1))
        nodes, where = np.unique(dofs // 3, return_inverse=True)
        v = np.zeros((len(nodes), 3, vec.shape[1]))
        v[where, dofs % 3] = vec[dofs]
        return _force_moment(x[nodes], v)

    @property
    def support_reactions(self) -> dict[str, np.ndarray]:
        """Support name -> reaction force and moment about the origin (k, 6) on the part."""
        return {name: self.resultants(d, self.reactions) for name, d in self.support_dofs.items()}

    @functools.cached_property
    def equilibrium_error(self) -> np.ndarray:
        """(k,) |Σ applied + Σ reactions| (forces and moments) relative to Σ|applied nodal forces|."""
        x = self.model.mesh.nodes
        tot = _force_moment(x, (self.F + self.reactions).reshape(len(x), 3, -1))
        L = np.ptp(self.model.mesh.nodes, axis=0).max()
        scale = np.linalg.norm(self.F.reshape(-1, 3, self.F.shape[1]), axis=1).sum(0)
        err = np.hypot(np.linalg.norm(tot[:, :3], axis=1), np.linalg.norm(tot[:, 3:], axis=1) / L)
        return np.where(scale > 0, err / np.where(scale > 0, scale, 1), err)


def _force_moment(x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Σ f and Σ x × f about the origin (k, 6) of nodal forces ``v`` (n, 3, k) at points ``x`` (n, 3)."""
    # one pass over v (einsum's own loop: a threaded BLAS stalls on a busy machine, 1 s for 20 ms of work)
    A = np.einsum("na,nj->aj", np.column_stack([x, np.ones(len(x))]), v.reshape(len(x), -1)).reshape(4, 3, -1)
    m = [A[1, 2] - A[2, 1], A[2, 0] - A[0, 2], A[0, 1] - A[1, 0]]  # Σ x_j f_l, antisymmetrised
    return np.concatenate([A[3], np.stack(m)]).T
