"""Supports: fixed surfaces, fixed components, symmetry planes, a shaft in a hole, free-body mode.

:class:`FixedComponents` holds chosen displacement components at zero on a named surface or,
with ``edge_with``, only on the line of nodes it shares with a second surface (the standard
benchmarks' "u_z = 0 along the mid-plane edge", NAFEMS LE10).

How rigfem models a shaft in a hole (:class:`ShaftInHole`): the hole wall rests
on an elastic foundation that connects it to a rigid, fixed shaft.  Springs per
unit area act in the local radial, tangential and axial directions.  The radial
modulus defaults to E/r (the contact stiffness of a steel shaft of radius r,
order of magnitude), the tangential and axial ones to 1e-3 of it, so the shaft
carries radial load like a pin and only weakly resists rotation about, and
sliding along, its axis (those reactions are reported: they should be small).
With ``direction`` set, radial springs act only on the half of the wall facing
that direction (the side the shaft bears on).  Unlike clamping every node of
the hole, the support traction is bounded, so it adds no stress singularity
at the hole edges; the peak converges under mesh refinement.

Free-body mode (:class:`FreeBody`) removes only the six rigid-body modes by a
statically determinate 3-2-1 support on three far-apart nodes; for a
self-equilibrated load set its six reactions are ≈ 0 (reported), and the rigid
motion is projected out of the displacement afterwards.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from rigfem.errors import ComputeError
from rigfem.fe.assembly import (
    FEMesh,
    _scatter,
    element_dofs,
    shape_dL,
    shape_values,
    tri_quadrature,
)
from rigfem.fe.inputs import (  # noqa: F401  the supports a user states (re-exported here)
    Fixed, FixedComponents, FreeBody, ShaftInHole, Support, Symmetry, check_rigid, check_supports, plane_axis,
)
from rigfem.mesh.partmesh import Hole




def surface_quadrature(fm: FEMesh, name: str, degree: int, normals: bool = False):
    """Points (K, nq, 3), weights·area (K, nq), shape values (nq, nloc), nodes (K, nloc) of a
    surface, and with ``normals`` unit normals (K, nq, 3) (orientation: (x1−x0)×(x2−x0)).

    6-node triangles are mapped isoparametrically, so a curved triangle's points, area and
    normals are those of its curved shape.  Kept in the mesh's cache: a hole's bearing loads in
    every direction integrate over the same points.
    """
    key = ("surface_quadrature", name, degree, normals)
    if key not in fm.cache:
        fm.cache[key] = _surface_quadrature(fm, name, degree, normals)
    return fm.cache[key]


def _triangles(fm: FEMesh, name: str) -> np.ndarray:
    """A named surface's triangles: the name passed :mod:`rigfem.fe.inputs` (the supports' and
    loads' check), so a missing one is a bug."""
    if name not in fm.surfaces:
        raise ComputeError(f"surface {name!r} is not in the mesh (a name the supports' and loads' check "
                           f"did not see); available: {', '.join(fm.surfaces) or 'none'}")
    return fm.surfaces[name]


def _surface_quadrature(fm: FEMesh, name: str, degree: int, normals: bool):
    tri = _triangles(fm, name)
    assert len(tri), f"surface {name!r} is empty (rigfem.fe.inputs refuses it)"
    L, W = tri_quadrature(degree)
    x = fm.nodes[tri]
    N = shape_values(L, fm.order)
    dL = shape_dL(L, fm.order)
    t = np.einsum("qak,Kad->Kqkd", dL[..., 1:] - dL[..., :1], x)  # tangents ∂x/∂ξ1, ∂x/∂ξ2
    nv = np.cross(t[:, :, 0], t[:, :, 1])
    area2 = np.linalg.norm(nv, axis=-1)
    out = (np.einsum("qa,kad->kqd", N, x), area2 * W[None, :], N, tri)
    return out + (nv / area2[..., None],) if normals else out


def surface_nodes(fm: FEMesh, name: str) -> np.ndarray:
    """Unique node ids of a named surface (a name checked by :mod:`rigfem.fe.inputs`)."""
    return np.unique(_triangles(fm, name))


def component_dofs(fm: FEMesh, s: FixedComponents) -> np.ndarray:
    """The DOFs a :class:`FixedComponents` support holds at zero (its components and its line
    checked by :func:`rigfem.fe.inputs.check_supports`)."""
    comps = str(s.components)
    nodes = surface_nodes(fm, s.surface)
    if s.edge_with is not None:
        nodes = np.intersect1d(nodes, surface_nodes(fm, s.edge_with))
    return (3 * nodes[:, None] + np.array(["xyz".index(c) for c in comps])).ravel()


def rigid_modes(x: np.ndarray) -> np.ndarray:
    """Rigid-body modes (3N, 6) about the centroid; rotations scaled by the body size."""
    c = x - x.mean(0)
    s = max(np.abs(c).max(), np.finfo(float).tiny)
    c = c / s
    R = np.zeros((len(x), 3, 6))
    R[:, [0, 1, 2], [0, 1, 2]] = 1.0
    R[:, 1, 3], R[:, 2, 3] = -c[:, 2], c[:, 1]
    R[:, 0, 4], R[:, 2, 4] = c[:, 2], -c[:, 0]
    R[:, 0, 5], R[:, 1, 5] = -c[:, 1], c[:, 0]
    return R.reshape(-1, 6)


def shaft_terms(fm: FEMesh, hole: Hole, s: ShaftInHole, E: float) -> tuple[np.ndarray, ...]:
    """The elastic foundation of a shaft in a hole at each quadrature point of the wall.

    Returns points (K, nq, 3), spring moduli (K, nq, 3) in the radial, tangential and axial
    directions, those directions (K, nq, 3, 3), weights·area (K, nq), shape values (nq, nloc)
    and the wall's nodes (K, nloc).  :func:`shaft_springs` assembles them; the CalculiX export
    writes the same terms as springs.
    """
    kr = E / hole.radius if s.k_radial is None else s.k_radial
    kt = 1e-3 * kr if s.k_tangential is None else s.k_tangential
    ka = 1e-3 * kr if s.k_axial is None else s.k_axial
    assert all(np.isfinite(v) and v >= 0 for v in (kr, kt, ka)), f"ShaftInHole({s.hole!r}): moduli unchecked"
    pts, w, N, tri = surface_quadrature(fm, s.hole, 4)
    a = np.asarray(hole.axis, float) / np.linalg.norm(hole.axis)
    d = pts - np.asarray(hole.center, float)
    rad = d - (d @ a)[..., None] * a
    n = rad / np.linalg.norm(rad, axis=-1, keepdims=True)
    t = np.cross(a, n)
    krq = np.full(w.shape, kr)
    if s.direction is not None:
        dirn = np.asarray(s.direction, float)
        dirn = dirn - (dirn @ a) * a
        if np.linalg.norm(dirn) == 0:
            raise ComputeError(f"ShaftInHole({s.hole!r}).direction is parallel to the hole axis "
                               f"(rigfem.fe.inputs.check_supports refuses it)")
        krq = np.where(n @ dirn > 0, kr, 0.0)
    k = np.stack([krq, np.full(w.shape, kt), np.full(w.shape, ka)], -1)
    dirs = np.stack([n, t, np.broadcast_to(a, n.shape)], -2)
    return pts, k, dirs, w, N, tri


def shaft_springs(fm: FEMesh, hole: Hole, s: ShaftInHole, E: float) -> sp.csr_matrix:
    """Stiffness of the elastic foundation of a shaft in a hole."""
    _, k, dirs, w, N, tri = shaft_terms(fm, hole, s, E)
    S = np.einsum("kqd,kqdi,kqdj->kqij", k, dirs, dirs)
    Ke = np.einsum("kq,qa,qb,kqij->kaibj", w, N, N, S, optimize=True)
    n = Ke.shape[1] * 3
    return _scatter(element_dofs(tri), Ke.reshape(-1, n, n), fm.ndof)


def three_two_one(x: np.ndarray) -> np.ndarray:
    """Six DOFs of a statically determinate 3-2-1 support on three far-apart nodes."""
    c = x.mean(0)
    A = int(np.argmax(np.linalg.norm(x - c, axis=1)))
    B = int(np.argmax(np.linalg.norm(x - x[A], axis=1)))
    ab = x[B] - x[A]
    d = x - x[A]
    C = int(np.argmax(np.linalg.norm(np.cross(d, ab), axis=1)))
    e = np.cross(ab, x[C] - x[A])  # motion of C under a rotation about AB
    kb = [k for k in range(3) if k != int(np.argmax(np.abs(ab)))]
    kc = int(np.argmax(np.abs(e)))
    return np.array([3 * A, 3 * A + 1, 3 * A + 2, 3 * B + kb[0], 3 * B + kb[1], 3 * C + kc])


def constraints(fm: FEMesh, holes: dict[str, Hole], supports: list, E: float):
    """Fixed DOFs, spring matrix (or None) and per-support DOF sets of a user's ``supports``:
    checked first by :func:`rigfem.fe.inputs.check_supports` (names against the mesh, values),
    then for rigid-body modes left free (:func:`rigfem.fe.inputs.check_rigid`)."""
    check_supports(fm, holes, supports, E)
    fixed, springs, groups = [], None, {}
    for s in supports:
        if isinstance(s, Fixed):
            dofs = (3 * surface_nodes(fm, s.surface)[:, None] + np.arange(3)).ravel()
            groups[f"Fixed({s.surface})"] = dofs
        elif isinstance(s, FixedComponents):
            dofs = component_dofs(fm, s)
            edge = f", edge_with={s.edge_with}" if s.edge_with else ""
            groups[f"FixedComponents({s.surface}, {s.components}{edge})"] = dofs
        elif isinstance(s, Symmetry):
            ax = plane_axis(fm, s.surface)
            dofs = 3 * surface_nodes(fm, s.surface) + ax
            groups[f"Symmetry({s.surface})"] = dofs
        elif isinstance(s, ShaftInHole):
            Ks = shaft_springs(fm, holes[s.hole], s, E)
            springs = Ks if springs is None else springs + Ks
            groups[f"ShaftInHole({s.hole})"] = (3 * surface_nodes(fm, s.hole)[:, None] + np.arange(3)).ravel()
            continue
        elif isinstance(s, FreeBody):
            dofs = three_two_one(fm.nodes[:fm.n_vertices])
            groups["FreeBody(3-2-1)"] = dofs
        else:
            raise ComputeError(f"supports: {s!r} is not a support (check_supports passed it)")
        fixed.append(dofs)
    fixed = np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, dtype=np.int64)
    check_rigid(rigid_modes(fm.nodes), fixed, springs)
    return fixed, springs, groups

