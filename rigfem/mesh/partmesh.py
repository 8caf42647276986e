"""The mesh of one part: the one data type shared by meshing, the FE solver and the reports.

Units: mm.  A :class:`PartMesh` is what gmsh produced for a part, reduced to plain
arrays (like meshio's ``Mesh``): the tetrahedra's vertices, the named interface surfaces as
triangles, the geometry of every cylindrical interface (holes, bearing seat) so loads and
supports can attach by name, and the curved edges: the mid-edge nodes of gmsh's second-order
mesh that are off their chords (on the grooves, holes and fillets, and the interior nodes
gmsh moved to keep the elements next to them valid), so P2 elements follow the geometry
instead of faceting it (:func:`quadratic`).

:func:`mesh_part` meshes a part of :mod:`rigfem.rig.parts` in gmsh (OpenCASCADE geometry, HXT
linear tets, one thread so identical input gives an identical mesh): a global ``size_mm`` and a
Distance/Threshold field that grades down to ``local_size_mm`` at the surface groups that carry
load (``MeshSettings.refine``), coarse elsewhere.  Before meshing it estimates the element count
and the memory of the mesh and of a direct P2 solve on it and refuses requests above the
machine (24 GiB), first from the part's dimensions before gmsh starts; gmsh runs in a child
process that a signal ends at once (:mod:`rigfem.mesh.worker`); after meshing it reports gmsh's minSICN quality (min, p01, p05, median) and
refuses a mesh below ``min_quality``; then makes the mesh second order (:func:`second_order`).
Results are cached as .npz in verified cache entries (:mod:`rigfem.cache`), keyed by the
part definition, the settings, the gmsh version and the meshing code.
The FE solver builds P2 from :func:`quadratic`; :func:`write_mesh` exports .vtu/.msh (tetra or
tetra10).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rigfem.errors import ComputeError
from rigfem.files import whole_file


@dataclass(frozen=True)
class Hole:
    """A cylindrical interface surface of a part (screw hole, pivot hole, bearing seat)."""

    center: np.ndarray  #: (3,) mm, point on the axis at mid-depth of the cylinder
    axis: np.ndarray  #: (3,) unit vector along the cylinder axis
    radius: float  #: mm
    depth: float  #: mm, axial length of the cylindrical surface


@dataclass
class PartMesh:
    """Linear tetrahedral mesh of one part with its named interface surfaces."""

    name: str
    points: np.ndarray  #: (N, 3) float, mm
    tets: np.ndarray  #: (M, 4) int, 0-based, positively oriented
    surfaces: dict[str, np.ndarray] = field(default_factory=dict)  #: group name -> (K, 3) triangles
    holes: dict[str, Hole] = field(default_factory=dict)  #: group name -> cylinder geometry
    quality: dict[str, float] = field(default_factory=dict)  #: e.g. {"min": .., "p01": .., "median": ..}
    meta: dict = field(default_factory=dict)  #: part parameters, mesh settings, content hash
    #: edges whose P2 node is off its chord (:func:`second_order`): vertex pairs (E, 2), nodes (E, 3)
    curved_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    curved_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


def fit_cylinder(points: np.ndarray, tris: np.ndarray, rtol: float = 1e-3) -> Hole | None:
    """The cylinder through the vertices of a triangulated surface, or None if it is not one.

    Start: axis orthogonal to the face normals (smallest eigenvector of sum n n^T), circle by
    a linear (Kasa) fit in the plane normal to it; then a least-squares fit of the distances
    to the axis.  Rejected if the surface is flat or a vertex lies off by more than rtol*r.
    """
    from scipy.optimize import least_squares

    p = points[tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    w, v = np.linalg.eigh(n.T @ n)
    if w[1] < 0.05 * w.sum() or w[0] > 0.2 * w.sum():  # flat, or normals spread in 3-D
        return None
    a0 = v[:, 0]
    q = points[np.unique(tris)]
    e1 = np.cross(a0, [1.0, 0, 0] if abs(a0[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a0, e1)
    x, y = q @ e1, q @ e2
    sol, *_ = np.linalg.lstsq(np.c_[2 * x, 2 * y, np.ones_like(x)], x**2 + y**2, rcond=None)
    r0 = np.sqrt(sol[2] + sol[0] ** 2 + sol[1] ** 2)

    def axis_point(z):
        a = a0 + z[0] * e1 + z[1] * e2
        return a / np.linalg.norm(a), (sol[0] + z[2]) * e1 + (sol[1] + z[3]) * e2

    def residual(z):
        a, c = axis_point(z)
        return np.linalg.norm(np.cross(q - c, a), axis=1) - z[4]

    fit = least_squares(residual, [0, 0, 0, 0, r0], x_scale=[1, 1, r0, r0, r0], xtol=1e-14, ftol=1e-14)
    a, c = axis_point(fit.x)
    r = float(fit.x[4])
    if r <= 0 or np.abs(fit.fun).max() > rtol * r:
        return None
    a = a * np.sign(a[np.argmax(np.abs(a))])
    t = (q - c) @ a
    return Hole(c + a * (t.min() + t.max()) / 2, a, r, float(t.max() - t.min()))


def quality_summary(q: np.ndarray) -> dict[str, float]:
    """Minimum, 1st and 5th percentile and median of per-tet quality values."""
    return {"min": float(q.min()), "p01": float(np.percentile(q, 1)),
            "p05": float(np.percentile(q, 5)), "median": float(np.median(q))}


def save_npz(pm: PartMesh, path: Path) -> None:
    """Store a PartMesh as .npz (atomic: written to a temporary name, then renamed)."""
    arrays = {"points": pm.points, "tets": pm.tets, "curved_edges": pm.curved_edges,
              "curved_points": pm.curved_points}
    arrays |= {f"surf:{k}": v for k, v in pm.surfaces.items()}
    arrays |= {f"hole:{k}": np.concatenate([h.center, h.axis, [h.radius, h.depth]])
               for k, h in pm.holes.items()}
    arrays["json"] = np.array(json.dumps({"name": pm.name, "quality": pm.quality, "meta": pm.meta}))
    path.parent.mkdir(parents=True, exist_ok=True)
    with whole_file(path) as tmp:
        np.savez_compressed(tmp, **arrays)


def load_npz(source: Path | bytes | bytearray) -> PartMesh:
    """Read a PartMesh written by :func:`save_npz` (from a file, or its bytes)."""
    with np.load(io.BytesIO(source) if isinstance(source, (bytes, bytearray)) else source) as z:
        info = json.loads(str(z["json"]))
        surfaces = {k[5:]: z[k] for k in z.files if k.startswith("surf:")}
        holes = {k[5:]: Hole(z[k][:3].copy(), z[k][3:6].copy(), float(z[k][6]), float(z[k][7]))
                 for k in z.files if k.startswith("hole:")}
        return PartMesh(info["name"], z["points"], z["tets"], surfaces, holes, info["quality"], info["meta"],
                        z["curved_edges"], z["curved_points"])


TET10_EDGES = np.array([[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]])  #: VTK/meshio tetra10 order


TRI6_EDGES = np.array([[0, 1], [1, 2], [2, 0]])
#: corner nodes of a tetrahedron's four faces, in CalculiX's face order (S1..S4)
TET_FACES = np.array([[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]])
#: the corner opposite each face of TET_FACES
TET_FACE_OPPOSITE = np.array([3, 2, 0, 1])


def boundary_faces(tets: np.ndarray) -> np.ndarray:
    """Triangles (K, 3) that belong to exactly one tetrahedron, outward for positive tets."""
    f = np.vstack([tets[:, face[::-1]] for face in TET_FACES])
    _, idx, cnt = np.unique(np.sort(f, axis=1), axis=0, return_index=True, return_counts=True)
    return f[idx[cnt == 1]]


def face_owners(tets: np.ndarray, tris: np.ndarray, what: str = "surface") -> tuple[np.ndarray, np.ndarray]:
    """Element index and face number (0..3, :data:`TET_FACES` order) of each triangle (K, >=3).

    ComputeError naming ``what`` if a triangle is not a face of the mesh (a script's own mesh is
    judged at the edge: rigfem.fe.inputs.check_mesh).
    """
    tris = np.asarray(tris)
    if tris.ndim != 2 or tris.shape[1] < 3 or len(tris) == 0:
        raise ComputeError(f"{what} triangles must be a non-empty (K, 3) or (K, 6) array, got {tris.shape}")
    m = max(int(tets[:, :4].max()), int(tris[:, :3].max())) + 1
    faces = vertex_set_keys(tets[:, TET_FACES], m).ravel()  # row 4e + f
    order = np.argsort(faces)
    key = vertex_set_keys(tris[:, :3], m)
    pos = np.searchsorted(faces[order], key).clip(0, len(faces) - 1)
    if not np.array_equal(faces[order][pos], key):
        raise ComputeError(f"{what} has triangles that are not faces of the mesh")
    idx = order[pos]
    return idx // 4, idx % 4


def vertex_set_keys(corners: np.ndarray, n: int) -> np.ndarray:
    """One key per vertex set of a mesh of ``n`` points (the last axis of ``corners``, in any
    order): the sorted set as an int64 in base n (an edge (a, b), a < b: a·n + b), or its bytes
    where that would overflow (triangles of more than 2 million points)."""
    c = np.sort(np.asarray(corners), axis=-1).astype(np.int64)
    k = c.shape[-1]
    if n**k >= 2**63:
        return np.ascontiguousarray(c).view(np.dtype((np.void, 8 * k)))[..., 0]
    return c @ (np.int64(n) ** np.arange(k - 1, -1, -1, dtype=np.int64))


def quadratic(pm: PartMesh) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """P2 nodes, tetra10 elements (M, 10) and triangle6 groups of a mesh (VTK / C3D10 order).

    Nodes are the vertices, then one node per edge: at ``pm.curved_points`` for the edges of
    ``pm.curved_edges``, at the straight midpoint elsewhere.
    """
    points, tets = np.asarray(pm.points, float), np.asarray(pm.tets, np.int64)
    n = len(points)
    ukeys, inv = np.unique(vertex_set_keys(tets[:, TET10_EDGES], n), return_inverse=True)
    mid = 0.5 * (points[ukeys // n] + points[ukeys % n])

    def lookup(pairs: np.ndarray, what: str) -> np.ndarray:
        k = vertex_set_keys(pairs, n)
        pos = np.searchsorted(ukeys, k).clip(0, len(ukeys) - 1)
        if not (ukeys[pos] == k).all():
            raise ComputeError(f"{what} has edges that are not tet edges of the mesh")
        return pos

    if len(pm.curved_edges):
        mid[lookup(np.asarray(pm.curved_edges, np.int64), "curved_edges")] = pm.curved_points
    surfaces = {name: np.hstack([tri, n + lookup(np.asarray(tri, np.int64)[:, TRI6_EDGES], f"surface {name!r}")])
                for name, tri in pm.surfaces.items()}
    return np.vstack([points, mid]), np.hstack([tets, n + inv.reshape(-1, 6)]), surfaces


def to_meshio(pm: PartMesh, order: int = 1):
    """meshio.Mesh of the part: tets plus one triangle block per named surface.

    ``order=2`` writes tetra10/triangle6 with the mid-edge nodes of :func:`quadratic` (on the
    geometry where the boundary is curved).
    """
    import meshio

    if order not in (1, 2):  # the CLI's --order offers 1 and 2 only
        raise ComputeError(f"order = {order!r} must be 1 or 2")
    if order == 2:
        points, tets, surfaces = quadratic(pm)
    else:
        points, tets = np.asarray(pm.points, float), np.asarray(pm.tets, np.int64)
        surfaces = {k: np.asarray(v, np.int64) for k, v in pm.surfaces.items()}
    tet_t, tri_t = ("tetra", "triangle") if order == 1 else ("tetra10", "triangle6")
    names = sorted(surfaces)
    cells = [(tet_t, tets)] + [(tri_t, surfaces[k]) for k in names]
    ids = [np.full(len(tets), len(names) + 1)] + [np.full(len(surfaces[k]), i + 1) for i, k in enumerate(names)]
    field_data = {k: np.array([i + 1, 2]) for i, k in enumerate(names)}
    field_data[pm.name] = np.array([len(names) + 1, 3])
    return meshio.Mesh(points, cells, cell_data={"gmsh:physical": ids, "gmsh:geometrical": ids},
                       field_data=field_data)


def write_mesh(pm: PartMesh, path: str | Path, order: int = 1) -> None:
    """Write .vtu or .msh (gmsh 2.2 format, physical names kept) through meshio."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".vtu", ".msh"):  # the CLI's --out is checked so (rigfem.cli.outputs.new_output)
        raise ComputeError(f"--out {path}: file type must be .vtu or .msh")
    mesh = to_meshio(pm, order)
    with whole_file(path) as tmp:
        if suffix == ".msh":
            mesh.write(tmp, file_format="gmsh22", binary=False)
        else:
            mesh.write(tmp, file_format="vtu")
