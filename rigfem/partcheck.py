"""One part case through the FE solver: mesh → unit solutions → superposed peak → verdict.

A :class:`rigfem.loadcases.PartCase` is meshed (cached), solved once per *unit* load with one
factorisation, and the stress of every row (crank angle) is the superposition
``σ(θ) = Σ_k c_k(θ) σ_k``, evaluated in chunks so a 360-angle cycle costs a few matrix
products, not 360 solves.

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

from rigfem.fe import LOCKING_NU, Model, build_model, load_matrix, solve
from rigfem.loadcases import PartCase, UnitLoad
from rigfem.loads import BearingLoad, Inertia
from rigfem.mesh import MeshSettings, PartMesh, mesh_part
from rigfem.parts import load_part
from rigfem.solution import Solution
from rigfem.supports import Fixed, FreeBody, ShaftInHole, Symmetry
from rigfem.verdict import goodman, half_ultimate

#: surface groups that raise stress without carrying load (the I-profile's root fillets, whose
#: peak needs about half the interface size: results/convergence/README.md)
CONCENTRATORS = ("fillets",)
#: rows superposed at once (memory: rows × nodes × 6 doubles)
CHUNK = 24


def mesh_case(case: PartCase, size_mm: float, local_size_mm: float) -> PartMesh:
    """The (cached) mesh of a case's part, refined at the interfaces that carry its load and,
    twice as finely, at the refined groups that concentrate stress (:data:`CONCENTRATORS`)."""
    part = load_part(case.part, case.params or None)
    conc = tuple(g for g in case.refine if g in CONCENTRATORS)
    return mesh_part(part, MeshSettings(size=size_mm, refine=tuple(g for g in case.refine if g not in conc),
                                        refine_size=local_size_mm, concentrate=conc))


def supports_of(case: PartCase) -> list:
    """rigfem.supports objects of a case: screws as shafts in holes, fixed faces, faces that
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
    """The rigfem.loads object of a unit load (bearing on a hole, or a unit inertia field)."""
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


def relieved_cases(model: Model, loads: list) -> tuple[list, np.ndarray, np.ndarray]:
    """Each load plus the rigid-acceleration inertia field that cancels its resultant.

    Returns the FE load cases, the resultants (6, k) that were relieved (force, moment about
    the centroid) and each load's force magnitude scale (k,), to judge a combination.  A
    bearing load's resultant is exact by construction (its force through the hole centre), so
    only body forces are integrated here.
    """
    x = model.mesh.nodes
    c = x.mean(0)
    R = np.zeros((6, len(loads)))
    body = [k for k, ld in enumerate(loads) if isinstance(ld, Inertia)]
    if body:
        R[:, body] = _resultants(x, load_matrix(model, [loads[k] for k in body]), c)
    for k, ld in enumerate(loads):
        if isinstance(ld, BearingLoad):
            f = np.asarray(ld.force, float)
            R[:3, k] = f
            R[3:, k] = np.cross(np.asarray(model.part.holes[ld.hole].center, float) - c, f)
    unit = [Inertia(a0=tuple(e), origin=tuple(c)) for e in np.eye(3)]
    unit += [Inertia(alpha=tuple(e), origin=tuple(c)) for e in np.eye(3)]
    G = _resultants(x, load_matrix(model, unit), c)  # (6, 6): resultant per unit rigid acceleration
    acc = -np.linalg.solve(G, R)  # (6, k)
    cases = [[ld, Inertia(a0=tuple(a[:3]), alpha=tuple(a[3:]), origin=tuple(c))]
             for ld, a in zip(loads, acc.T)]
    return cases, R, np.linalg.norm(R[:3], axis=0)


@dataclasses.dataclass
class CaseResult:
    """Outcome of one part case: the peak over all rows and what backs it."""

    case: PartCase
    mode: str
    solution: Solution  #: shared by every case of the same part geometry and supports
    coef: np.ndarray  #: (n_rows, solution load cases) weights of this case
    vm_rows: np.ndarray  #: (n_rows,) peak von Mises of every row
    row: int  #: the critical row
    peak: object  #: rigfem.solution.Peak of the critical row
    fatigue: dict | None
    mesh: PartMesh
    imbalance: float  #: largest relieved load imbalance of a row (free bodies), relative
    seconds: dict


def _key(case: PartCase) -> tuple:
    return case.part, tuple(sorted(case.params.items()))


def solve_cases(cases: list[tuple[str, PartCase]], settings, solver: str = "auto",
                progress=None) -> list[CaseResult]:
    """Solve every (mode, case); cases of one part geometry share mesh and stiffness, cases
    with the same supports share one factorisation, identical unit loads are solved once."""
    geo: dict[tuple, list[tuple[str, PartCase]]] = {}
    for mode, case in cases:
        geo.setdefault(_key(case), []).append((mode, case))
    results = {}
    for group in geo.values():
        t0 = time.perf_counter()
        refine = tuple(sorted({g for _, c in group for g in c.refine}))
        first = group[0][1]
        pm = mesh_case(dataclasses.replace(first, refine=refine), settings.size_mm, settings.local_size_mm)
        model = build_model(pm, settings.material, settings.order)
        t_model = time.perf_counter() - t0
        by_support: dict[tuple, list[tuple[str, PartCase]]] = {}
        for mode, case in group:
            by_support.setdefault(tuple(case.supports), []).append((mode, case))
        for sup_cases in by_support.values():
            for (mode, case), res in zip(sup_cases, _solve_shared(model, pm, sup_cases, settings, solver)):
                res.seconds["mesh+assembly (shared)"] = t_model
                results[id(case)] = res
                if progress:
                    progress(case.name, mode)
    return [results[id(case)] for _, case in cases]


def _solve_shared(model: Model, pm: PartMesh, sup_cases: list[tuple[str, PartCase]], settings,
                  solver: str) -> list[CaseResult]:
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
        loads, R, scale = relieved_cases(model, loads)
    sol = solve(model, supports, loads, solver=solver)
    t_solve = time.perf_counter() - t0
    fe_mass = model.volume * model.material.density * 1e3  # kg (density in t/mm³)
    out = []
    for mode, case in sup_cases:
        t1 = time.perf_counter()
        coef = np.zeros((len(case.rows), len(unique)))
        for j, u in enumerate(case.loads):
            ratio = case.mass_kg / fe_mass if (u.kind == "inertia" and case.mass_kg) else 1.0
            coef[:, unique[u]] += ratio * case.coef[:, j]
        imbalance = 0.0
        if free:
            load = np.abs(coef) @ scale
            imbalance = float((np.linalg.norm(coef @ R[:3].T, axis=1) / np.where(load > 0, load, 1)).max())
        vm_rows, peak_nodes = sol.peak_sweep(coef, chunk=CHUNK)
        row = int(np.argmax(vm_rows))
        fat = None
        if len(case.rows) > 1:  # fatigue: the stress cycle at every node that peaks at some angle
            nodes = np.unique(peak_nodes)
            hist = np.einsum("rk,knc->rnc", coef, sol.nodal_stress[:, nodes])
            fat = goodman(hist, model.material.sigma_u, **settings.fatigue)
            fat["node"] = int(nodes[fat.pop("point")])
            fat["location_mm"] = [float(v) for v in model.mesh.nodes[fat["node"]]]
        out.append(CaseResult(case, mode, sol, coef, vm_rows, row, sol.peak(coef[row]), fat, pm,
                              imbalance, {"solve (shared)": t_solve,
                                          "superpose": time.perf_counter() - t1}))
    return out


def _profile_caveat(res: CaseResult) -> list[str]:
    """A rail whose section is heavier than the catalogue's is stiffer and stronger than the real one."""
    part = load_part(res.case.part, res.case.params or None)
    ref = part.reference.get("linear_mass_catalogue")
    if part.kind != "rail" or ref is None:
        return []
    kg_m = res.solution.model.volume * part.density * 1e-9 / (part["length"] / 1000.0)
    if kg_m <= 1.05 * ref.value:
        return []
    return [f"rail section {kg_m:.2f} kg/m against the catalogue's {ref.value:g} kg/m: the modelled profile "
            f"is stiffer and stronger than the real one, so this stress is likely low (a 3.1 kg/m profile "
            f"carried 1.8-2.1x the rectangle's peak: results/rail_profile/study.md)"]


def verdict_of(res: CaseResult, settings) -> dict:
    """Report entry of a case result (plain data, MPa, mm, deg)."""
    mat = settings.material
    pk = res.peak
    v = half_ultimate(pk.value, mat.sigma_u, 100.0 * pk.error, settings.limit_factor)
    sol = res.solution
    c = res.coef[res.row]
    eq = float(np.max(sol.equilibrium_error))
    out = {
        "name": res.case.name, "part": res.case.part, "mode": res.mode,
        "peak_mpa": v.peak_mpa, "crank_deg": float(res.case.rows[res.row]),
        "surface": pk.surface, "location_mm": [round(float(t), 3) for t in pk.xyz],
        "error_pct": v.error_pct, "limit_mpa": v.limit_mpa, "utilisation_pct": v.utilisation_pct,
        "verdict": v.verdict,
        "max_displacement_mm": float(np.linalg.norm(sol.displacement(c), axis=1).max()),
        "fatigue": res.fatigue,
        "mesh": {"nodes": int(len(res.mesh.points)), "tets": int(len(res.mesh.tets)),
                 "dofs": int(sol.model.mesh.ndof), "order": settings.order,
                 "quality_min": float(res.mesh.quality.get("min", 0.0)),
                 "curved_elements": int(sol.model.mesh.curved.sum()) if sol.model.mesh.curved is not None else 0,
                 "straightened": int(sol.model.mesh.straightened),
                 "cache": res.mesh.meta.get("cache", "")},
        "solve": {"method": sol.method, "load_cases": int(sol.U.shape[1]),
                  "rows": int(len(res.case.rows)),
                  "residual_max": float(sol.residuals.max()), "equilibrium_error": eq,
                  "relieved_imbalance": res.imbalance,
                  "seconds": {k: round(t, 3) for k, t in res.seconds.items()}},
        "notes": list(res.case.notes),
    }
    out["notes"] += _profile_caveat(res)
    if settings.order == 1 and mat.nu >= LOCKING_NU:
        out["notes"].append(f"linear elements with nu = {mat.nu:g}: volumetric locking under-predicts stress; "
                            f"use order 2")
    if res.imbalance > 1e-3:
        out["notes"].append(f"free-body loads were out of balance by up to {100 * res.imbalance:.1f} % "
                            f"(FE vs dynamics mass distribution); removed by inertia relief")
    return out
