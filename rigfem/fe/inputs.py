"""The FE's public inputs judged once: supports, loads and the solver's name against the mesh.

A script calls :func:`rigfem.fe.build_model`, :func:`rigfem.fe.solve` (``StaticProblem``,
``load_matrix``, ``load_vector``, ``export_data``) and ``LinearSolver`` directly with its own
surface and hole names, supports, loads and solver name (docs/guide/own-part.md,
examples/custom_part.py), so these are user input as much as a scene file is: this module is a
boundary (tests/test_boundaries.py).  The public entry points call it once, before anything is
assembled: :func:`check_supports` and :func:`check_rigid` from
:func:`rigfem.fe.supports.constraints`, :func:`check_cases` and :func:`check_load` from
:func:`rigfem.fe.model.load_matrix` and :func:`rigfem.fe.forces.load_vector`, :func:`check_solver`
from ``LinearSolver``, :func:`check_mesh` (a script's own PartMesh and order) from
:func:`rigfem.fe.assembly.fe_mesh`.  Each raises InputError naming the support or load, its
field, the value and what is allowed (the surfaces or holes the mesh has).  The FE's inner
functions (quadrature, nodal vectors, springs) trust what passed here: a name they cannot find
there is a bug, a ComputeError.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from rigfem.errors import InputError
from rigfem.mesh.partmesh import vertex_set_keys

METHODS = ("auto", "pardiso", "superlu", "amg")  #: the linear solvers a caller may name

_SUPPORTS = "Fixed, FixedComponents, Symmetry, ShaftInHole, FreeBody"
_LOADS = "SurfaceForce, Traction, Pressure, BearingLoad, Torque, BoltCircleTorque, Gravity, Inertia"


@dataclass(frozen=True)
class Fixed:
    """All displacement components zero on a named surface."""

    surface: str


@dataclass(frozen=True)
class FixedComponents:
    """Displacement ``components`` (a string of x, y, z) zero on a named surface's nodes, or,
    with ``edge_with``, only on the nodes it shares with that second surface (a line)."""

    surface: str
    components: str
    edge_with: str | None = None


@dataclass(frozen=True)
class Symmetry:
    """Zero normal displacement on a plane surface whose normal is a coordinate axis."""

    surface: str


@dataclass(frozen=True)
class ShaftInHole:
    """Hole wall on an elastic foundation to a fixed rigid shaft; moduli in force/length³."""

    hole: str
    k_radial: float | None = None  #: default E / radius
    k_tangential: float | None = None  #: default 1e-3 k_radial
    k_axial: float | None = None  #: default 1e-3 k_radial
    direction: tuple[float, float, float] | None = None  #: bearing side; None = whole wall


@dataclass(frozen=True)
class FreeBody:
    """No support: only rigid-body motion is removed (self-equilibrated loads)."""


Support = Fixed | FixedComponents | Symmetry | ShaftInHole | FreeBody


@dataclass(frozen=True)
class SurfaceForce:
    """Total force (3,) on a named surface, as uniform traction."""

    surface: str
    force: tuple[float, float, float]


@dataclass(frozen=True)
class Traction:
    """Uniform traction (3,) in MPa (N/mm²) on a named surface; its resultant is traction × area."""

    surface: str
    traction_mpa: tuple[float, float, float]


@dataclass(frozen=True)
class Pressure:
    """Uniform pressure p in MPa (positive into the material) on a named surface."""

    surface: str
    p: float


@dataclass(frozen=True)
class BearingLoad:
    """Pin/bolt force (3,) on a hole, cosine-distributed over the loaded half."""

    hole: str
    force: tuple[float, float, float]


@dataclass(frozen=True)
class Torque:
    """Torque (scalar, right-handed about the hole axis) carried by a bore."""

    hole: str
    torque: float


@dataclass(frozen=True)
class BoltCircleTorque:
    """Torque (scalar, right-handed about the holes' common axis) carried by bolts in holes."""

    holes: tuple[str, ...]
    torque: float


@dataclass(frozen=True)
class Gravity:
    """Gravitational acceleration (3,), e.g. (0, 0, -9810) mm/s²."""

    g: tuple[float, float, float]


@dataclass(frozen=True)
class Inertia:
    """Rigid-body motion: a0 at ``origin`` (3,), angular acceleration α (3,), angular velocity ω (3,)."""

    a0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    alpha: tuple[float, float, float] = (0.0, 0.0, 0.0)
    omega: tuple[float, float, float] = (0.0, 0.0, 0.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)


Load = SurfaceForce | Traction | Pressure | BearingLoad | Torque | BoltCircleTorque | Gravity | Inertia


def vector(name: str, v) -> np.ndarray:
    """``v`` as 3 finite floats; InputError naming ``name`` otherwise."""
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} = {v!r} must be 3 finite numbers") from None
    if a.shape != (3,) or not np.isfinite(a).all():
        raise InputError(f"{name} = {v!r} must be 3 finite numbers")
    return a


def surface(fm, name: str, what: str = "surface", nonempty: bool = False) -> np.ndarray:
    """The triangles of a named surface; InputError listing the mesh's surfaces when it has none
    of that name (or, with ``nonempty``, when the surface has no triangles)."""
    if name not in fm.surfaces:
        raise InputError(f"{what} {name!r} is not in the mesh; available: {', '.join(fm.surfaces) or 'none'}")
    tri = fm.surfaces[name]
    if nonempty and len(tri) == 0:
        raise InputError(f"surface {name!r} is empty")
    return tri


def hole(holes: dict, name: str, what: str = "hole"):
    """The named hole of the part; InputError listing the part's holes when it has none of that name."""
    if name not in holes:
        raise InputError(f"{what} {name!r} is not in the part; available: {', '.join(holes) or 'none'}")
    return holes[name]


def _axis(h) -> np.ndarray:
    return np.asarray(h.axis, float) / np.linalg.norm(h.axis)


def plane_axis(fm, name: str) -> int:
    """The coordinate axis (0, 1, 2) a symmetry surface is normal to; InputError when the
    surface is missing or is not such a plane."""
    tri = surface(fm, name, "symmetry surface")
    x = fm.nodes[tri[:, :3]]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    ax = int(np.argmax(np.abs(n[0])))
    if not np.allclose(np.abs(n[:, ax]), 1.0, atol=1e-6):
        raise InputError(f"symmetry surface {name!r} must be a plane normal to the x, y or z axis")
    return ax


def check_supports(fm, holes: dict, supports: list, E: float) -> None:
    """Every support of ``supports`` names a surface or hole of the mesh and holds valid values;
    the list is not empty and FreeBody() stands alone."""
    if not supports:
        raise InputError("supports: none given; add Fixed/Symmetry/ShaftInHole supports, or FreeBody() "
                         "for a self-equilibrated load set")
    if any(isinstance(s, FreeBody) for s in supports) and len(supports) > 1:
        raise InputError("supports: FreeBody() cannot be combined with other supports")
    for s in supports:
        if isinstance(s, Fixed):
            surface(fm, s.surface)
        elif isinstance(s, FixedComponents):
            comps = str(s.components)
            if not comps or any(c not in "xyz" for c in comps) or len(set(comps)) != len(comps):
                raise InputError(f"FixedComponents({s.surface!r}).components = {s.components!r} must be distinct "
                                 f"letters of 'xyz', e.g. 'xy'")
            nodes = np.unique(surface(fm, s.surface))
            if s.edge_with is not None:
                shared = np.intersect1d(nodes, np.unique(surface(fm, s.edge_with)))
                if len(shared) < 2:
                    raise InputError(f"FixedComponents({s.surface!r}, edge_with={s.edge_with!r}): the surfaces "
                                     f"share {len(shared)} node(s), not a line")
        elif isinstance(s, Symmetry):
            plane_axis(fm, s.surface)
        elif isinstance(s, ShaftInHole):
            h = hole(holes, s.hole, "ShaftInHole: hole")
            surface(fm, s.hole, nonempty=True)
            kr = E / h.radius if s.k_radial is None else s.k_radial
            for nm, v in (("k_radial", kr), ("k_tangential", s.k_tangential), ("k_axial", s.k_axial)):
                if v is not None and not (isinstance(v, (int, float, np.number)) and np.isfinite(v) and v >= 0):
                    raise InputError(f"ShaftInHole({s.hole!r}).{nm} = {v!r} must be finite and >= 0")
            if s.direction is not None:
                a = _axis(h)
                d = vector(f"ShaftInHole({s.hole!r}).direction", s.direction)
                if np.linalg.norm(d - (d @ a) * a) == 0:
                    raise InputError(f"ShaftInHole({s.hole!r}).direction must not be parallel to the hole axis")
        elif not isinstance(s, FreeBody):
            raise InputError(f"supports: {s!r} is not a support ({_SUPPORTS})")


def check_rigid(R: np.ndarray, fixed: np.ndarray, springs: sp.csr_matrix | None) -> None:
    """InputError when the supports (their fixed DOFs and springs) leave one of the rigid-body
    modes ``R`` (3N, 6) (:func:`rigfem.fe.supports.rigid_modes`) free."""
    Q = R[fixed].T @ R[fixed] / max(len(fixed), 1)
    if springs is not None:
        Qs = R.T @ (springs @ R)
        Q = Q + Qs / max(np.abs(np.diag(Qs)).max(), np.finfo(float).tiny)
    ev, V = np.linalg.eigh(Q)
    bad = ev < 1e-12 * max(ev.max(), np.finfo(float).tiny)
    if bad.any():
        names = ["translation x", "translation y", "translation z", "rotation x", "rotation y", "rotation z"]
        modes = [names[int(np.argmax(np.abs(V[:, i])))] for i in np.where(bad)[0]]
        raise InputError(f"supports: insufficient, {bad.sum()} rigid-body mode(s) free (e.g. {', '.join(modes)}); "
                         f"add supports, or FreeBody() for a self-equilibrated load set")


def check_cases(cases: list) -> None:
    """At least one load case."""
    if not cases:
        raise InputError("loads: at least one load case is required")


def check_load(fm, holes: dict, load) -> None:
    """One load names a surface or hole of the mesh and holds finite values of the right shape."""
    if isinstance(load, SurfaceForce):
        vector(f"SurfaceForce({load.surface!r}).force", load.force)
        surface(fm, load.surface, nonempty=True)
    elif isinstance(load, Traction):
        vector(f"Traction({load.surface!r}).traction_mpa", load.traction_mpa)
        surface(fm, load.surface, nonempty=True)
    elif isinstance(load, Pressure):
        try:
            p = float(load.p)
        except (TypeError, ValueError):
            p = float("nan")
        if not np.isfinite(p):
            raise InputError(f"Pressure({load.surface!r}).p = {load.p!r} must be finite")
        surface(fm, load.surface, nonempty=True)
    elif isinstance(load, BearingLoad):
        _bearing(fm, holes, load.hole, vector(f"BearingLoad({load.hole!r}).force", load.force))
    elif isinstance(load, Torque):
        hole(holes, load.hole)
        surface(fm, load.hole, nonempty=True)
    elif isinstance(load, BoltCircleTorque):
        if len(load.holes) < 2:
            raise InputError("BoltCircleTorque.holes must name at least 2 holes")
        axes = [_axis(hole(holes, n)) for n in load.holes]
        for n, a in zip(load.holes, axes):
            surface(fm, n, nonempty=True)
            if np.linalg.norm(np.cross(a, axes[0])) > 1e-9:
                raise InputError(f"BoltCircleTorque.holes: hole {n!r}'s axis {tuple(a)} is not parallel to "
                                 f"hole {load.holes[0]!r}'s {tuple(axes[0])}")
    elif isinstance(load, Gravity):
        vector("Gravity.g", load.g)
    elif isinstance(load, Inertia):
        for k in ("a0", "alpha", "omega", "origin"):
            vector(f"Inertia.{k}", getattr(load, k))
    else:
        raise InputError(f"loads: {load!r} is not a load ({_LOADS})")


def _bearing(fm, holes: dict, name: str, F: np.ndarray) -> None:
    a = _axis(hole(holes, name))
    surface(fm, name, nonempty=True)
    mag = np.linalg.norm(F)
    if mag and abs(F @ a) > 1e-9 * mag:
        raise InputError(f"BearingLoad({name!r}).force must be perpendicular to the hole axis {tuple(a)}; "
                         f"axial component {F @ a:g}")


def check_mesh(mesh, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A PartMesh's points (N, 3) and tets (M, 4) as arrays, with each tet's signed volume, and
    the element order (1 or 2) a script asks :func:`rigfem.fe.build_model` for; InputError for an
    order other than 1 or 2, a malformed, non-finite or out-of-range mesh, degenerate tets, a
    surface triangle that is no tet face or a curved edge that is no tet edge."""
    if order not in (1, 2):
        raise InputError(f"order = {order!r} must be 1 or 2")
    p = np.asarray(mesh.points, dtype=float)
    t = np.asarray(mesh.tets, dtype=np.int64)
    if p.ndim != 2 or p.shape[1] != 3 or t.ndim != 2 or t.shape[1] != 4 or len(t) == 0:
        raise InputError("mesh must have points (N, 3) and tets (M, 4) with M >= 1")
    if t.min() < 0 or t.max() >= len(p) or not np.isfinite(p).all():
        raise InputError(f"mesh tets must index points 0..{len(p) - 1} and points must be finite")
    vol = np.linalg.det(p[t[:, 1:]] - p[t[:, :1]]) / 6
    flat = np.abs(vol) <= 1e-12 * np.abs(vol).max()
    if flat.any():
        raise InputError(f"mesh has {flat.sum()} degenerate (zero-volume) tets")
    _check_on_tets(mesh, t)
    return p, t, vol


def _on(t: np.ndarray, corners: np.ndarray, n: int) -> np.ndarray:
    """Which rows of ``corners`` (vertex sets, K × k) are corner sets of ``t``'s rows (tet faces
    or edges, M × j × k), in any order: only the tet sets whose vertices all lie in ``corners``
    are keyed, so a surface costs a pass over the tets, not a sort of them."""
    used = np.zeros(n, bool)
    used[corners] = True
    cand = t[used[t].all(-1)]
    return np.isin(vertex_set_keys(corners, n), vertex_set_keys(cand, n).ravel())


def _vertices(field: str, v, k: int, n: int) -> np.ndarray:
    """``v`` as an int64 (K, k) array of tet vertices (whole-valued floats accepted, as read by
    np.loadtxt); InputError naming the field, what is wrong and the allowed range."""
    v = np.asarray(v)
    if v.ndim != 2 or v.shape[1] != k:
        raise InputError(f"{field} must be a ({'K' if k == 3 else 'E'}, {k}) array of tet vertices, "
                         f"got shape {v.shape}")
    if v.size == 0:
        return np.zeros((0, k), np.int64)
    if v.dtype.kind not in "iuf":
        raise InputError(f"{field} must hold whole vertex numbers, got {v.dtype} values")
    if v.dtype.kind == "f" and not np.array_equal(v, np.round(v)):
        raise InputError(f"{field} must hold whole vertex numbers, got {v.dtype} values such as "
                         f"{v[v != np.round(v)][0].item()!r}")
    bad = (v < 0) | (v >= n)
    if bad.any():
        raise InputError(f"{field}: vertex {v[bad][0]:g} is not a tet vertex (0..{n - 1})")
    return v.astype(np.int64)


def _check_on_tets(mesh, t: np.ndarray) -> None:
    """Every surface triangle is a face of a tet and every curved edge an edge of one, so the
    FE's face and edge lookups (rigfem.mesh.partmesh: face_owners, quadratic) find them all."""
    from rigfem.mesh.partmesh import TET10_EDGES, TET_FACES

    n = int(t.max()) + 1
    tris = {name: _vertices(f"surface {name!r}", tri, 3, n) for name, tri in mesh.surfaces.items()}
    every = np.vstack([np.zeros((0, 3), np.int64), *tris.values()])
    if len(every) and not (on := _on(t[:, TET_FACES], every, n)).all():  # one pass for all surfaces
        for (name, tri), ok in zip(tris.items(), np.split(on, np.cumsum([len(v) for v in tris.values()])[:-1])):
            if not ok.all():
                raise InputError(f"surface {name!r}: {(~ok).sum()} of its {len(tri)} triangles are not faces "
                                 f"of the mesh's tets (first: vertices {tuple(tri[ok.argmin()].tolist())})")
    e = _vertices("curved_edges", mesh.curved_edges, 2, n) if np.size(mesh.curved_edges) else np.zeros((0, 2), int)
    x = np.asarray(mesh.curved_points)
    x = np.zeros((0, 3)) if x.size == 0 else x
    if x.shape != (len(e), 3) or x.dtype.kind not in "iuf" or not np.isfinite(x).all():
        raise InputError(f"curved_points must be one finite point (x, y, z) per curved edge, ({len(e)}, 3); "
                         f"got {x.dtype} {x.shape}")
    if len(e):
        off = ~_on(t[:, TET10_EDGES], e, n)
        if off.any():
            raise InputError(f"curved_edges: {off.sum()} of {len(e)} are not edges of the mesh's tets "
                             f"(first: vertices {tuple(e[off.argmax()].tolist())})")


def check_solver(method: str) -> None:
    """A linear solver's name is one of :data:`METHODS`."""
    if method not in METHODS:
        raise InputError(f"solver = {method!r} must be one of {METHODS}")


def pardiso_missing() -> None:
    """The caller asked for pardiso where it does not import."""
    raise InputError("solver = 'pardiso' is not available here (pypardiso does not import)")
