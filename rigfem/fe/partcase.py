"""One part geometry's cases through the FE solver at one mesh: mesh → unit solutions → superposed peaks.

A :class:`rigfem.loads.cases.PartCase` is meshed (cached), solved once per *unit* load with one
factorisation, and the stress of every row (crank angle) is the superposition
``σ(θ) = Σ_k c_k(θ) σ_k``, evaluated in chunks so a 360-angle cycle costs a few matrix
products, not 360 solves.  :func:`solve_group` is that, for the cases of one part geometry at one
mesh level, and nothing else: which levels to climb is :mod:`rigfem.fe.ladder`'s, when and in
which order parts are meshed and solved :mod:`rigfem.fe.executor`'s.

Free bodies (cycle mode) get *inertia relief*: the FE part's mass distribution is not exactly
the dynamics model's (the rail mesh starts behind the pivot, holes remove mass), so each unit
load is made self-equilibrated by the rigid-body acceleration field of the part itself that
cancels its resultant.  The relieved fraction is reported; the 3-2-1 support then carries
≈ 0 and adds no spurious point-support stress.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from rigfem.fe.cache import cached_solve, peak_sweep
from rigfem.fe.forces import BearingLoad, Inertia, body_basis, body_coefficients
from rigfem.fe.model import Model, build_model
from rigfem.fe.solution import Peak, Solution
from rigfem.tensors import von_mises
from rigfem.fe.supports import Fixed, FreeBody, ShaftInHole, Symmetry
from rigfem.loads.cases import PartCase, UnitLoad
from rigfem.cache import Cache, resolve, save_arrays
from rigfem.mesh.mesher import MeshSettings, mesh_part
from rigfem.verdict.part import Outcome
from rigfem.mesh.partmesh import PartMesh
from rigfem.rig.parts import load_part

#: surface groups that raise stress without carrying load (the I-profile's root fillets, whose
#: peak needs about half the interface size: results/convergence/README.md)
CONCENTRATORS = ("fillets",)


def mesh_job(case: PartCase, settings: MeshSettings) -> tuple:
    """The part and mesh settings of a case: ``settings`` (a preset or a check's settings) refined
    at the interfaces that carry its load and, twice as finely, at the refined groups that
    concentrate stress (:data:`CONCENTRATORS`)."""
    part = load_part(case.part, case.params or None)
    conc = tuple(g for g in case.refine if g in CONCENTRATORS)
    return part, settings.refined(tuple(g for g in case.refine if g not in conc), conc)


def mesh_case(case: PartCase, settings: MeshSettings, cache: Cache | None = None) -> PartMesh:
    """The (cached) mesh of a case's part (:func:`mesh_job`)."""
    return mesh_part(*mesh_job(case, settings), cache=cache)


def part_geometries(cases: list[tuple[str, PartCase]]) -> dict[tuple, list[tuple[str, PartCase]]]:
    """The (mode, case) pairs of each part geometry (part and parameters), in order: they share one
    mesh and one stiffness (:func:`solve_cases`)."""
    geo: dict[tuple, list[tuple[str, PartCase]]] = {}
    for mode, case in cases:
        geo.setdefault((case.part, tuple(sorted(case.params.items()))), []).append((mode, case))
    return geo


def _merged(group: list[tuple[str, PartCase]]) -> PartCase:
    """The first case of a part geometry's group, refined where any case of the group is."""
    refine = tuple(sorted({g for _, c in group for g in c.refine}))
    return dataclasses.replace(group[0][1], refine=refine)


def group_job(group: list[tuple[str, PartCase]], settings: MeshSettings) -> tuple:
    """The part and mesh settings of a part geometry's cases (:func:`part_geometries`): its mesh
    is refined where any of them is loaded (:func:`mesh_job`)."""
    return mesh_job(_merged(group), settings)


def supports_of(case: PartCase) -> list:
    """rigfem.fe.supports objects of a case: screws as shafts in holes, fixed faces, faces that
    may slide on their support (zero normal displacement), or a free body."""
    out = []
    for kind, groups in case.supports:
        if kind == "bolt":
            out += [ShaftInHole(g) for g in groups]
        elif kind == "fixed":
            out += [Fixed(g) for g in groups]
        elif kind == "slide":
            out += [Symmetry(g) for g in groups]
        elif kind == "free":
            out.append(FreeBody())
        else:
            raise ValueError(f"unknown support kind {kind!r}")
    return out


def fe_load(u: UnitLoad):
    """The rigfem.fe.forces object of a unit load (bearing on a hole, or a unit inertia field)."""
    if u.kind == "bearing":
        return BearingLoad(u.group, u.direction)
    o = u.direction
    return {"a0x": Inertia(a0=(1.0, 0.0, 0.0), origin=o), "a0y": Inertia(a0=(0.0, 1.0, 0.0), origin=o),
            "alpha": Inertia(alpha=(0.0, 0.0, 1.0), origin=o),
            "omega2": Inertia(omega=(0.0, 0.0, 1.0), origin=o)}[u.component]


def _resultants(x: np.ndarray, F: np.ndarray, about: np.ndarray) -> np.ndarray:
    """Force and moment about ``about`` (6, k) of nodal load columns F (3N, k)."""
    f = F.reshape(len(x), 3, -1)
    moment = np.cross((x - about)[:, None, :], f.transpose(0, 2, 1)).sum(0).T
    return np.concatenate([f.sum(0), moment], axis=0)


def _basis_resultants(model: Model, c: np.ndarray, cache: Cache) -> np.ndarray:
    """Force and moment about ``c`` (6, 12) of each of the model's body-force basis vectors
    (:func:`rigfem.fe.forces.body_basis`; a body load's resultant is this times its 12 weights),
    through a verified cache entry keyed by the mesh: a warm check assembles no body force.  A
    stored matrix is used only if a unit acceleration's force is the part's mass (ρ × volume)."""
    fm, rho = model.mesh, float(model.material.density)
    mass = rho * model.volume * np.eye(3)
    got, _ = cache.cached(
        "body_resultants", {"mesh": [fm.nodes, fm.elements], "density": rho},
        lambda: _resultants(fm.nodes, body_basis(fm, rho)[0], c),
        lambda RB, tmp: save_arrays(tmp, {"RB": RB}), lambda entry: entry.array("RB"),
        lambda RB: "" if RB.shape == (6, 12) and np.allclose(RB[:3, :3], mass, rtol=1e-6, atol=0.0)
        else "a unit acceleration's force is not the part's mass")
    return got


def relieved_cases(model: Model, loads: list, cache: Cache | None = None) -> tuple[list, np.ndarray, np.ndarray]:
    """Each load plus the rigid-acceleration inertia field that cancels its resultant.

    Returns the FE load cases, the resultants (6, k) that were relieved (force, moment about
    the centroid) and each load's force magnitude scale (k,), to judge a combination
    (:func:`imbalance`).  A bearing load's resultant is exact by construction (its force
    through the hole centre), so only body forces are integrated here.
    """
    x = model.mesh.nodes
    c = x.mean(0)
    RB = _basis_resultants(model, c, resolve(cache))
    R = np.zeros((6, len(loads)))
    body = [k for k, ld in enumerate(loads) if isinstance(ld, Inertia)]
    if body:
        R[:, body] = RB @ np.stack([body_coefficients(loads[k], c) for k in body], axis=1)
    for k, ld in enumerate(loads):
        if isinstance(ld, BearingLoad):
            f = np.asarray(ld.force, float)
            R[:3, k] = f
            R[3:, k] = np.cross(np.asarray(model.part.holes[ld.hole].center, float) - c, f)
    unit = [Inertia(a0=tuple(e), origin=tuple(c)) for e in np.eye(3)]
    unit += [Inertia(alpha=tuple(e), origin=tuple(c)) for e in np.eye(3)]
    G = RB @ np.stack([body_coefficients(u, c) for u in unit], axis=1)  # (6, 6): per unit rigid acceleration
    acc = -np.linalg.solve(G, R)  # (6, k)
    cases = [[ld, Inertia(a0=tuple(a[:3]), alpha=tuple(a[3:]), origin=tuple(c))]
             for ld, a in zip(loads, acc.T)]
    return cases, R, np.linalg.norm(R[:3], axis=0)


@dataclasses.dataclass(frozen=True)
class CaseResult:
    """Outcome of one part case: the peak over all rows and what backs it."""

    case: PartCase
    mode: str
    solution: Solution  #: shared by every case of the same part geometry and supports
    coef: np.ndarray  #: (n_rows, solution load cases) weights of this case
    vm_rows: np.ndarray  #: (n_rows,) peak von Mises of every row
    row: int  #: the critical row
    peak: Peak  #: the critical row's peak, its place and its error band
    cycle_nodes: np.ndarray | None  #: nodes that peak at some row (the fatigue candidates)
    cycle_stress: np.ndarray | None  #: (n_rows, len(cycle_nodes), 6) stress history there, MPa
    mesh: PartMesh
    imbalance: tuple[float, float]  #: largest relative (force, moment) imbalance of a row (free bodies)
    seconds: dict
    level: str = ""  #: the mesh level the part stopped at (rigfem.settings.LADDER), or "forced"
    stopped: str = ""  #: why it stopped there
    ladder: tuple = ()  #: per level tried: name, sizes, DOF, seconds
    #: animation frames once final (:func:`finish`): case row -> vertex fields (float32)
    frames: dict = dataclasses.field(default_factory=dict)
    #: the same rows' pin loads (:func:`finish`): case row -> (hole, its centre mm, force N) per loaded hole
    frame_loads: dict = dataclasses.field(default_factory=dict)

    @property
    def loaded(self) -> bool:
        """Whether any load of the case is non-zero (a part nothing loads is never a pass)."""
        return bool(np.any(self.coef != 0))

    @property
    def crank_deg(self) -> float:
        """The critical row's crank angle (deg)."""
        return float(self.case.rows[self.row])

    @property
    def outcome(self) -> Outcome:
        """What the verdict stage judges of this case."""
        return Outcome(self.case.name, self.case.part, self.mode, self.peak.value, self.peak.error_pct,
                       self.crank_deg, self.imbalance, self.loaded, self.cycle_stress)


def lever_mm(model: Model) -> float:
    """The part's lever: its farthest node from the centroid, mm (the scale of an imbalance's moment)."""
    x = model.mesh.nodes
    return float(np.linalg.norm(x - x.mean(0), axis=1).max())


def imbalance(coef: np.ndarray, R: np.ndarray, scale: np.ndarray, lever: float) -> tuple[float, float]:
    """Largest relative (force, moment) imbalance over the rows of a free body's combination.

    Row by row: the net force ``|Σ c_k F_k|`` over the applied load ``Σ |c_k| |F_k|``, and the
    net moment about the centroid over that load times the part's ``lever``
    (:func:`lever_mm`); ``R`` (6, k) and ``scale`` (k,) are the unit loads' resultants and force
    magnitudes (:func:`relieved_cases`).  A balanced free body gives ≈ 0 in both; a history that
    lost a load (a driver torque read as zero) leaves a moment the inertia relief would silently
    cancel.
    """
    load = np.abs(coef) @ scale
    safe = np.where(load > 0, load, 1.0)
    net = coef @ R.T  # (rows, 6): force (N) and moment (N·mm) about the centroid
    force = np.linalg.norm(net[:, :3], axis=1) / safe
    moment = np.linalg.norm(net[:, 3:], axis=1) / (safe * lever)
    return float(force.max()), float(moment.max())


def solve_group(group: list[tuple[str, PartCase]], settings, solver: str = "auto",
                cache: Cache | None = None) -> list[CaseResult]:
    """The cases of one part geometry (:func:`part_geometries`) at the mesh ``settings``, in the
    order of ``group``: one mesh and one stiffness; cases with the same supports share one
    factorisation, identical unit loads are solved once."""
    t0 = time.perf_counter()
    cache = resolve(cache)
    pm = mesh_case(_merged(group), settings, cache)
    model = build_model(pm, settings.material, settings.order, cache)
    t_model = time.perf_counter() - t0
    by_support: dict[tuple, list[tuple[str, PartCase]]] = {}
    for mode, case in group:
        by_support.setdefault(tuple(case.supports), []).append((mode, case))
    results = {}
    for sup_cases in by_support.values():
        for (mode, case), res in zip(sup_cases, _solve_shared(model, pm, sup_cases, solver, cache)):
            res.seconds["mesh+assembly (shared)"] = t_model
            results[id(case)] = res
    model.release()  # its stiffness and quadrature caches: the results keep mesh and arrays only
    return [results[id(case)] for _, case in group]


def _solve_shared(model: Model, pm: PartMesh, sup_cases: list[tuple[str, PartCase]], solver: str,
                  cache: Cache) -> list[CaseResult]:
    t0 = time.perf_counter()
    unique: dict[UnitLoad, int] = {}
    for _, case in sup_cases:
        for u in case.loads:
            unique.setdefault(u, len(unique))
    loads = [fe_load(u) for u in unique]
    supports = supports_of(sup_cases[0][1])
    free = any(isinstance(s, FreeBody) for s in supports)
    R = scale = None
    if free:
        loads, R, scale = relieved_cases(model, loads, cache)
    sol = cached_solve(model, supports, loads, solver=solver, cache=cache)
    t_solve = time.perf_counter() - t0
    fe_mass = model.volume * model.material.density * 1e3  # kg (density in t/mm³)
    out = []
    for mode, case in sup_cases:
        t1 = time.perf_counter()
        coef = np.zeros((len(case.rows), len(unique)))
        for j, u in enumerate(case.loads):
            ratio = case.mass_kg / fe_mass if (u.kind == "inertia" and case.mass_kg) else 1.0
            coef[:, unique[u]] += ratio * case.coef[:, j]
        unbalanced = imbalance(coef, R, scale, lever_mm(model)) if free else (0.0, 0.0)
        vm_rows, peak_nodes = peak_sweep(sol, coef, cache)
        row = int(np.argmax(vm_rows))
        nodes = hist = None
        # the stress cycle at every node that peaks at some angle (an original-mode case's rows are
        # alternative equal peaks, not a cycle)
        if mode == "cycle" and len(case.rows) > 1:
            nodes = np.unique(peak_nodes)
            hist = np.einsum("rk,knc->rnc", coef, sol.nodal_stress[:, nodes])
        out.append(CaseResult(case, mode, sol, coef, vm_rows, row, sol.peak(coef[row]), nodes, hist, pm,
                              unbalanced, {"solve (shared)": t_solve,
                                          "superpose": time.perf_counter() - t1}))
    return out


def hole_forces(result: CaseResult, c: np.ndarray) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(hole, its nodes, the applied force on them N) of each hole a pin or screw loads in the
    combination ``c`` of the case's solution (none where the force is zero)."""
    F, fm = result.solution.loads(c).reshape(-1, 3), result.solution.model.mesh
    out = []
    for g in dict.fromkeys(ld.group for ld in result.case.loads if ld.kind == "bearing" and ld.group):
        nodes = np.unique(fm.surfaces[g]) if g in fm.surfaces else np.zeros(0, int)
        f = F[nodes].sum(0)
        if len(nodes) and np.linalg.norm(f) > 0:
            out.append((g, nodes, f))
    return out


def frame_rows(result: CaseResult, frames: int) -> list[int]:
    """The rows of a cycle case's animation: ``frames`` crank angles, evenly spaced, and its critical
    row (the governing crank angle, which even steps miss: crank_rail's 30.5 % at 8° read 22.9 % at
    0°); none but in cycle mode or with no frames asked for."""
    if result.mode != "cycle" or not frames:
        return []
    even = np.linspace(0, len(result.case.rows), frames, endpoint=False).astype(int)
    return [int(i) for i in np.unique(np.append(even, result.row))]


def finish(results: list[CaseResult], frames: int) -> list[CaseResult]:
    """The cases of a part that is final, holding only what a report reads: each case's animation
    frames (``frames`` rows of a cycle case: von Mises, stress and displacement on the mesh's
    vertices, float32, and the pin load on each loaded hole) and its solution reduced to the critical rows' combinations
    (:meth:`~rigfem.fe.solution.Solution.kept`; cases sharing a solution share the reduced one):
    the unit solutions of a finished part are not held while the next parts solve."""
    out, kept = [], {}
    for r in results:
        x = r.solution.model.mesh.nodes
        n = r.solution.model.mesh.n_vertices
        fields, loads = {}, {}
        for i in frame_rows(r, frames):
            s = r.solution.stress(r.coef[i])[:n]
            fields[i] = {"displacement": r.solution.displacement(r.coef[i])[:n].astype(np.float32),
                         "stress": s.astype(np.float32), "von_mises": von_mises(s).astype(np.float32)}
            loads[i] = [(g, x[nodes].mean(0), f) for g, nodes, f in hole_forces(r, r.coef[i])]
        out.append(dataclasses.replace(r, frames=fields, frame_loads=loads))
        kept.setdefault(id(r.solution), (r.solution, []))[1].append(r.coef[r.row])
    small = {k: sol.kept(np.vstack(C)) for k, (sol, C) in kept.items()}
    return [dataclasses.replace(r, solution=small[id(r.solution)]) for r in out]
