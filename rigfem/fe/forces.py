"""Loads on named surfaces and holes, and body forces, as consistent nodal vectors.

Every load is a small frozen dataclass; :func:`load_vector` turns it into the
consistent nodal force vector (length 3·nodes) of a model.  Forces act *on*
the part.

* :class:`SurfaceForce` — a total force (N) spread as uniform traction.
* :class:`Traction` — a uniform traction vector in MPa (N/mm², force per area) on a
  surface: the load as an engineer states a stress (σ on an end face).
* :class:`Pressure` — uniform pressure p in MPa on a surface (traction −p·n, n the
  outward normal; p > 0 pushes into the material).
* :class:`BearingLoad` — a pin/bolt pushing on a hole with force F: normal
  pressure p0·cos θ over the half of the wall the pin pushes on (θ measured from
  F).  Tiny cosine corrections cancel the discretisation error, so the discrete
  resultant is exactly F through the hole centre (no moment).  F must be
  perpendicular to the hole axis.
* :class:`Torque` — a torque about a bore's axis as uniform shear on the wall
  (discrete moment exactly T about the axis, no other resultant).
* :class:`BoltCircleTorque` — a torque carried by bolts in several holes: each
  bolt bears ``F_i = T·(a × r_i)/Σ|r_i|²`` (r_i from the bolt-circle centre).
* :class:`Gravity` — body force ρ·g.
* :class:`Inertia` — d'Alembert body force of a rigid-body motion.  A point at
  r (from ``origin``) has acceleration a = a0 + α×r + ω×(ω×r), which for plane
  motion is a0 + α×r − ω²r; the load applied is **−ρ·a**, so the joint forces
  on the bar plus this load are in equilibrium (bar analysed free, in dynamic
  equilibrium).  Units: accelerations in mm/s² with ρ in t/mm³ give N/mm³.
"""

from __future__ import annotations

import numpy as np

from rigfem.errors import ComputeError
from rigfem.fe.assembly import FEMesh, geometry, points_at, shape_values, tet_quadrature
from rigfem.fe.inputs import (  # noqa: F401  the loads a user states (re-exported here)
    BearingLoad, BoltCircleTorque, Gravity, Inertia, Load, Pressure, SurfaceForce, Torque, Traction, check_load,
)
from rigfem.fe.supports import surface_quadrature
from rigfem.mesh.partmesh import TET_FACE_OPPOSITE, Hole, face_owners


def _vec(name: str, v) -> np.ndarray:
    """A load's vector, 3 finite numbers (:func:`rigfem.fe.inputs.check_load` checked it)."""
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ComputeError(f"{name} = {v!r} is not 3 finite numbers (a load check_load did not see)")
    return a




def _assemble_surface(fm: FEMesh, name: str, traction, degree: int) -> np.ndarray:
    """∫ N t dA for traction(points (K, nq, 3)) -> (K, nq, 3)."""
    pts, w, N, tri = surface_quadrature(fm, name, degree)
    fe = np.einsum("kq,qa,kqi->kai", w, N, traction(pts))
    f = np.zeros(fm.ndof)
    np.add.at(f, (3 * tri[:, :, None] + np.arange(3)).ravel(), fe.ravel())
    return f


def outward_normals(fm: FEMesh, name: str, degree: int = 1) -> np.ndarray:
    """Unit outward normals (K, nq, 3) of a named surface at the points of the degree's rule
    (of the curved surface where its triangles are curved)."""
    *_, tri, normals = surface_quadrature(fm, name, degree, normals=True)
    tri = tri[:, :3]
    elem, face = face_owners(fm.elements, tri, f"surface {name!r}")
    opposite = fm.nodes[fm.elements[elem, TET_FACE_OPPOSITE[face]]]  # vertex not on the face
    x = fm.nodes[tri]
    return normals * np.sign(np.einsum("kqd,kd->kq", normals, x[:, 0] - opposite))[..., None]


def _resultant(fm: FEMesh, f: np.ndarray, about: np.ndarray, nodes=slice(None)) -> tuple[np.ndarray, np.ndarray]:
    """Force and moment about ``about`` of the nodal vector f, loaded at ``nodes`` only."""
    F = f.reshape(-1, 3)[nodes]
    return F.sum(0), np.cross(fm.nodes[nodes] - about, F).sum(0)


def _hole(holes: dict[str, Hole], name: str) -> tuple[Hole, np.ndarray]:
    """The hole and its unit axis (a name :func:`rigfem.fe.inputs.check_load` checked)."""
    if name not in holes:
        raise ComputeError(f"hole {name!r} is not in the part (a name check_load did not see)")
    h = holes[name]
    return h, np.asarray(h.axis, float) / np.linalg.norm(h.axis)


def bearing_vector(fm: FEMesh, holes: dict[str, Hole], name: str, force) -> np.ndarray:
    """Nodal vector of a cosine bearing pressure whose resultant is ``force`` (perpendicular to
    the hole's axis: :func:`rigfem.fe.inputs.check_load` holds a user's BearingLoad to it, a bolt
    circle's bearings are so by construction)."""
    F = _vec(f"BearingLoad({name!r}).force", force)
    h, a = _hole(holes, name)
    mag = np.linalg.norm(F)
    if mag == 0:
        return np.zeros(fm.ndof)
    assert abs(F @ a) <= 1e-9 * mag, f"BearingLoad({name!r}).force has an axial component {F @ a:g}"
    e = F / mag
    c = np.asarray(h.center, float)
    return _exact(fm, name, c, a, _cosine(fm, name, c, a, e, h.depth), e, np.concatenate([F, np.zeros(3)]))


def _cosine(fm: FEMesh, name: str, c: np.ndarray, a: np.ndarray, d: np.ndarray, depth: float,
            axial: bool = False) -> np.ndarray:
    """Nodal vector of the normal pressure max(cos θ, 0) on a hole wall, θ from direction d.

    With ``axial`` the pressure is weighted by the axial coordinate (x − c)·a / depth.
    """
    def traction(x):
        r = x - c
        z = r @ a
        r = r - z[..., None] * a
        r = r / np.linalg.norm(r, axis=-1, keepdims=True)
        w = np.maximum(r @ d, 0.0) * (z / depth if axial else 1.0)
        return w[..., None] * r
    return _assemble_surface(fm, name, traction, 6)


def _exact(fm: FEMesh, name: str, c: np.ndarray, a: np.ndarray, f0: np.ndarray, e: np.ndarray,
           target: np.ndarray) -> np.ndarray:
    """f0 plus tiny cosine pressures so the discrete force and moment about c equal ``target`` (6,) exactly.

    ``e`` is the in-plane direction of f0's force (bearing) or any in-plane direction
    (torque, whose f0 has no force).  The corrections only cancel the discretisation
    error of f0 on an unsymmetric surface mesh.
    """
    e2 = np.cross(a, e)
    on = np.unique(fm.surfaces[name])  # the only loaded nodes
    depth = max(np.ptp((fm.nodes[on] - c) @ a), np.finfo(float).tiny)
    fs = [f0, _cosine(fm, name, c, a, e2, depth), _cosine(fm, name, c, a, e, depth, True),
          _cosine(fm, name, c, a, e2, depth, True)]
    z = np.zeros(3)
    rows = [np.r_[e, z], np.r_[e2, z], np.r_[z, e], np.r_[z, e2]]
    if np.linalg.norm(target[:3]) == 0:  # torque: also cancel the force along e
        fs.append(_cosine(fm, name, c, a, e, depth))
        rows.append(np.r_[z, a])
    rows = np.array(rows)
    R = np.array([np.concatenate(_resultant(fm, f, c, on)) for f in fs]).T  # (6, n)
    k = np.linalg.solve(rows @ R, rows @ target)
    return sum(ki * fi for ki, fi in zip(k, fs))


def torque_vector(fm: FEMesh, holes: dict[str, Hole], name: str, torque: float) -> np.ndarray:
    """Nodal vector of uniform shear on a bore: moment ``torque`` about the axis, no other resultant."""
    h, a = _hole(holes, name)
    c = np.asarray(h.center, float)

    def traction(x):
        d = x - c
        r = d - (d @ a)[..., None] * a
        return np.cross(a, r / np.linalg.norm(r, axis=-1, keepdims=True))

    e = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    return _exact(fm, name, c, a, _assemble_surface(fm, name, traction, 4), e / np.linalg.norm(e),
                  np.concatenate([np.zeros(3), float(torque) * a]))


def body_vector(fm: FEMesh, density: float, accel) -> np.ndarray:
    """∫ N ρ b dV for a body acceleration field accel(points (M, nq, 3)) -> (M, nq, 3)."""
    if "body" not in fm.cache:  # the same quadrature for every body load of a mesh
        L, W = tet_quadrature(3)
        fm.cache["body"] = (geometry(fm, L, grads=False)[1] * W, shape_values(L, fm.order), points_at(fm, L))
    dw, N, pts = fm.cache["body"]
    fe = np.einsum("mq,qa,mqi->mai", density * dw, N, accel(pts), optimize=True)
    return np.bincount((3 * fm.elements[:, :, None] + np.arange(3)).ravel(), fe.ravel(), minlength=fm.ndof)


def body_basis(fm: FEMesh, density: float) -> np.ndarray:
    """Body-force vectors (3N, 12) of the 12 fields every rigid-body acceleration combines:
    a constant acceleration along each axis, then the fields ``(x_j − c_j) e_i`` (column
    3 + 3i + j, c the node centroid).  Built once per mesh and density, so a model's many
    unit inertia loads cost a matrix product each, not a body-force assembly each."""
    key = ("body basis", float(density))
    if key not in fm.cache:
        c = fm.nodes.mean(0)
        eye = np.eye(3)
        cols = [body_vector(fm, density, lambda x, e=e: np.broadcast_to(e, x.shape)) for e in eye]
        cols += [body_vector(fm, density, lambda x, i=i, j=j: (x[..., j] - c[j])[..., None] * eye[i])
                 for i in range(3) for j in range(3)]
        fm.cache[key] = (np.stack(cols, axis=1), c)
    return fm.cache[key]


def body_coefficients(load, centroid: np.ndarray) -> np.ndarray | None:
    """The 12 weights of :func:`body_basis` that give a Gravity or Inertia load, or None for
    another load.  A rigid motion's acceleration is a(x) = a0 + M (x − o) with
    M = [α]× + ωωᵀ − |ω|² I; the applied field is −a(x) = −(a0 + M (c − o)) − M (x − c)."""
    if isinstance(load, Gravity):
        return np.r_[_vec("Gravity.g", load.g), np.zeros(9)]
    if not isinstance(load, Inertia):
        return None
    a0, al, om, o = (_vec(f"Inertia.{k}", getattr(load, k)) for k in ("a0", "alpha", "omega", "origin"))
    cross = np.array([[0.0, -al[2], al[1]], [al[2], 0.0, -al[0]], [-al[1], al[0], 0.0]])
    M = cross + np.outer(om, om) - (om @ om) * np.eye(3)  # a(x) = a0 + M (x − o)
    return -np.r_[a0 + M @ (centroid - o), M.ravel()]


def load_vector(fm: FEMesh, holes: dict[str, Hole], density: float, load) -> np.ndarray:
    """Consistent nodal force vector (3N,) of one load (checked first against the mesh and the
    part's holes by :func:`rigfem.fe.inputs.check_load`: a user's script calls this)."""
    check_load(fm, holes, load)
    return nodal_vector(fm, holes, density, load)


def nodal_vector(fm: FEMesh, holes: dict[str, Hole], density: float, load) -> np.ndarray:
    """:func:`load_vector` of a load already checked (:func:`rigfem.fe.model.load_matrix` checks
    its cases once)."""
    if isinstance(load, SurfaceForce):
        F = _vec(f"SurfaceForce({load.surface!r}).force", load.force)
        pts, w, _, _ = surface_quadrature(fm, load.surface, 2)
        return _assemble_surface(fm, load.surface, lambda x: np.broadcast_to(F / w.sum(), x.shape), 2)
    if isinstance(load, Traction):
        t = _vec(f"Traction({load.surface!r}).traction_mpa", load.traction_mpa)
        return _assemble_surface(fm, load.surface, lambda x: np.broadcast_to(t, x.shape), 2)
    if isinstance(load, Pressure):
        p = float(load.p)
        n = outward_normals(fm, load.surface, 2)
        return _assemble_surface(fm, load.surface, lambda x: -p * n, 2)
    if isinstance(load, BearingLoad):
        return bearing_vector(fm, holes, load.hole, load.force)
    if isinstance(load, Torque):
        return torque_vector(fm, holes, load.hole, load.torque)
    if isinstance(load, BoltCircleTorque):
        hs = [_hole(holes, n) for n in load.holes]
        a = hs[0][1]
        c = np.mean([np.asarray(h.center, float) for h, _ in hs], axis=0)
        r = [np.asarray(h.center, float) - c for h, _ in hs]
        r = [ri - (ri @ a) * a for ri in r]
        s = sum(ri @ ri for ri in r)
        return sum(bearing_vector(fm, holes, n, float(load.torque) * np.cross(a, ri) / s)
                   for n, ri in zip(load.holes, r))
    if isinstance(load, Gravity):
        g = _vec("Gravity.g", load.g)
        return body_vector(fm, density, lambda x: np.broadcast_to(g, x.shape))
    if isinstance(load, Inertia):
        a0, al, om, o = (_vec(f"Inertia.{k}", getattr(load, k)) for k in ("a0", "alpha", "omega", "origin"))

        def minus_accel(x):
            r = x - o
            return -(a0 + np.cross(al, r) + np.cross(om, np.cross(om, r)))
        return body_vector(fm, density, minus_accel)
    raise ComputeError(f"loads: {load!r} is not a load (check_load passed it)")
