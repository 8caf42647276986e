"""One part case through the FE solver: mesh → unit solutions → superposed peak → verdict.

A :class:`rigfem.loads.cases.PartCase` is meshed (cached), solved once per *unit* load with one
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

import collections
import dataclasses
import math
import time

import numpy as np

from rigfem.fe.assembly import start_compiling
from rigfem.fe.cache import cached_solve, ladder_inputs, peak_sweep, read_ladder, save_ladder
from rigfem.fe.forces import BearingLoad, Inertia, body_basis, body_coefficients
from rigfem.fe.model import Model, build_model
from rigfem.fe.solution import Solution
from rigfem.fe.supports import Fixed, FreeBody, ShaftInHole, Symmetry
from rigfem.loads.cases import PartCase, UnitLoad
from rigfem.memory import trim_heap
from rigfem.mesh import pool
from rigfem.mesh.cache import array_digest, cached_arrays, code_hash
from rigfem.mesh.mesher import MeshSettings, estimate_part, mesh_part, mesh_state, prefetch
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


def mesh_case(case: PartCase, settings: MeshSettings) -> PartMesh:
    """The (cached) mesh of a case's part (:func:`mesh_job`)."""
    return mesh_part(*mesh_job(case, settings))


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


def _basis_resultants(model: Model, c: np.ndarray) -> np.ndarray:
    """Force and moment about ``c`` (6, 12) of each of the model's body-force basis vectors
    (:func:`rigfem.fe.forces.body_basis`; a body load's resultant is this times its 12 weights),
    through a verified cache entry keyed by the mesh: a warm check assembles no body force.  A
    stored matrix is used only if a unit acceleration's force is the part's mass (ρ × volume)."""
    fm, rho = model.mesh, float(model.material.density)
    inputs = {"mesh": array_digest(fm.nodes, fm.elements), "density": rho,
              "code": code_hash("fe/assembly.py", "fe/forces.py", "fe/partcase.py")}
    mass = rho * model.volume * np.eye(3)
    got, _ = cached_arrays(
        "body_resultants", inputs, ("RB",), lambda: {"RB": _resultants(fm.nodes, body_basis(fm, rho)[0], c)},
        lambda a: "" if a["RB"].shape == (6, 12) and np.allclose(a["RB"][:3, :3], mass, rtol=1e-6, atol=0.0)
        else "a unit acceleration's force is not the part's mass")
    return got["RB"]


def relieved_cases(model: Model, loads: list) -> tuple[list, np.ndarray, np.ndarray]:
    """Each load plus the rigid-acceleration inertia field that cancels its resultant.

    Returns the FE load cases, the resultants (6, k) that were relieved (force, moment about
    the centroid) and each load's force magnitude scale (k,), to judge a combination
    (:func:`imbalance`).  A bearing load's resultant is exact by construction (its force
    through the hole centre), so only body forces are integrated here.
    """
    x = model.mesh.nodes
    c = x.mean(0)
    RB = _basis_resultants(model, c)
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


@dataclasses.dataclass
class CaseResult:
    """Outcome of one part case: the peak over all rows and what backs it."""

    case: PartCase
    mode: str
    solution: Solution  #: shared by every case of the same part geometry and supports
    coef: np.ndarray  #: (n_rows, solution load cases) weights of this case
    vm_rows: np.ndarray  #: (n_rows,) peak von Mises of every row
    row: int  #: the critical row
    peak: object  #: rigfem.fe.solution.Peak of the critical row
    cycle_nodes: np.ndarray | None  #: nodes that peak at some row (the fatigue candidates)
    cycle_stress: np.ndarray | None  #: (n_rows, len(cycle_nodes), 6) stress history there, MPa
    mesh: PartMesh
    imbalance: tuple[float, float]  #: largest relative (force, moment) imbalance of a row (free bodies)
    seconds: dict
    level: str = ""  #: the mesh level the part stopped at (rigfem.settings.LADDER), or "forced"
    stopped: str = ""  #: why it stopped there
    ladder: list = dataclasses.field(default_factory=list)  #: per level tried: name, sizes, DOF, seconds


def imbalance(model: Model, coef: np.ndarray, R: np.ndarray, scale: np.ndarray) -> tuple[float, float]:
    """Largest relative (force, moment) imbalance over the rows of a free body's combination.

    Row by row: the net force ``|Σ c_k F_k|`` over the applied load ``Σ |c_k| |F_k|``, and the
    net moment about the centroid over that load times the part's lever (its farthest node
    from the centroid).  A balanced free body gives ≈ 0 in both; a history that lost a load
    (a driver torque read as zero) leaves a moment the inertia relief would silently cancel.
    """
    load = np.abs(coef) @ scale
    safe = np.where(load > 0, load, 1.0)
    x = model.mesh.nodes
    lever = float(np.linalg.norm(x - x.mean(0), axis=1).max())
    net = coef @ R.T  # (rows, 6): force (N) and moment (N·mm) about the centroid
    force = np.linalg.norm(net[:, :3], axis=1) / safe
    moment = np.linalg.norm(net[:, 3:], axis=1) / (safe * lever)
    return float(force.max()), float(moment.max())


def best_shrink(coarse, fine, order: int) -> float:
    """How much a peak's error band narrows from mesh settings ``coarse`` to ``fine`` at the
    asymptotic rate of order-p elements' stress error, h^p, h the smaller of the global and the
    local size ratios.  A heuristic: a level at which a case would stay unsettled with its band
    narrowed so much, its peak unchanged, is skipped (:func:`solve_cases`).  A skip costs time
    (a finer level than needed), never the verdict: the part is still judged where it stops."""
    return min(fine.size_mm / coarse.size_mm, fine.near_mm / coarse.near_mm) ** order


def solve_cases(cases: list[tuple[str, PartCase]], settings, solver: str = "auto",
                progress=None, settled=None, on_stage=None, on_final=None) -> list[CaseResult]:
    """Solve every (mode, case); cases of one part geometry share mesh and stiffness, cases
    with the same supports share one factorisation, identical unit loads are solved once.

    With ``settled`` (``settled(result, shrink=1.0) -> bool``, the verdict layer's judge, with
    the band narrowed by ``shrink``) every part geometry climbs ``settings.levels()`` (coarse
    first) and stops at the first level where all its cases are settled, or at the last level
    (the cap).  A level at which a case would stay unsettled with the band narrowed by
    :func:`best_shrink` is skipped.  Parts are queued smallest first (the estimated mesh) and
    solved as their meshes are made: the first part in the queue whose mesh is ready; a part that
    climbs goes to the back of the queue, its finer mesh (and the cap's, in case it climbs on)
    made in a mesher process while the other parts solve.  Without ``settled`` every part is
    solved at ``settings`` only.  Where the ladder stopped is stored
    (:func:`rigfem.fe.cache.save_ladder`, keyed by the cases, the levels and the code): a later
    check of the same cases starts at that level.  ``on_stage(text)`` hears 'meshing part X' and
    'solving part X' (with the level) as each begins.  With ``on_final`` (``on_final(result)`` ->
    the rows of the case the caller still needs, None for all), called for each case as its part
    is final, the part's solution is then reduced to those rows' combinations (:func:`_keep_only`):
    the unit solutions of the parts already solved are not held while the next ones are.
    """
    geo = part_geometries(cases)
    levels = settings.levels() if settled is not None else [(getattr(settings, "fidelity", ""), settings)]
    last = len(levels) - 1
    # where each geometry's ladder stopped before (a warm check starts there: the levels it
    # discarded are not loaded again)
    keys = {g: ladder_inputs(group, levels, solver) if last else None for g, group in geo.items()}
    climbed = {g: read_ladder(k) if k else None for g, k in keys.items()}
    names = [n for n, _ in levels]
    start = {g: names.index(c[-1]["level"]) if c else 0 for g, c in climbed.items()}
    level = dict(start)
    ladders = {g: c[:-1] if c else [] for g, c in climbed.items()}
    # every part's first level meshed ahead, 2 at a time, the smallest first: the FE starts on
    # the part meshed soonest and works while the larger ones are meshed
    def job(g: tuple) -> tuple:  # the part and mesh settings of g's current level
        return group_job(geo[g], levels[level[g]][1])

    order = sorted(geo, key=lambda g: getattr(estimate_part(*job(g)), "tets", math.inf))
    prefetch([job(g) for g in order])
    start_compiling()  # a first run after an install: numba compiles while the meshes are made
    queue, results = collections.deque(order), {}
    while queue:
        g = _next_ready(queue, job)
        queue.remove(g)
        group, k = geo[g], level[g]
        name, s = levels[k]
        t0 = time.perf_counter()
        out = _solve_group(group, s, solver, on_stage, name)
        ladders[g].append({"level": name, "size_mm": s.size_mm, "local_size_mm": s.near_mm,
                           "dofs": int(out[0].solution.model.mesh.ndof),
                           "seconds": round(time.perf_counter() - t0, 3)})
        done = settled is not None and all(settled(r) for r in out)
        if not done and k < last:
            while k + 1 < last and not all(settled(r, best_shrink(s, levels[k + 1][1], s.order)) for r in out):
                k += 1  # unsettled there even at the asymptotic rate: skipped
                ladders[g][-1].setdefault("skipped", []).append(names[k])
            level[g] = k + 1
            # the cap's mesh too, after the next level's: a part that climbs once often climbs on,
            # and then its FE would wait for the mesh (made while the other parts solve)
            prefetch([job(g)] + ([group_job(geo[g], levels[last][1])] if level[g] < last else []), keep=True)
            queue.append(g)
            out = None  # free this level's model, matrix and factor before the next part's
            trim_heap()
            continue
        if keys[g] and level[g] != start[g]:
            save_ladder(keys[g], ladders[g])
        stopped = ("fixed mesh (no ladder)" if not last else
                   "decided within the reporting target" if done else "reached the cap")
        for res in out:
            res.level, res.stopped, res.ladder = name, stopped, ladders[g]
        if on_final is not None:
            _keep_only(out, on_final)
        trim_heap()  # what the part's solve and the reduction freed goes back to the system
        for (mode, case), res in zip(group, out):
            results[id(case)] = res
            if progress:
                progress(case.name, mode)
    return [results[id(case)] for _, case in cases]


def _keep_only(results: list[CaseResult], rows_of) -> None:
    """Reduce each solution of ``results`` to the combinations of the rows ``rows_of(result)`` of
    the cases that share it (:meth:`~rigfem.fe.solution.Solution.kept`); in place.  A case whose
    ``rows_of`` is None keeps its solution whole."""
    rows: dict[int, tuple] = {}
    for r in results:
        want = rows_of(r)
        rows.setdefault(id(r.solution), (r.solution, []))[1].append(None if want is None else
                                                                    r.coef[np.atleast_1d(want)])
    small = {k: sol if any(c is None for c in C) else sol.kept(np.vstack(C)) for k, (sol, C) in rows.items()}
    for r in results:
        r.solution = small[id(r.solution)]


#: how often a part waiting for its mesh looks at the mesher processes, s
POLL_S = 0.05


def _next_ready(queue: collections.deque, job) -> tuple:
    """The first part in ``queue`` whose mesh (``job(g)``: part, settings) is ready, waiting while
    the mesher processes make them (the estimates only guess which comes first); the first part
    when none is being made.  An interruption while waiting cancels the mesh jobs."""
    jobs = {g: job(g) for g in queue}
    try:
        while True:
            states = {g: mesh_state(*jobs[g]) for g in queue}
            ready = [g for g in queue if states[g] == "ready"]
            if ready or "making" not in states.values():
                return (ready or list(queue))[0]
            time.sleep(POLL_S)
    except BaseException:
        pool.cancel()
        raise


def _solve_group(group: list[tuple[str, PartCase]], settings, solver: str, on_stage=None,
                 level: str = "") -> list[CaseResult]:
    """The cases of one part geometry at ``settings``, in the order of ``group``."""
    t0 = time.perf_counter()
    first = _merged(group)
    at = f" ({level})" if level else ""
    if on_stage:
        on_stage(f"meshing part {first.name}{at}")
    pm = mesh_case(first, settings)
    model = build_model(pm, settings.material, settings.order)
    t_model = time.perf_counter() - t0
    if on_stage:
        on_stage(f"solving part {first.name}{at}")
    by_support: dict[tuple, list[tuple[str, PartCase]]] = {}
    for mode, case in group:
        by_support.setdefault(tuple(case.supports), []).append((mode, case))
    results = {}
    for sup_cases in by_support.values():
        for (mode, case), res in zip(sup_cases, _solve_shared(model, pm, sup_cases, settings, solver)):
            res.seconds["mesh+assembly (shared)"] = t_model
            results[id(case)] = res
    model.release()  # its stiffness and quadrature caches: the results keep mesh and arrays only
    return [results[id(case)] for _, case in group]


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
    sol = cached_solve(model, supports, loads, solver=solver)
    t_solve = time.perf_counter() - t0
    fe_mass = model.volume * model.material.density * 1e3  # kg (density in t/mm³)
    out = []
    for mode, case in sup_cases:
        t1 = time.perf_counter()
        coef = np.zeros((len(case.rows), len(unique)))
        for j, u in enumerate(case.loads):
            ratio = case.mass_kg / fe_mass if (u.kind == "inertia" and case.mass_kg) else 1.0
            coef[:, unique[u]] += ratio * case.coef[:, j]
        unbalanced = imbalance(model, coef, R, scale) if free else (0.0, 0.0)
        vm_rows, peak_nodes = peak_sweep(sol, coef)
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
