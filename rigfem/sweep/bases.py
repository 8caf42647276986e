"""The rig sweep's FE unit bases: per rail geometry and support set, one factorisation gives
the unit stress fields of every load a configuration can apply, and a configuration's peak
von Mises follows by superposition, evaluated only at the nodes whose bound can reach it
(:mod:`rigfem.sweep.run`).

Units: mm, N, MPa, deg.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rigfem.dynamics.cycle import simulate
from rigfem.dynamics.history import peaks
from rigfem.errors import ComputeError, InputError
from rigfem.linkage.mechanisms import four_bar, slider_crank
from rigfem.loads.cases import PartCase, UnitLoad, directions, part_cases
from rigfem.rig.parts import rail_hole_name
from rigfem.settings import CheckSettings
from rigfem.sweep.configs import (
    BOUND_GROUPS,
    ORIGINAL_DIRECTIONS,
    ROW_CHUNK,
    SweepParams,
    TOP_NODES,
    rig_rail_layout,
    enumerate_configs,
)


# ----------------------------------------------------------------------------- FE unit bases
@dataclass
class UnitBasis:
    """Unit stress fields of one part geometry and support set (float32, every node)."""

    key: tuple
    loads: list[UnitLoad]
    groups: dict[str, tuple[np.ndarray, np.ndarray]]  #: group -> (angles rad sorted, columns)
    inertia: dict[tuple, int]  #: (component, origin) -> column
    S: np.ndarray  #: (k, N, 6) float32 nodal stress of every unit load
    vm: np.ndarray  #: (k, N) float32 von Mises of every unit field (the bound of ``case_peak``)
    top: np.ndarray  #: (k, TOP_NODES) the nodes where each unit field is highest
    fe_mass: float  #: kg, mass of the meshed part


class _Mapped(np.memmap):
    """A read-only memory-mapped array that pickles as its file name: the workers of a local
    cluster (or the process a child built a basis for) map the same file, one copy in the page
    cache, instead of each receiving a copy."""

    def __reduce__(self):
        return _open_mapped, (self.filename,)


def _open_mapped(path: str) -> np.ndarray:
    return np.load(path, mmap_mode="r").view(_Mapped)


def _basis_file(folder: Path, key: tuple, field: str) -> Path:
    return folder / f"basis_{hashlib.sha256(repr(key).encode()).hexdigest()[:16]}_{field}.npy"


def mapped(b: UnitBasis, folder: Path) -> UnitBasis:
    """``b`` with its stress fields stored in ``folder`` and memory-mapped from there (those not
    mapped yet): a process holds only the pages it reads (a configuration's peak reads its few
    candidate nodes)."""
    arrays = {}
    for field in ("S", "vm"):
        a = getattr(b, field)
        if not isinstance(a, _Mapped):
            f = _basis_file(folder, b.key, field)
            np.save(f, a)
            a = _open_mapped(str(f))
        arrays[field] = a
    return dataclasses.replace(b, **arrays)


def case_key(case: PartCase) -> tuple:
    return case.part, tuple(sorted(case.params.items())), tuple(case.supports)


def _reference_cases(p: SweepParams, s: CheckSettings) -> list[tuple[str, PartCase]]:
    """The cases of the first configuration that runs (its parts, supports and load groups)."""
    from rigfem.linkage.model import AssemblyError, ClosureError

    q = dataclasses.replace(p, samples=36)
    for cfg in enumerate_configs(p):
        try:
            with np.errstate(divide="ignore", invalid="ignore"):
                lk = four_bar(**cfg, rails_mm=p.rails) if p.linkage_type == "four-bar" else \
                    slider_crank(**cfg, rails_mm=p.rails)
                h = simulate(lk, samples=q.samples, speed_hz=q.speed_hz, model=q.model)
        except (ClosureError, AssemblyError):
            continue
        pk = peaks(h)
        if not h.meta.get("singular") and not any(v.get("singular") for v in pk.values()):
            return part_cases(h, pk, s)
    raise InputError(f"no {p.linkage_type} configuration of rails {list(p.rails)} mm can run")


def _basis_specs(p: SweepParams, s: CheckSettings) -> dict[tuple, tuple[PartCase, list[UnitLoad]]]:
    """Per (part, params, supports): a template case (mesh, supports, refinement) and every unit
    load any configuration can use.  Supports, load groups and inertia loads come from the
    load-case functions themselves (a reference configuration); only the sets are widened:
    a rail's coupling may use any hole in cycle mode, and bearing directions span the basis."""
    specs: dict[tuple, tuple[PartCase, list[UnitLoad]]] = {}
    ncyc, norig = directions(s.bearing_directions), directions(ORIGINAL_DIRECTIONS)
    for mode, case in _reference_cases(p, s):
        groups = list(dict.fromkeys(u.group for u in case.loads if u.kind == "bearing"))
        refine = tuple(case.refine)
        if "length" in case.params and mode == "cycle":
            groups = [rail_hole_name(i) for i in range(len(rig_rail_layout(case.params["length"]).hole_x))]
            refine = tuple(dict.fromkeys(refine + tuple(groups)))
        loads = [UnitLoad("bearing", g, d) for g in groups for d in (ncyc if mode == "cycle" else norig)]
        loads += [u for u in case.loads if u.kind == "inertia"]
        if mode == "original" and "length" not in case.params:  # a fitting's fixed study load stays exact
            loads += list(case.loads)
        key = case_key(case)
        old_case, old_loads = specs.get(key, (case, []))
        specs[key] = (dataclasses.replace(old_case, name="basis",
                                          refine=tuple(sorted(set(old_case.refine) | set(refine)))),
                      list(dict.fromkeys(old_loads + loads)))
    return specs


def parallel_bases(workers: int, geometries: int) -> int:
    """How many part geometries :func:`build_bases` solves at a time: at most two (the
    :data:`rigfem.mesh.pool.WORKERS` of the meshers beside them), one per worker."""
    from rigfem.mesh.pool import WORKERS

    return max(1, min(workers, WORKERS, geometries))


def _geometries(p: SweepParams) -> tuple[dict, dict, list]:
    """The bases' specs by part geometry, each geometry's merged case (one mesh), and the
    geometries largest first (estimated mesh); worked out once per process (it simulates a
    reference configuration) for the parameters and their parts' geometry (:meth:`SweepParams.key`)."""
    return _geometries_at(p, p.key())


@functools.lru_cache(maxsize=4)
def _geometries_at(p: SweepParams, params_key: str) -> tuple[dict, dict, list]:
    from rigfem.fe.partcase import mesh_job
    from rigfem.mesh.mesher import estimate_part

    s = p.settings()
    by_geo: dict[tuple, dict[tuple, tuple[PartCase, list[UnitLoad]]]] = {}
    for key, spec in _basis_specs(p, s).items():
        by_geo.setdefault(key[:2], {})[key] = spec
    merged = {geo: dataclasses.replace(next(iter(specs.values()))[0],
                                       refine=tuple(sorted({g for c, _ in specs.values() for g in c.refine})))
              for geo, specs in by_geo.items()}
    order = sorted(by_geo, key=lambda geo: -getattr(estimate_part(*mesh_job(merged[geo], s)), "tets", 0))
    return by_geo, merged, order


def mesh_ahead(p: SweepParams) -> None:
    """Start meshing the geometries of :func:`build_bases` in the mesher processes, largest first
    (it finds them made, or being made), and numba compiling the assembly on a first run: a
    caller with other work first overlaps the two."""
    from rigfem.fe.assembly import start_compiling
    from rigfem.fe.partcase import mesh_job
    from rigfem.mesh.mesher import prefetch

    s = p.settings()
    _, merged, order = _geometries(p)
    prefetch([mesh_job(merged[geo], s) for geo in order])
    start_compiling()


def build_bases(p: SweepParams, solver: str = "auto", workers: int = 1,
                folder: Path | None = None) -> dict[tuple, UnitBasis]:
    """One mesh, one factorisation and the unit solutions of every part geometry and support set.

    The geometries are meshed ahead in the mesher processes (:func:`mesh_ahead`), largest first.
    With ``workers`` > 1 their FE runs in child processes (:func:`rigfem.mesh.worker.call`),
    :func:`parallel_bases` at a time: most of a basis's time is single-threaded (stress recovery,
    load vectors), so two geometries at once use two cores and hold two geometries' FE in memory
    (a sweep's ``--workers`` chooses this; :func:`rigfem.sweep.cost.bases_cost` counts it).  A
    child returns only the float32 unit fields.  Otherwise, or in a daemonic process (a sweep
    worker), the geometries are built here one after another, the largest first (while the
    fewest bases are held), each model released before the next one's is built.  With
    ``folder`` each basis is stored there as it is made and memory-mapped (:func:`mapped`): the
    bases built are not held while the next ones are (the caller keeps the folder while it uses
    them)."""
    import multiprocessing as mp
    import threading
    from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

    from rigfem.fe.assembly import compiled
    from rigfem.fe.partcase import mesh_case
    from rigfem.mesh import pool
    from rigfem.mesh.worker import call

    s = p.settings()
    by_geo, merged, order = _geometries(p)
    parallel = workers > 1 and len(by_geo) > 1 and not mp.current_process().daemon
    mesh_ahead(p)  # (the jobs an earlier call started go on)

    if parallel:
        compiled()  # numba compiles the kernels once, while the meshers work, for both children
        stop = threading.Event()  # an error or an interruption here ends the children

        def child(g: tuple) -> dict[tuple, UnitBasis]:
            if stop.is_set():
                raise ComputeError("unit bases cancelled")
            pm = mesh_case(merged[g], s)
            return call(_geo_bases, pm, by_geo[g], s, solver, folder, cancel=stop, what="unit bases")

        threads = ThreadPoolExecutor(parallel_bases(workers, len(order)), thread_name_prefix="rigfem-bases")
        try:
            futures = [threads.submit(child, geo) for geo in order]
            finished, _ = wait(futures, return_when=FIRST_EXCEPTION)  # the first error, not the largest part's end
            for f in finished:
                if f.exception() is not None:
                    raise f.exception()
            done = {g: f.result() for g, f in zip(order, futures)}
        except BaseException:
            stop.set()
            pool.cancel()
            raise
        finally:
            threads.shutdown(wait=True, cancel_futures=True)
    else:
        done = {geo: _geo_bases(mesh_case(merged[geo], s), by_geo[geo], s, solver, folder) for geo in order}
    return {key: b for geo in by_geo for key, b in done[geo].items()}


#: unit loads of a basis solved (and cached) at a time: their float64 solution is held only until
#: it is reduced to the basis's float32 fields and stored in the cache (while the next batch is
#: solved), not the whole basis's at once
BASIS_BATCH = 24


def _geo_bases(pm, specs: dict[tuple, tuple[PartCase, list[UnitLoad]]], s: CheckSettings,
               solver: str, folder: Path | None = None) -> dict[tuple, UnitBasis]:
    """The unit bases of one part geometry's mesh ``pm``, one per support set of ``specs``: one
    factorisation per support set, its unit loads solved :data:`BASIS_BATCH` at a time, each
    batch's cache entry written in a thread while the next is solved; each basis mapped from
    ``folder`` if given (:func:`mapped`)."""
    from concurrent.futures import ThreadPoolExecutor

    from rigfem.fe.model import build_model

    model = build_model(pm, s.material, s.order)
    out = {}
    writer, pending = ThreadPoolExecutor(1, thread_name_prefix="rigfem-cache-write"), []

    def store(write) -> None:  # one entry written at a time: a batch is held until it is written
        while pending:
            pending.pop().result()
        pending.append(writer.submit(write))

    with writer:
        for key, (case, loads) in specs.items():
            out[key] = _basis(model, key, case, loads, s, solver, folder, store)
        while pending:
            pending.pop().result()
    model.release()
    return out


def _basis(model, key: tuple, case: PartCase, loads: list[UnitLoad], s: CheckSettings, solver: str,
           folder: Path | None, store) -> UnitBasis:
    """One support set's basis (:func:`_geo_bases`)."""
    from rigfem.fe.cache import cached_solve
    from rigfem.fe.partcase import fe_load, relieved_cases, supports_of
    from rigfem.fe.supports import FreeBody
    from rigfem.fe.tensors import von_mises
    from rigfem.memory import trim_heap

    supports = supports_of(case)
    fe_loads = [fe_load(u) for u in loads]
    if any(isinstance(x, FreeBody) for x in supports):
        fe_loads = relieved_cases(model, fe_loads)[0]
    shape = (len(loads), len(model.mesh.nodes), 6)
    vm = np.empty(shape[:2], np.float32)
    if folder is None:
        S, out_file = np.empty(shape, np.float32), None
    else:  # the fields go to their file batch by batch, never all in memory
        out_file = open(_basis_file(folder, key, "S"), "wb")
        np.lib.format.write_array_header_1_0(out_file, {"descr": "<f4", "fortran_order": False, "shape": shape})
    factorised: dict = {}  # one factorisation for every batch the cache lacks
    with out_file or contextlib.nullcontext():
        for b in range(0, len(fe_loads), BASIS_BATCH):
            sol = cached_solve(model, supports, fe_loads[b:b + BASIS_BATCH], solver=solver,
                               factorised=factorised, store=store)
            vm[b:b + BASIS_BATCH] = von_mises(sol.nodal_stress)
            if out_file is None:
                S[b:b + BASIS_BATCH] = sol.nodal_stress
            else:
                sol.nodal_stress.astype("<f4").tofile(out_file)
            del sol
    del factorised
    if out_file is not None:
        S = _open_mapped(out_file.name)
    basis = _reduce(key, loads, S, vm, model.volume * s.material.density * 1e3)
    del S, vm
    if folder is not None:
        basis = mapped(basis, folder)
    trim_heap()
    return basis


def _reduce(key: tuple, loads: list[UnitLoad], S: np.ndarray, vm: np.ndarray, fe_mass: float) -> UnitBasis:
    """Index the unit loads and keep float32 fields and each field's top nodes."""
    groups: dict[str, list] = {}
    inertia = {}
    for j, u in enumerate(loads):
        if u.kind == "bearing":
            groups.setdefault(u.group, []).append((np.mod(np.arctan2(u.direction[1], u.direction[0]), 2 * np.pi), j))
        else:
            inertia[(u.component, tuple(u.direction))] = j
    g = {}
    for name, lst in groups.items():
        lst.sort()
        g[name] = (np.array([a for a, _ in lst]), np.array([j for _, j in lst]))
    n_top = min(TOP_NODES, vm.shape[1])
    top = np.argpartition(-vm, n_top - 1, axis=1)[:, :n_top]
    return UnitBasis(key, loads, g, inertia, S.astype(np.float32, copy=False), vm.astype(np.float32, copy=False),
                     top, fe_mass)


def _columns(b: UnitBasis, u: UnitLoad, mass_ratio: float) -> list[tuple[int, float]]:
    """Basis columns and weights that reproduce unit load ``u`` (direction split if needed)."""
    if u.kind == "inertia":
        return [(b.inertia[(u.component, tuple(u.direction))], mass_ratio)]
    ang, cols = b.groups[u.group]
    a = np.mod(np.arctan2(u.direction[1], u.direction[0]), 2 * np.pi)
    diff = np.abs((ang - a + np.pi) % (2 * np.pi) - np.pi)
    i = int(np.argmin(diff))
    if diff[i] < 1e-9:
        return [(int(cols[i]), 1.0)]
    lo = int(np.searchsorted(ang, a)) - 1
    i0, i1 = lo % len(ang), (lo + 1) % len(ang)
    e0, e1 = np.array([np.cos(ang[i0]), np.sin(ang[i0])]), np.array([np.cos(ang[i1]), np.sin(ang[i1])])
    w = np.linalg.solve(np.c_[e0, e1], [np.cos(a), np.sin(a)])
    if (w < -1e-12).any() or (diff[i0] + diff[i1]) > np.pi / 2 + 1e-9:
        raise InputError(f"bearing direction on {u.group} is not between two basis directions")
    return [(int(cols[i0]), float(w[0])), (int(cols[i1]), float(w[1]))]


def _row_peaks(C: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Peak von Mises of every row of coefficients C (n, k) over the nodes of S (k, P, 6)."""
    from rigfem.fe.tensors import von_mises

    return np.concatenate([von_mises(np.tensordot(C[s:s + ROW_CHUNK], S, 1)).max(axis=1)
                           for s in range(0, len(C), ROW_CHUNK)])


def case_peak(b: UnitBasis, case: PartCase, exact: bool = False) -> tuple[float, float]:
    """Peak von Mises (MPa) of a case over all rows, and its crank angle (deg): exact, by bounds.

    Von Mises is a norm of the stress deviator, so at node p and any row of coefficients c,
    vm(Σ c_k σ_k) ≤ Σ |c_k| vm(σ_k).  The rows are split into :data:`BOUND_GROUPS` groups,
    each bounded per node with its largest |c_k|; the combination is evaluated at the
    :data:`TOP_NODES` highest nodes of every unit field it uses (a lower bound of the peak),
    then only at the nodes whose bound reaches that lower bound, group by group.  No node that
    can hold the peak is skipped; ``exact=True`` evaluates every node (the tests' reference).
    """
    M = np.zeros((len(case.loads), len(b.loads)))
    for i, u in enumerate(case.loads):
        ratio = case.mass_kg / b.fe_mass if (u.kind == "inertia" and case.mass_kg) else 1.0
        for j, w in _columns(b, u, ratio):
            M[i, j] += w
    C = case.coef @ M
    used = np.flatnonzero(np.abs(C).max(axis=0) > 0)
    if used.size == 0:
        return 0.0, float(case.rows[0])
    rows_peak = superposed_peaks(b, C[:, used].astype(np.float32), used, exact)
    r = int(np.argmax(rows_peak))
    return float(rows_peak[r]), float(case.rows[r])


def superposed_peaks(b: UnitBasis, C: np.ndarray, used: np.ndarray, exact: bool = False) -> np.ndarray:
    """Peak von Mises of each row of ``C`` (rows, len(used)) over the basis fields ``used``;
    with bounds (see :func:`case_peak`) only the largest row's value is guaranteed exact."""
    if exact:
        return _row_peaks(C, b.S[used])
    cand = np.unique(b.top[used])
    rows_peak = _row_peaks(C, b.S[np.ix_(used, cand)])
    floor = rows_peak.max() * (1 - 1e-4)  # float32 round-off margin
    edges = np.linspace(0, len(C), min(BOUND_GROUPS, len(C)) + 1).astype(int)
    cmax = np.stack([np.abs(C[a:e]).max(axis=0) for a, e in zip(edges[:-1], edges[1:])])
    bound = cmax @ b.vm[used]  # (groups, N)
    for g, (a, e) in enumerate(zip(edges[:-1], edges[1:])):
        more = np.setdiff1d(np.flatnonzero(bound[g] >= floor), cand, assume_unique=True)
        if more.size:
            rows_peak[a:e] = np.maximum(rows_peak[a:e], _row_peaks(C[a:e], b.S[np.ix_(used, more)]))
    return rows_peak
