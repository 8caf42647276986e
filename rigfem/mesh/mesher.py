"""Meshing a part in gmsh: sizes, refinement fields, second-order nodes, memory estimate, the mesh cache (:mod:`rigfem.cache`)."""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass

import numpy as np

from rigfem.mesh import pool
from rigfem.cache import Cache, package_hash, resolve
from rigfem.mesh.partmesh import (
    PartMesh,
    fit_cylinder,
    load_npz,
    quality_summary,
    save_npz,
)
from rigfem.settings import MeshSettings, check_groups

#: machine memory the estimate is checked against, GiB: this machine's physical memory
MACHINE_GIB = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30


#: empirical tets per h^3 of volume for gmsh's Delaunay mesher (calibrated on the rail and plate)
TETS_PER_H3 = 8.4


#: tets gmsh makes per second, second-order step included, on one core (the draft 1000 mm rail:
#: 26.5k tets in 11-16 s on a busy 2-core machine)
TETS_PER_S = 2000.0


#: curved surfaces get CURVATURE_MM / size elements per 2*pi (gmsh Mesh.MeshSizeFromCurvature):
#: 6 at the draft 8 mm, 8 at the standard 6 mm, 12 at the fine 4 mm
CURVATURE_MM = 48.0


#: part kinds whose second-order mesh gets gmsh's ``HighOrderElastic`` smoothing.  Measured
#: (issue 26, standard ``final-cm``): without it the rails' peaks move by up to 6.8 %, the plates'
#: and posts' by about 0.1 % (results/benchmarks/levers.md), far inside the standard preset's 3 %
#: band, while it costs them 6.3 s of the cold check; a custom part's shape is unknown, so it keeps
#: it.  Elements it would have repaired are straightened by rigfem.fe.assembly.fe_mesh (MIN_JACOBIAN).
SMOOTHED_KINDS = frozenset({"rail", "custom"})


#: gmsh's relative precision for integrating the size field along a curve (``Mesh.LcIntegrationPrecision``),
#: which sets how many nodes each curve gets.  At gmsh's default, 1e-9, the 1D step was most of a
#: plate's or post's mesh time (2.5 s of the coarse post's 3.0 s); at 1e-4 it takes a tenth of that,
#: and no mesh of a check's ladder changes its tet count by more than 2 %
#: (``python benchmarks/bench_mesh.py``: results/benchmarks/mesh.md)
LC_INTEGRATION_PRECISION = 1e-4


def curvature_n(s: MeshSettings) -> int:
    """Elements per 2*pi on a curved surface: CURVATURE_MM / size (at least 6), so curved
    faces (rail grooves, holes) get finer with the global size and a size sequence converges."""
    return max(6, round(CURVATURE_MM / s.size_mm))


#: default global element size per part kind, mm (rail: about 4 elements across its 23 x 24 section)
DEFAULT_SIZE = {"rail": 6.0, "plate": 5.0, "iprofile": 4.0, "custom": 5.0}


@dataclass(frozen=True)
class Estimate:
    """Predicted size of a mesh and of its P2 solve, before meshing."""

    tets: int
    gmsh_bytes: float  #: peak memory of gmsh while meshing
    solve_bytes: float  #: memory of a direct P2 solve on the mesh (3 DOF per node)

    @property
    def seconds(self) -> float:
        """Wall time of meshing (linear tets, second order and its smoothing), s."""
        return self.tets / TETS_PER_S

    @property
    def gib(self) -> float:
        return max(self.gmsh_bytes, self.solve_bytes) / 2**30


def estimate_tets(volume: float, refined_area: float, s: MeshSettings, concentrated_area: float = 0.0) -> int:
    """Tetrahedra gmsh will make: volume/h^3 plus a graded layer over the refined surfaces.

    The size grows linearly from ``near_mm`` (half that on concentrators) at a refined surface
    to ``size_mm`` at ``dist_mm``; a layer of area A then holds A * integral of (1/h(d)^3 - 1/size^3)
    over 0..dist_mm extra tets (at most the whole volume at the refined size).
    """
    h, D = s.size_mm, s.dist_mm

    def layer(hn: float) -> float:
        hn = min(hn, h)
        return D / (h - hn) * (1 / (2 * hn**2) - 1 / (2 * h**2)) - D / h**3 if h - hn > 1e-12 else 0.0

    hn = min(s.near_mm, h)
    extra = refined_area * layer(hn) + concentrated_area * layer(hn / 2)
    return int(TETS_PER_H3 * min(volume / h**3 + extra, volume / (hn / 2 if concentrated_area else hn)**3))


def estimate(tets: int) -> Estimate:
    """Memory of meshing (about 1 kB per tet in gmsh) and of a direct P2 solve.

    P2 on tets: about 1.4 nodes per tet, 3 DOF each; the stiffness has about 80 entries
    per row; a nested-dissection factor of a 3-D problem holds about 8*n^(4/3) entries
    (12 bytes each, value plus index).
    """
    n = 3 * 1.4 * tets
    return Estimate(tets, 1000.0 * tets, 12.0 * (80 * n + 8 * n ** (4 / 3)))


def _quality() -> np.ndarray:
    """gmsh's minSICN of every linear tetrahedron of the current mesh."""
    import gmsh

    return np.asarray(gmsh.model.mesh.getElementQualities(gmsh.model.mesh.getElementsByType(4)[0], "minSICN"))


def second_order(groups: dict[str, list[int]], rtol: float = 1e-3, smooth: bool = True):
    """Make gmsh's current linear tet mesh second order and read it back.

    gmsh puts every boundary mid-edge node on the geometry (grooves, holes, fillets) and then
    moves the interior nodes by an elastic analogy (``HighOrderElastic``) so the elements next
    to a curved wall stay valid; that can shift vertices slightly, so the whole mesh is read
    again.  ``groups`` maps surface names to gmsh surface tags.  Returns points (N, 3),
    positively oriented tets (M, 4), the groups' triangles, and the curved edges: vertex pairs
    (E, 2) and mid-edge points (E, 3) of the edges whose node is off the straight midpoint by
    more than ``rtol`` times the edge length.  ``smooth=False`` skips the elastic smoothing
    (:data:`SMOOTHED_KINDS` says for which parts it changes the peak).
    """
    import gmsh

    gmsh.model.mesh.setOrder(2)
    if smooth:
        gmsh.model.mesh.optimize("HighOrderElastic")
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = np.zeros((int(tags.max()) + 1, 3))
    xyz[tags.astype(np.int64)] = coords.reshape(-1, 3)
    el = gmsh.model.mesh.getElementsByType(11)[1].astype(np.int64).reshape(-1, 10)
    vert = np.unique(el[:, :4])
    index = np.full(len(xyz), -1, np.int64)
    index[vert] = np.arange(len(vert))
    points, tets = xyz[vert], index[el[:, :4]]
    neg = np.linalg.det(points[tets[:, 1:]] - points[tets[:, :1]]) < 0
    tets[neg, 1:3] = tets[neg, 2:0:-1]
    surfaces = {name: index[np.concatenate([gmsh.model.mesh.getElementsByType(9, t)[1] for t in ents]
                                           ).astype(np.int64).reshape(-1, 6)[:, :3]]
                for name, ents in groups.items()}
    ref = np.asarray(gmsh.model.mesh.getElementProperties(11)[4]).reshape(10, 3)
    bary = np.c_[1 - ref.sum(1), ref]  # the two corners each of gmsh's mid-edge nodes lies between
    mids, first = np.unique(el[:, 4:].ravel(), return_index=True)
    pairs = el[:, np.array([np.flatnonzero(b > 0.25) for b in bary[4:]])].reshape(-1, 2)[first]
    a, b, m = xyz[pairs[:, 0]], xyz[pairs[:, 1]], xyz[mids]
    off = np.linalg.norm(m - 0.5 * (a + b), axis=1) > rtol * np.linalg.norm(b - a, axis=1)
    return points, tets, surfaces, index[pairs[off]], m[off]


def _set_fields(refine_tags: list[int], conc_tags: list[int], s: MeshSettings) -> None:
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMax", s.size_mm)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature_n(s))
    gmsh.option.setNumber("Mesh.LcIntegrationPrecision", LC_INTEGRATION_PRECISION)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)  # HXT: fastest here (min SICN: results/benchmarks/mesh.md)
    if not refine_tags:
        return
    f = gmsh.model.mesh.field
    plain = [t for t in refine_tags if t not in conc_tags]
    ths = [_threshold(tags, size, s) for tags, size in ((plain, s.near_mm), (conc_tags, s.near_mm / 2))
           if tags]
    if len(ths) > 1:
        both = f.add("Min")
        f.setNumbers(both, "FieldsList", ths)
        ths = [both]
    f.setAsBackgroundMesh(ths[0])
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)


def _threshold(tags: list[int], near_mm: float, s: MeshSettings) -> int:
    """A gmsh Threshold field: ``near_mm`` on the surfaces ``tags``, growing to ``s.size_mm`` at ``s.dist_mm``."""
    import gmsh

    f = gmsh.model.mesh.field
    dist = f.add("Distance")
    f.setNumbers(dist, "SurfacesList", tags)
    extent = max(float(np.ptp(np.array(gmsh.model.getBoundingBox(2, t)).reshape(2, 3), axis=0).max())
                 for t in tags)
    # sample points on each surface about half a refined element apart (within 20..500 per direction)
    f.setNumber(dist, "Sampling", int(np.clip(np.ceil(2 * extent / near_mm), 20, 500)))
    th = f.add("Threshold")
    f.setNumber(th, "InField", dist)
    f.setNumber(th, "SizeMin", min(near_mm, s.size_mm))
    f.setNumber(th, "SizeMax", s.size_mm)
    f.setNumber(th, "DistMin", 0.0)
    f.setNumber(th, "DistMax", s.dist_mm)
    return th


def estimate_part(part, s: MeshSettings) -> Estimate | None:
    """The estimate from the part's dimensions and the mesh settings, before gmsh builds
    anything: its envelope's volume at the global size (refinement comes on top, so a lower
    bound on the tets and a cheap first guard); None for a custom part (known only once read)."""
    from rigfem.rig.parts import envelope_mm3

    volume = envelope_mm3(part)
    return None if volume is None else estimate(estimate_tets(volume, 0.0, s))


def check_estimate(est: Estimate, s: MeshSettings, machine_gib: float, what: str = "would give") -> None:
    """Refuse (InfeasibleError, one line) a mesh whose estimate exceeds ``machine_gib``, unless the
    user lifted the limit (``rigfem --allow-large``)."""
    from rigfem.errors import InfeasibleError
    from rigfem.settings import allow_large

    if est.gib > machine_gib and not allow_large():
        raise InfeasibleError(f"size_mm = {s.size_mm:g} mm (local_size_mm = {s.near_mm:g} mm) "
                              f"{what} about {est.tets:.3g} tets needing {est.gib:.3g} GiB (gmsh "
                              f"{est.gmsh_bytes / 2**30:.3g} GiB, direct P2 solve {est.solve_bytes / 2**30:.3g} GiB) "
                              f"and about {est.seconds:.3g} s of meshing, more than the machine's {machine_gib:g} GiB: "
                              f"increase size_mm (--size), or pass rigfem --allow-large")


def mesh_part(part, settings: MeshSettings, *, cache: Cache | None = None,
              machine_gib: float = MACHINE_GIB) -> PartMesh:
    """Mesh a part (``rigfem.rig.parts.PartDef``) with linear tets, through ``cache`` (None: the
    environment's, :func:`rigfem.cache.resolve`; :data:`rigfem.cache.NO_CACHE`: meshed afresh).

    Refuses (InfeasibleError) a request whose estimate exceeds ``machine_gib`` (from the part's
    dimensions before gmsh starts, then from the built geometry) and a mesh whose minimum
    minSICN is below ``settings.min_quality``; ``refine`` must name surface groups.  gmsh runs
    in a child process (:mod:`rigfem.mesh.worker`), so a signal ends meshing at once (but with
    :data:`IN_PROCESS_ENV` set).
    """
    cache = resolve(cache)
    first = estimate_part(part, settings)
    if first is not None:
        check_estimate(first, settings, machine_gib, "would give at least")
    key, inputs = mesh_inputs(part, settings)
    if machine_gib == MACHINE_GIB:
        pm = pool.take(key)  # made ahead (prefetch): taken, so the pool keeps no copy of it
        if pm is not None:
            return pm
    pm = cache.get("meshes", inputs, lambda entry: load_npz(entry.bytes("mesh.npz")))
    if pm is not None:
        pm.meta["cache"] = "hit"
        return pm
    return make_mesh(part, settings, key, inputs, cache, machine_gib)


def mesh_state(part, settings: MeshSettings, cache: Cache) -> str:
    """'ready' (made ahead or cached: :func:`mesh_part` does not wait), 'making' (a mesher process) or 'none'."""
    key, inputs = mesh_inputs(part, settings)
    made = pool.state(key)
    return "ready" if made == "done" or cache.has("meshes", inputs) else "making" if made == "pending" else "none"


def prefetch(jobs: list[tuple], cache: Cache, keep: bool = False) -> int:
    """Start meshing every (part, MeshSettings) of ``jobs`` not in ``cache`` in the mesher
    processes of :mod:`rigfem.mesh.pool`, in the order given, so :func:`mesh_part` finds them
    made; returns how many were started.  Jobs of an earlier call never taken (a check that
    stopped early) are cancelled first, unless ``keep`` or asked for again (those go on).  In a
    daemonic process (a sweep worker, which may not have children) nothing is started."""
    import multiprocessing as mp

    if mp.current_process().daemon:  # (nothing can have been started here either)
        return 0
    keyed = [(part, settings, *mesh_inputs(part, settings)) for part, settings in jobs]
    if not keep:
        pool.cancel(spare=frozenset(key for *_, key, _ in keyed))
    started = 0
    for part, settings, key, inputs in keyed:
        if cache.has("meshes", inputs):  # mesh_part verifies the cached entry
            continue
        started += pool.submit(key, lambda stop, p=part, s=settings, k=key, i=inputs: make_mesh(p, s, k, i, cache,
                                                                                                  cancel=stop))
    return started


def mesh_inputs(part, settings: MeshSettings) -> tuple[str, dict]:
    """The key of a part's mesh (its identity: the solutions of a mesh are keyed by it) and the
    inputs it is made of (the package's code is in every cache key)."""
    import hashlib
    import json

    import gmsh

    inputs = {"part": part.name, "geometry": part.content_hash(), "settings": settings.key(),
              "smooth": part.kind in SMOOTHED_KINDS, "gmsh": gmsh.__version__}
    text = json.dumps({**inputs, "package": package_hash()}, sort_keys=True, default=str)
    return f"{part.name}-{hashlib.sha256(text.encode()).hexdigest()[:32]}", inputs


#: set (not "" or "0"), gmsh meshes in this process, one part at a time and not interruptible: for a
#: profiler or a debugger, and for mutation testing, whose coverage sees only this process
#: (tools/mutation_testing.py)
IN_PROCESS_ENV = "RIGFEM_MESH_IN_PROCESS"
_IN_PROCESS = threading.Lock()  # gmsh holds one model per process


def make_mesh(part, settings: MeshSettings, key: str, inputs: dict, cache: Cache,
              machine_gib: float = MACHINE_GIB, cancel=None) -> PartMesh:
    """Mesh in the mesher process (:mod:`rigfem.mesh.worker`; in this one with
    :data:`IN_PROCESS_ENV` set) and store the mesh in ``cache`` under ``inputs``; ``cancel`` (a
    threading.Event) ends the mesher, or a job still waiting for this process."""
    from rigfem.errors import ComputeError
    from rigfem.mesh.worker import call
    from rigfem.settings import allow_large

    limit = float("inf") if allow_large() else machine_gib  # the child may not share our environment
    if os.environ.get(IN_PROCESS_ENV, "") not in ("", "0"):
        with _IN_PROCESS:
            if cancel is not None and cancel.is_set():
                raise ComputeError("mesher cancelled")
            pm = _mesh(part, settings, limit, key)
    else:
        pm = call(_mesh, part, settings, limit, key, cancel=cancel)
    cache.put("meshes", inputs, lambda d: save_npz(pm, d / "mesh.npz"))
    return pm


def _mesh(part, settings: MeshSettings, machine_gib: float, key: str) -> PartMesh:
    """The gmsh work of :func:`mesh_part` (run in the mesher process)."""
    import gmsh

    from rigfem.errors import InfeasibleError
    from rigfem.mesh.geometry import build, gmsh_session

    t0 = time.perf_counter()
    stages = {}  # seconds of each step, in the mesh's metadata (benchmarks/bench_mesh.py reads them)

    def lap(name: str) -> None:
        stages[name] = time.perf_counter() - t0 - sum(stages.values())

    with gmsh_session(part.name):
        gmsh.option.setNumber("General.NumThreads", 1)
        holes = build(part)
        groups = {gmsh.model.getPhysicalName(d, t): t for d, t in gmsh.model.getPhysicalGroups(2)}
        check_groups(part.name, settings, groups)
        refine_tags, conc_tags = (sorted({t for g in names for t in gmsh.model.getEntitiesForPhysicalGroup(2, groups[g])})
                                  for names in (settings.refine + settings.concentrate, settings.concentrate))
        est = _estimate_model(refine_tags, conc_tags, settings)
        curved = _curved_groups(groups, settings)
        check_estimate(est, settings, machine_gib)
        _set_fields(refine_tags, conc_tags, settings)
        lap("geometry")
        for dim in (1, 2, 3):  # generate(3)'s mesh (to rounding), one dimension at a time to time each
            gmsh.model.mesh.generate(dim)
            lap(f"{dim}D")
        q = _quality()
        if len(q) and q.min() < settings.min_quality:
            # HXT can leave a flat tet across a thin wall whose two faces carry mirrored surface
            # meshes (the filleted I-profile web); gmsh's Delaunay inserts points and recovers
            gmsh.model.mesh.clear()
            gmsh.option.setNumber("Mesh.Algorithm3D", 1)
            gmsh.model.mesh.generate(3)
            q = _quality()
            lap("3D again (Delaunay)")
        if len(q) and q.min() < settings.min_quality:  # before the (costly) second-order step
            raise InfeasibleError(f"part {part.name}: mesh quality minSICN min = {q.min():.3f} is below "
                                  f"min_quality = {settings.min_quality:g}; change size_mm = {settings.size_mm:g} mm "
                                  f"or local_size_mm = {settings.near_mm:g} mm (or check thin walls in the part file)")
        points, tets, surfaces, edges, mids = second_order(
            {g: list(gmsh.model.getEntitiesForPhysicalGroup(2, t)) for g, t in groups.items()},
            smooth=part.kind in SMOOTHED_KINDS)
        lap("second order")
    seconds = time.perf_counter() - t0
    empty = [k for k, v in surfaces.items() if len(v) == 0]
    if empty or len(tets) == 0:
        raise InfeasibleError(f"part {part.name}: mesh has empty groups {empty}: decrease size_mm = {settings.size_mm:g} mm")
    if not holes:  # custom part: cylinders fitted to the meshed surfaces
        holes = {k: h for k, v in surfaces.items() if (h := fit_cylinder(points, v)) is not None}
    quality = quality_summary(q)  # of the linear mesh, before gmsh curved it
    meta = {"part": part.name, "kind": part.kind, "dims": {k: d.value for k, d in part.dims.items()},
            "density": part.density, "settings": settings.key(), "hash": key,
            "smoothed": part.kind in SMOOTHED_KINDS,
            "curved": curved, "estimate_tets": est.tets, "estimate_gib": est.gib, "seconds": seconds, "stages": stages,
            "cache": "miss"}
    pm = PartMesh(part.name, points, tets, surfaces, holes, quality, meta, edges, mids)
    return pm


def _estimate_model(refine_tags: list[int], conc_tags: list[int], s: MeshSettings) -> Estimate:
    """Estimate from the current gmsh model's volume, the area of the refined surfaces and the
    curved surfaces that curvature-based sizing meshes finer than ``s.size_mm``."""
    import gmsh

    occ_vols = gmsh.model.occ.getEntities(3)
    if occ_vols:
        volume = sum(gmsh.model.occ.getMass(3, t) for _, t in occ_vols)
        area = sum(gmsh.model.occ.getMass(2, t) for t in refine_tags if t not in conc_tags)
        conc = sum(gmsh.model.occ.getMass(2, t) for t in conc_tags)
        curved = [(gmsh.model.occ.getMass(2, t), _curvature_size(t, curvature_n(s))) for _, t in gmsh.model.getEntities(2)
                  if t not in refine_tags]
    else:  # built-in kernel: bounding box as an upper bound
        lo, hi = np.array(gmsh.model.getBoundingBox(-1, -1)).reshape(2, 3)
        volume = float(np.prod(hi - lo))
        area = sum(float(np.prod(np.sort(np.diff(np.array(gmsh.model.getBoundingBox(2, t)).reshape(2, 3),
                                                         axis=0)[0])[1:])) for t in refine_tags)
        curved, conc = [], 0.0
    tets = estimate_tets(volume, area, s, conc)
    # a layer one curvature size hc thick over a curved surface: A*hc/hc^3 tets instead of A*hc/h^3
    tets += int(TETS_PER_H3 * sum(a * (1 / hc**2 - hc / s.size_mm**3) for a, hc in curved if hc < s.size_mm))
    return estimate(tets)


def _curved_groups(groups: dict[str, int], s: MeshSettings) -> dict[str, float]:
    """Surface groups not in ``s.refine`` that curvature sizing meshes finer than ``s.size_mm``:
    name -> their smallest curvature size, mm (OpenCASCADE models; the built-in kernel gives none)."""
    import gmsh

    if not gmsh.model.occ.getEntities(3):
        return {}
    out = {}
    for name, tag in groups.items():
        if name not in s.refine:
            h = min(_curvature_size(t, curvature_n(s)) for t in gmsh.model.getEntitiesForPhysicalGroup(2, tag))
            if h < s.size_mm:
                out[name] = round(float(h), 3)
    return out


def _curvature_size(tag: int, n: int) -> float:
    """Element size gmsh's curvature sizing gives a surface: 2*pi/(k*n), k its largest principal
    curvature on a 3 x 3 grid of parametric points (inf for a flat surface)."""
    import gmsh

    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    uv = np.stack(np.meshgrid(*[np.linspace(a + 0.1 * (b - a), b - 0.1 * (b - a), 3) for a, b in zip(lo, hi)]),
                  -1).reshape(-1)
    kmax = np.abs(np.concatenate(gmsh.model.getPrincipalCurvatures(tag, uv)[:2])).max()
    return 2 * np.pi / (kmax * n) if kmax > 1e-9 else np.inf
