"""The rig sweep's FE unit bases: per rail geometry and support set, one factorisation gives
the unit stress and displacement fields of every load a configuration can apply
(:mod:`rigfem.sweep.superpose` combines them), stored compact (float32) in the cache.

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
from rigfem.cache import Cache, resolve
from rigfem.errors import ComputeError, InfeasibleError
from rigfem.linkage.mechanisms import four_bar, slider_crank
from rigfem.loads.cases import PartCase, UnitLoad, directions, part_cases
from rigfem.rig.parts import rail_hole_name
from rigfem.settings import CheckSettings
from rigfem.sweep.configs import (
    ORIGINAL_DIRECTIONS,
    SweepParams,
    TOP_NODES,
    rig_rail_layout,
    enumerate_configs,
)


# ----------------------------------------------------------------------------- FE unit bases
@dataclass
class UnitBasis:
    """The unit solutions of one part geometry and support set (float32, every node): what a
    configuration's peak, its error band and its free-body balance are superposed from."""

    key: tuple
    loads: list[UnitLoad]
    groups: dict[str, tuple[np.ndarray, np.ndarray]]  #: group -> (angles rad sorted, columns)
    inertia: dict[tuple, int]  #: (component, origin) -> column
    S: np.ndarray  #: (k, N, 6) nodal stress of every unit load
    vm: np.ndarray  #: (k, N) von Mises of every unit field (the bound of :func:`case_peak`)
    top: np.ndarray  #: (k, TOP_NODES) the nodes where each unit field is highest
    U: np.ndarray  #: (k, N, 3) displacement of every unit load (the error band at a peak)
    R: np.ndarray | None  #: (6, k) resultants of the unit loads of a free body, None when supported
    scale: np.ndarray | None  #: (k,) their force magnitudes
    mesh: object  #: the rigfem.fe.assembly.FEMesh the fields live on (nodes, elements, curved)
    material: tuple[float, float]  #: E (MPa), nu
    lever: float  #: mm, the part's farthest node from its centroid
    fe_mass: float  #: kg, mass of the meshed part


class _Mapped(np.memmap):
    """A read-only memory-mapped array that pickles as its file name: the workers of a local
    cluster (or the process a child built a basis for) map the same file, one copy in the page
    cache, instead of each receiving a copy."""

    def __reduce__(self):
        return _open_mapped, (self.filename,)


def _open_mapped(path: str) -> np.ndarray:
    return np.load(path, mmap_mode="r").view(_Mapped)


#: the large fields of a basis: memory-mapped from a folder when there is one
_FIELDS = ("S", "vm", "U")


def mapped(b: UnitBasis, folder: Path) -> UnitBasis:
    """``b`` with its large fields stored in ``folder`` and memory-mapped from there (those not
    mapped yet): a process holds only the pages it reads (a configuration's peak reads its few
    candidate nodes)."""
    arrays = {}
    for field in _FIELDS:
        a = getattr(b, field)
        if not isinstance(a, _Mapped):
            f = folder / f"basis_{hashlib.sha256(repr(b.key).encode()).hexdigest()[:16]}_{field}.npy"
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
    raise InfeasibleError(f"no {p.linkage_type} configuration of rails {list(p.rails)} mm can run")


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


def mesh_ahead(p: SweepParams, cache: Cache) -> None:
    """Start meshing the geometries of :func:`build_bases` in the mesher processes, largest first
    (it finds them made, or being made), and numba compiling the assembly on a first run: a
    caller with other work first overlaps the two."""
    from rigfem.fe.assembly import start_compiling
    from rigfem.fe.partcase import mesh_job
    from rigfem.mesh.mesher import prefetch

    s = p.settings()
    by_geo, merged, order = _geometries(p)
    todo = [geo for geo in order if not _cached(mesh_job(merged[geo], s), by_geo[geo], p, cache)]
    if todo:
        prefetch([mesh_job(merged[geo], s) for geo in todo], cache)
        start_compiling(cache)


def _cached(job: tuple, specs: dict, p: SweepParams, cache: Cache, solver: str = "auto") -> bool:
    """Whether every basis of a geometry seems stored (a cheap look: no mesh is needed then)."""
    return all(cache.has("bases", inputs) for inputs in _geo_keys(job, specs, p.settings(), solver).values())


def build_bases(p: SweepParams, solver: str = "auto", workers: int = 1,
                folder: Path | None = None, cache: Cache | None = None) -> dict[tuple, UnitBasis]:
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
    from rigfem.fe.partcase import mesh_job
    from rigfem.mesh import pool
    from rigfem.mesh.mesher import mesh_part
    from rigfem.mesh.worker import call

    s = p.settings()
    by_geo, merged, order = _geometries(p)
    jobs = {geo: mesh_job(merged[geo], s) for geo in order}
    keys = {geo: _geo_keys(jobs[geo], by_geo[geo], s, solver) for geo in order}
    parallel = workers > 1 and len(by_geo) > 1 and not mp.current_process().daemon
    cache = resolve(cache)
    mesh_ahead(p, cache)  # (the jobs an earlier call started go on)

    if parallel:
        compiled(cache)  # numba compiles the kernels once, while the meshers work, for both children
        stop = threading.Event()  # an error or an interruption here ends the children

        def child(g: tuple) -> dict[tuple, UnitBasis]:
            if stop.is_set():
                raise ComputeError("unit bases cancelled")
            stored = _stored(keys[g], cache, folder)
            if stored is not None:
                return stored
            pm = mesh_part(*jobs[g], cache=cache)  # here: the mesher processes made it ahead
            return call(_solve_geo, pm, (by_geo[g], keys[g]), s, solver, folder, cache, cancel=stop,
                        what="unit bases")

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
        done = {}
        for geo in order:
            done[geo] = _stored(keys[geo], cache, folder)
            if done[geo] is None:
                done[geo] = _solve_geo(mesh_part(*jobs[geo], cache=cache), (by_geo[geo], keys[geo]), s, solver,
                                       folder, cache)
    return {key: b for geo in by_geo for key, b in done[geo].items()}


#: unit loads of a basis solved at a time: their float64 solution is held only until it is reduced
#: to the basis's float32 fields, written to the basis's files, not the whole basis's at once
BASIS_BATCH = 24


def _basis_inputs(mesh_key: str, case: PartCase, loads: list[UnitLoad], s: CheckSettings, solver: str) -> dict:
    """Everything a basis depends on (its cache key; the package's code is in every key)."""
    from rigfem.fe.cache import _plain
    from rigfem.fe.partcase import supports_of

    return {"mesh": mesh_key, "order": s.order, "material": _plain(s.material),
            "supports": _plain(supports_of(case)), "loads": _plain(loads), "solver": solver}


def _geo_keys(pm_job: tuple, specs: dict, s: CheckSettings, solver: str) -> dict[tuple, dict]:
    from rigfem.mesh.mesher import mesh_inputs

    mesh_key = mesh_inputs(*pm_job)[0]
    return {key: _basis_inputs(mesh_key, case, loads, s, solver) for key, (case, loads) in specs.items()}


def _stored(keys: dict[tuple, dict], cache: Cache, folder: Path | None) -> dict[tuple, UnitBasis] | None:
    """Every basis of a geometry from the cache (mapped into ``folder`` if given), or None."""
    got = {}
    for key, inputs in keys.items():
        b = cache.get("bases", inputs, lambda entry, key=key: _load(entry, key, folder))
        if b is None:
            return None
        got[key] = b
    return got


def _solve_geo(pm, specs: tuple[dict, dict], s: CheckSettings, solver: str, folder: Path | None,
               cache: Cache) -> dict[tuple, UnitBasis]:
    """The unit bases of one part geometry's mesh ``pm``, one per support set of ``specs`` (the
    specs and their cache inputs): one model, one factorisation per support set, the unit loads
    solved :data:`BASIS_BATCH` at a time and streamed to the basis's files, stored in the cache;
    each basis mapped from ``folder`` if given (:func:`mapped`), else held in memory."""
    import tempfile

    from rigfem.fe.model import build_model

    specs, keys = specs
    model = build_model(pm, s.material, s.order, cache)
    out = {}
    for key, (case, loads) in specs.items():
        with tempfile.TemporaryDirectory(prefix="rigfem-basis-", dir=folder) as tmp:
            _build(model, case, loads, s, solver, Path(tmp))
            cache.put("bases", keys[key], lambda entry: _link_all(Path(tmp), entry))
            out[key] = _load(_Folder(Path(tmp)), key, folder)
    model.release()
    return out


class _Folder:
    """A freshly built basis's folder read as a cache entry is (:class:`rigfem.cache.Entry`)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder

    def json(self, name: str):
        import json

        return json.loads((self.folder / name).read_text())

    def array(self, name: str) -> np.ndarray:
        return np.load(self.folder / f"{name}.npy")

    def copy(self, name: str, dest: Path) -> None:
        import shutil

        shutil.copyfile(self.folder / name, dest)


def _link_all(src: Path, dest: Path) -> None:
    """Every file of ``src`` into ``dest``: hard links where the file system allows, else copies."""
    import os
    import shutil

    for f in src.iterdir():
        try:
            os.link(f, dest / f.name)
        except OSError:
            shutil.copyfile(f, dest / f.name)


def _build(model, case: PartCase, loads: list[UnitLoad], s: CheckSettings, solver: str, tmp: Path) -> None:
    """Solve one support set's unit loads into ``tmp``: the float32 fields S, vm and U streamed
    batch by batch, the free body's resultants, the mesh and the numbers of the basis."""
    import json

    from rigfem.errors import ComputeError
    from rigfem.fe.cache import check_energy
    from rigfem.fe.model import StaticProblem
    from rigfem.fe.partcase import fe_load, lever_mm, relieved_cases, supports_of
    from rigfem.fe.supports import FreeBody
    from rigfem.tensors import von_mises
    from rigfem.memory import trim_heap

    supports = supports_of(case)
    fe_loads = [fe_load(u) for u in loads]
    free = any(isinstance(x, FreeBody) for x in supports)
    R = scale = None
    if free:
        fe_loads, R, scale = relieved_cases(model, fe_loads)
    fm, n = model.mesh, len(model.mesh.nodes)
    problem = StaticProblem(model, supports, solver)
    vm = np.empty((len(loads), n), np.float32)
    files = {name: open(tmp / f"{name}.npy", "wb") for name in ("S", "U")}
    with contextlib.ExitStack() as stack:
        for name, shape in (("S", (len(loads), n, 6)), ("U", (len(loads), n, 3))):
            stack.enter_context(files[name])
            np.lib.format.write_array_header_1_0(files[name], {"descr": "<f4", "fortran_order": False, "shape": shape})
        for b in range(0, len(fe_loads), BASIS_BATCH):
            sol = problem.solve(fe_loads[b:b + BASIS_BATCH], last=b + BASIS_BATCH >= len(fe_loads))
            why = check_energy(sol)
            if why:
                raise ComputeError(f"the unit solutions of part {model.part.name} cannot be right: {why}")
            vm[b:b + BASIS_BATCH] = von_mises(sol.nodal_stress)
            sol.nodal_stress.astype("<f4").tofile(files["S"])
            np.ascontiguousarray(sol.U.T.reshape(-1, n, 3), dtype="<f4").tofile(files["U"])
            del sol
    del problem
    arrays = {"vm": vm, "nodes": fm.nodes, "elements": fm.elements.astype(np.int32),
              "curved": fm.curved if fm.curved is not None else np.zeros(len(fm.elements), bool)}
    if free:
        arrays.update(R=R, scale=scale)
    for name, a in arrays.items():
        np.save(tmp / f"{name}.npy", a, allow_pickle=False)
    (tmp / "basis.json").write_text(json.dumps({
        "fe_mass": model.volume * s.material.density * 1e3, "lever": lever_mm(model), "order": fm.order,
        "n_vertices": fm.n_vertices, "E": s.material.E, "nu": s.material.nu, "free": free,
        "loads": [dataclasses.asdict(u) for u in loads]}))
    trim_heap()


def _load(entry, key: tuple, folder: Path | None) -> UnitBasis:
    """The basis of an entry (a cache entry, or a freshly built folder): its large fields
    memory-mapped from copies in ``folder`` if given, else read into memory."""
    from rigfem.fe.assembly import FEMesh

    info = entry.json("basis.json")
    if folder is None:
        big = {name: entry.array(name) for name in _FIELDS}
    else:
        big = {}
        for name in _FIELDS:
            dest = Path(folder) / f"basis_{hashlib.sha256(repr(key).encode()).hexdigest()[:16]}_{name}.npy"
            entry.copy(f"{name}.npy", dest)
            big[name] = _open_mapped(str(dest))
    mesh = FEMesh(entry.array("nodes"), entry.array("elements").astype(np.int64), {}, info["order"],
                  info["n_vertices"], entry.array("curved"))
    loads = [UnitLoad(u["kind"], u["group"], None if u["direction"] is None else tuple(u["direction"]),
                      u["component"]) for u in info["loads"]]
    free = info["free"]
    return _reduce(key, loads, big, mesh, info, entry.array("R") if free else None,
                   entry.array("scale") if free else None)


def _reduce(key: tuple, loads: list[UnitLoad], big: dict, mesh, info: dict, R, scale) -> UnitBasis:
    """Index the unit loads and keep each field's top nodes."""
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
    vm = big["vm"]
    n_top = min(TOP_NODES, vm.shape[1])
    top = np.argpartition(-np.asarray(vm), n_top - 1, axis=1)[:, :n_top]
    return UnitBasis(key, loads, g, inertia, big["S"], vm, top, big["U"], R, scale, mesh,
                     (info["E"], info["nu"]), info["lever"], info["fe_mass"])
