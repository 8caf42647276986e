"""Quadratic/linear tetrahedral meshes and a fast vectorised elasticity stiffness.

The P2 mesh adds one node per edge (:func:`rigfem.mesh.partmesh.quadratic`): where gmsh's second-order
mesh puts it for the curved edges (on the geometry at grooves, holes and fillets, moved
elastically beside them), at the midpoint elsewhere.  Elements with such a node are *curved*
(isoparametric): their Jacobian varies inside, so gradients and volume weights are
computed per quadrature point; all others are affine.  A curved element whose Jacobian falls
below :data:`MIN_JACOBIAN` of its straight shape anywhere is straightened (mid-nodes back to
the chords) rather than left distorted.  Element node order is CalculiX C3D10 / VTK
``tetra10`` (0-based): corners 0-3, then edges 0-1, 1-2, 2-0, 0-3, 1-3, 2-3.  Global DOF
``3*node + c`` (c = x, y, z).

>>> import numpy as np
>>> from skfem import MeshTet
>>> from rigfem.mesh import PartMesh
>>> m = MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 3)
>>> fm = fe_mesh(PartMesh("cube", m.p.T, m.t.T), order=2)
>>> K = stiffness(fm, 210e3, 0.3)
>>> K.shape == (3 * len(fm.nodes),) * 2
True
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTet, RefTri

from rigfem.fe.inputs import check_mesh
from rigfem.material import lame
from rigfem.cache import NO_CACHE, Cache, array_digest, resolve
from rigfem.mesh.partmesh import PartMesh, quadratic

TET_EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])


TRI_EDGES = np.array([[0, 1], [1, 2], [2, 0]])


#: barycentric coordinates of the 10 nodes of a P2 tetrahedron
NODE_BARY = np.vstack([np.eye(4), 0.5 * (np.eye(4)[TET_EDGES[:, 0]] + np.eye(4)[TET_EDGES[:, 1]])])


#: smallest det J of a curved element, relative to its straight shape, at its nodes and
#: quadrature points; below it the element is straightened
MIN_JACOBIAN = 0.2


@dataclass
class FEMesh:
    """Nodes and P1/P2 elements of a part; ``surfaces`` hold 3- or 6-node triangles."""

    nodes: np.ndarray  #: (N, 3)
    elements: np.ndarray  #: (M, 4) or (M, 10), C3D4/C3D10 order
    surfaces: dict[str, np.ndarray]  #: name -> (K, 3) or (K, 6)
    order: int
    n_vertices: int
    curved: np.ndarray | None = None  #: (M,) bool, elements with a mid-node off its chord (P2)
    straightened: int = 0  #: curved elements straightened for a distorted Jacobian
    cache: dict = field(default_factory=dict, repr=False)  #: derived arrays reused across loads

    @property
    def ndof(self) -> int:
        return 3 * len(self.nodes)


def fe_mesh(mesh: PartMesh, order: int = 2, cache: Cache = NO_CACHE) -> FEMesh:
    """P1 or P2 mesh of ``mesh``; P2 follows the curved boundary edges of the PartMesh (the
    elements straightened: through ``cache``)."""
    p, t, vol = check_mesh(mesh, order)  # a script's own PartMesh and order (rigfem.fe.inputs)
    t = t.copy()
    t[vol < 0, 1:3] = t[vol < 0, 2:0:-1]  # orient positively (C3D10 needs it)
    surfaces = {k: np.asarray(v, dtype=np.int64) for k, v in mesh.surfaces.items()}
    if order == 1:
        return FEMesh(p, t, surfaces, 1, len(p))
    nodes, elements, surf2 = quadratic(dataclasses.replace(mesh, points=p, tets=t, surfaces=surfaces))
    fm = FEMesh(nodes, elements, surf2, 2, len(p))
    fm.straightened = _straighten_cached(fm, cache)
    return fm


def _straighten_cached(fm: FEMesh, cache: Cache) -> int:
    """:func:`_straighten_distorted` through a verified cache entry keyed by the P2 mesh: the
    elements it straightened (a mid-node goes to its chord's midpoint, which depends on the corners
    only), so a warm check skips the Jacobian test of every curved element."""
    n = len(fm.elements)
    got, stored = cache.cached(
        "straightened", {"mesh": array_digest(fm.nodes, fm.elements)}, lambda: _straighten_distorted(fm),
        lambda a, tmp: np.save(tmp / "elements.npy", a), lambda entry: entry.array("elements"),
        lambda a: "" if a.ndim == 1 and a.dtype.kind == "i"
        and np.all((a >= 0) & (a < n)) else "element numbers out of range")
    if stored:  # read from the entry: move them (when computed, _straighten_distorted has)
        _to_chords(fm, got)
        fm.curved = np.abs(_chords(fm, slice(None))).max(axis=(1, 2)) > 0
    return len(got)


def _chords(fm: FEMesh, elems: np.ndarray) -> np.ndarray:
    """Offsets (m, 6, 3) of the mid-edge nodes of ``elems`` from their edges' midpoints."""
    el = fm.elements[elems]
    x = fm.nodes
    return x[el[:, 4:]] - 0.5 * (x[el[:, TET_EDGES[:, 0]]] + x[el[:, TET_EDGES[:, 1]]])


def _to_chords(fm: FEMesh, elems: np.ndarray) -> None:
    """Move the mid-edge nodes of ``elems`` to the midpoints of their edges."""
    el = fm.elements[elems]
    fm.nodes[el[:, 4:]] = 0.5 * (fm.nodes[el[:, TET_EDGES[:, 0]]] + fm.nodes[el[:, TET_EDGES[:, 1]]])


def _straighten_distorted(fm: FEMesh) -> np.ndarray:
    """Mark curved elements; move the mid-nodes of distorted ones back to their chords.

    Checks det J at the 10 nodes and the 11 points of the degree-4 rule against the straight
    element's; repeats while straightening an edge distorts a neighbour.  Returns the elements
    straightened.
    """
    L = np.vstack([NODE_BARY, tet_quadrature(4)[0]])
    done = [np.zeros(0, np.int64)]
    for _ in range(10):
        idx = np.flatnonzero(np.abs(_chords(fm, slice(None))).max(axis=(1, 2)) > 0)
        x = fm.nodes[fm.elements[idx, :4]]
        det0 = _det3(np.swapaxes(x[:, 1:] - x[:, :1], 1, 2))
        bad = idx[(_det3(_curved_jacobian(fm, L, idx)).min(1) < MIN_JACOBIAN * det0)]
        if not len(bad):
            break
        _to_chords(fm, bad)
        done.append(bad)
    fm.curved = np.abs(_chords(fm, slice(None))).max(axis=(1, 2)) > 0
    return np.concatenate(done)


def tet_quadrature(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points (nq, 4) and weights summing to 1/6 on the reference tet."""
    X, W = get_quadrature(RefTet, degree)
    return np.vstack([1 - X.sum(0), X]).T, W


def tri_quadrature(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points (nq, 3) and weights summing to 1/2 on the reference triangle."""
    X, W = get_quadrature(RefTri, degree)
    return np.vstack([1 - X.sum(0), X]).T, W


def shape_values(L: np.ndarray, order: int) -> np.ndarray:
    """Shape functions (nq, nloc) at barycentric points L (nq, 3|4) of a triangle or tet."""
    if order == 1:
        return L.copy()
    edges = TET_EDGES if L.shape[1] == 4 else TRI_EDGES
    return np.hstack([L * (2 * L - 1), 4 * L[:, edges[:, 0]] * L[:, edges[:, 1]]])


def shape_dL(L: np.ndarray, order: int) -> np.ndarray:
    """dN_a/dL_k (nq, nloc, nv) at barycentric points L (nq, nv) of a triangle (nv 3) or tet (nv 4)."""
    nq, nv = L.shape
    if order == 1:
        return np.broadcast_to(np.eye(nv), (nq, nv, nv))
    edges = TET_EDGES if nv == 4 else TRI_EDGES
    C = np.zeros((nq, nv + len(edges), nv))
    C[:, np.arange(nv), np.arange(nv)] = 4 * L - 1
    for a, (i, j) in enumerate(edges):
        C[:, nv + a, i] = 4 * L[:, j]
        C[:, nv + a, j] = 4 * L[:, i]
    return C


def bary_gradients(fm: FEMesh) -> tuple[np.ndarray, np.ndarray]:
    """Gradients of the barycentric coordinates (M, 4, 3) and det J = 6·volume (M,) of the
    straight (corner) tetrahedra."""
    x = fm.nodes[fm.elements[:, :4]]
    J = np.swapaxes(x[:, 1:] - x[:, :1], 1, 2)  # columns = edge vectors
    Ji = np.linalg.inv(J)  # rows = grad L1..L3
    return np.concatenate([-Ji.sum(1, keepdims=True), Ji], axis=1), np.linalg.det(J)


def _ref_grads(L: np.ndarray) -> np.ndarray:
    """∂N_a/∂ξ_k (nq, 10, 3) of P2 at barycentric points L, with L0 = 1 − ξ1 − ξ2 − ξ3."""
    dL = shape_dL(L, 2)
    return dL[..., 1:] - dL[..., :1]


def _curved_jacobian(fm: FEMesh, L: np.ndarray, elems: np.ndarray) -> np.ndarray:
    """Isoparametric Jacobians J[k, d] = ∂x_d/∂ξ_k (m, nq, 3, 3) of P2 elements."""
    return np.einsum("qak,mad->mqkd", _ref_grads(L), fm.nodes[fm.elements[elems]], optimize=True)


def _curved_J(fm: FEMesh, L: np.ndarray, elems: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Isoparametric Jacobians (m, nq, 3, 3) and det J (m, nq) of P2 elements (LAPACK's det: assembly)."""
    J = _curved_jacobian(fm, L, elems)
    return J, np.linalg.det(J)


def _det3(J: np.ndarray) -> np.ndarray:
    """Determinants (...) of 3 × 3 matrices (..., 3, 3) by the rule of Sarrus: a tenth of LAPACK's
    time on millions of small matrices (the distortion test of every curved element)."""
    a, b, c = J[..., 0, :], J[..., 1, :], J[..., 2, :]
    return (a[..., 0] * (b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1])
            - a[..., 1] * (b[..., 0] * c[..., 2] - b[..., 2] * c[..., 0])
            + a[..., 2] * (b[..., 0] * c[..., 1] - b[..., 1] * c[..., 0]))


def geometry(fm: FEMesh, L: np.ndarray, elems: np.ndarray | slice = slice(None),
             grads: bool = True) -> tuple[np.ndarray | None, np.ndarray]:
    """Physical shape-function gradients (m, nq, nloc, 3) (None unless ``grads``) and det J
    (m, nq) at barycentric points L (nq, 4): affine per element, per point on curved elements."""
    sub = _subset(fm, elems)
    G, det0 = bary_gradients(sub)
    det = np.repeat(det0[:, None], len(L), axis=1)
    dN = np.einsum("qak,ekd->eqad", shape_dL(L, fm.order), G, optimize=True) if grads else None
    curved = np.flatnonzero(sub.curved) if sub.curved is not None else np.zeros(0, int)
    if len(curved):
        J, det[curved] = _curved_J(sub, L, curved)
        if grads:
            dN[curved] = np.einsum("qak,mqdk->mqad", _ref_grads(L), np.linalg.inv(J), optimize=True)
    return dN, det


def points_at(fm: FEMesh, L: np.ndarray, elems: np.ndarray | slice = slice(None)) -> np.ndarray:
    """Physical coordinates (m, nq, 3) of barycentric points L (nq, 4) (on curved elements too)."""
    return np.einsum("qa,mad->mqd", shape_values(L, fm.order), fm.nodes[fm.elements[elems]], optimize=True)


def volume(fm: FEMesh) -> float:
    """Volume of the mesh (mm³ in mm), curved elements included (det J of a P2 map is cubic:
    the degree-3 rule is exact)."""
    L, W = tet_quadrature(3)
    return float(sum((geometry(fm, L, slice(s, s + 65536), grads=False)[1] @ W).sum()
                     for s in range(0, len(fm.elements), 65536)))


def _subset(fm: FEMesh, elems) -> FEMesh:
    curved = None if fm.curved is None else fm.curved[elems]
    return FEMesh(fm.nodes, fm.elements[elems], {}, fm.order, fm.n_vertices, curved)


def element_dofs(elements: np.ndarray) -> np.ndarray:
    """Global DOFs (M, 3*nloc) in local order a*3 + c."""
    return (3 * elements[:, :, None] + np.arange(3)).reshape(len(elements), -1)


def stiffness(fm: FEMesh, E: float, nu: float, chunk: int = 8192) -> sp.csr_matrix:
    """Global stiffness matrix of isotropic linear elasticity (exact quadrature).

    Element matrices are computed and summed straight into the node-block (3×3)
    sparsity pattern by a compiled kernel; no COO triplets are formed.
    """
    add_elastic_blocks = _kernels().add_elastic_blocks  # numba: loaded when a matrix is assembled
    lam, mu = lame(E, nu)
    L, W = tet_quadrature(2 * (fm.order - 1))
    indptr, indices, pos = block_pattern(fm.elements, len(fm.nodes))
    data = np.zeros((len(indices), 3, 3))
    for s in range(0, len(fm.elements), chunk):
        sl = slice(s, s + chunk)
        dN, det = geometry(fm, L, sl)
        add_elastic_blocks(dN, det * W[None, :], lam, mu, pos[sl], data)
    return sp.bsr_matrix((data, indices, indptr), shape=(fm.ndof, fm.ndof)).tocsr()


def block_pattern(elements: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node-level CSR pattern (indptr, indices) and each element pair's block index (M, nloc, nloc)."""
    return _kernels().block_pattern(np.ascontiguousarray(elements, dtype=np.int64), n)


def _scatter(dofs: np.ndarray, data: np.ndarray, n: int) -> sp.csr_matrix:
    """Sum element matrices (M, k, k) into a CSR matrix."""
    k = dofs.shape[1]
    rows = np.repeat(dofs, k, axis=1).ravel()
    cols = np.tile(dofs, (1, k)).ravel()
    K = sp.csr_matrix((data.ravel(), (rows, cols)), shape=(n, n))
    K.sum_duplicates()
    return K


#: True in the child process that compiles the kernels (:func:`compile_kernels`)
_COMPILING = False
#: set in the child's environment too: a second guard, so that no single slip lets a child start
#: another (a chain of processes that fills the memory)
_CHILD_ENV = "RIGFEM_KERNELS_CHILD"
#: the child compiling the kernels and the cache that records it ran (:func:`start_compiling`);
#: False once waited for (or not startable)
_compiler = None


def _marker() -> dict:
    """Inputs of the cache entry that says the kernels were compiled once."""
    import importlib.metadata
    import sys

    return {"numba": importlib.metadata.version("numba"), "python": sys.version}


def start_compiling(cache: Cache) -> None:
    """On the first assembly after an install (numba has not compiled the kernels yet: no marker
    in ``cache``) start a child process that compiles them into numba's cache
    (:func:`compile_kernels`); a caller that knows it will assemble starts it early, so that the
    compile overlaps the meshing."""
    global _compiler
    import os
    import subprocess
    import sys

    if os.environ.get(_CHILD_ENV):
        return
    if _COMPILING or _compiler is not None or cache.folder is None or cache.has("kernels", _marker()):
        return
    try:
        child = subprocess.Popen([sys.executable, "-c", "from rigfem.fe.assembly import compile_kernels; "
                                  "compile_kernels()"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                 env={**os.environ, _CHILD_ENV: "1"})
        _compiler = (child, cache)
    except OSError:
        _compiler = False  # compiled here instead, on first use


def compiled(cache: Cache | None = None) -> None:
    """Wait for the child of :func:`start_compiling` (started now with ``cache`` if none was),
    and record that it ran; a caller that starts processes which assemble calls it first, so they
    start none."""
    global _compiler
    import subprocess

    if _compiler is None:
        start_compiling(resolve(cache))
    job, _compiler = _compiler, False  # from now on nothing more is started or waited for
    if not job:
        return
    child, marked = job
    try:
        child.wait(timeout=900)
    except BaseException as exc:  # too slow (compiled here instead), or interrupted: it ends here
        child.kill()
        child.wait()
        if not isinstance(exc, subprocess.TimeoutExpired):
            raise
        return
    marked.put("kernels", _marker(), lambda tmp: None)


@functools.lru_cache(maxsize=1)
def _kernels():
    """The compiled kernels (:mod:`rigfem.fe.kernels`), compiled by the child of
    :func:`start_compiling` and loaded here: LLVM's working memory, which a process keeps once it
    has compiled, goes with the child (a cold check's peak RSS: ``python benchmarks/bench_perf.py
    --rows check``).  A marker entry in rigfem's cache, keyed by the kernels' code and the numba
    and Python versions, says the child ran once; where it failed, or numba's cache went missing
    since, this process compiles them (slower, correct)."""
    compiled()
    import rigfem.fe.kernels

    return rigfem.fe.kernels


def compile_kernels() -> None:
    """Assemble the stiffness of one P1 and one P2 tetrahedron: numba compiles (and caches) every
    kernel signature that a part's assembly uses."""
    global _COMPILING
    _COMPILING = True  # this process is the child: it compiles, it starts no other
    pm = PartMesh("kernels", np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]), np.array([[0, 1, 2, 3]]))
    for order in (1, 2):
        stiffness(fe_mesh(pm, order), 1.0, 0.3)
