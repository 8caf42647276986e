"""CalculiX cross-check: write rigfem's exact model as a ccx deck, run ccx, read the .frd.

Units: mm, N, MPa, t (density in t/mm³, as in :mod:`rigfem.material`).  Node numbers in the
deck are the 0-based indices of ``nodes`` plus one.  Element connectivity uses
scikit-fem's P2 tetrahedron order, which is CalculiX's C3D10 order: vertices 0..3,
then the midside nodes of edges (0,1), (1,2), (0,2), (0,3), (1,3), (2,3) — exactly
what ``Basis(MeshTet, ElementTetP2()).element_dofs`` gives (scalar P2, one dof per
node).  Negatively oriented tetrahedra are renumbered, never rejected.

Stress arrays hold six components in the order xx, yy, zz, xy, yz, zx (as rigfem's).
The .frd holds 5 significant digits, so ccx and rigfem agree to about 1e-5 on the same model.

:func:`export_model` writes a rigfem model (supports, load cases) as a deck and
:func:`cross_check` solves it in both codes and compares them case by case.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from rigfem.errors import ComputeError, InputError, check_range
from rigfem.files import whole_file
from rigfem.mesh.partmesh import face_owners

#: renumbering of a C3D10/C3D4 element that swaps vertices 1 and 2 (flips orientation)
_FLIP = {10: np.array([0, 2, 1, 3, 6, 5, 4, 7, 9, 8]), 4: np.array([0, 2, 1, 3])}


class CalculixError(ComputeError):
    """ccx is missing, failed, or wrote no usable results."""


@dataclass
class FrdResult:
    """Nodal results of a .frd file, one entry per step; rows indexed by node number − 1."""

    displacement: np.ndarray  #: (S, N, 3) mm, NaN where the file has no value
    stress: np.ndarray  #: (S, N, 6) MPa, xx yy zz xy yz zx, element-extrapolated and averaged
    node_ids: np.ndarray  #: (N_file,) node numbers present in the file


@dataclass
class CcxResult:
    """What :func:`run_ccx` returns: the .frd contents plus run facts."""

    displacement: np.ndarray  #: (S, N, 3) mm
    stress: np.ndarray  #: (S, N, 6) MPa
    wall_time: float  #: s, the whole ccx process
    ccx_time: float  #: s, "Total CalculiX Time" reported by ccx (NaN if absent)
    threads: int
    log: str  #: ccx's stdout and stderr


def _material(material: Any) -> tuple[float, float, float | None]:
    """(E MPa, nu, density t/mm³ or None) from an object with E, nu[, density] or a tuple."""
    if isinstance(material, Sequence) and not isinstance(material, str):
        vals = list(material) + [None] * (3 - len(material))
        e, nu, rho = vals[:3]
    else:
        e, nu, rho = getattr(material, "E", None), getattr(material, "nu", None), getattr(material, "density", None)
    e = check_range("material.E", e, 0.0, None, "MPa", lo_open=True)
    nu = check_range("material.nu", nu, -1.0, 0.4999)
    if rho is not None:
        rho = check_range("material.density", rho, 0.0, None, "t/mm³")
    return e, nu, rho


def _fixed_pairs(fixed: Any, n_nodes: int) -> np.ndarray:
    """(K, 2) int array of (node, dof 0..2) from a (N, 3) bool mask or (K, 2) pairs."""
    arr = np.asarray(fixed)
    if arr.dtype == bool:
        if arr.shape != (n_nodes, 3):
            raise InputError(f"fixed mask must have shape ({n_nodes}, 3), got {arr.shape}")
        return np.argwhere(arr)
    arr = arr.reshape(-1, 2) if arr.size else np.zeros((0, 2), int)
    if not np.issubdtype(arr.dtype, np.integer):
        raise InputError("fixed must be a bool mask (N, 3) or integer (node, dof) pairs")
    if arr.size and (arr[:, 0].min() < 0 or arr[:, 0].max() >= n_nodes):
        raise InputError(f"fixed node index outside [0, {n_nodes - 1}]")
    if arr.size and (arr[:, 1].min() < 0 or arr[:, 1].max() > 2):
        raise InputError("fixed dof outside [0, 2]")
    return np.unique(arr, axis=0)


def _orient(nodes: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Elements with every tetrahedron positively oriented (vertex 3 above face 0-1-2)."""
    p = nodes[elements[:, :4]]
    vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    if np.any(vol == 0.0):
        raise InputError(f"elements: {int(np.sum(vol == 0.0))} tetrahedra have zero volume")
    out = elements.copy()
    out[vol < 0] = elements[vol < 0][:, _FLIP[elements.shape[1]]]
    return out


#: corner nodes (0-based) of the faces P1..P4 of CalculiX's C3D4/C3D10


def _lines(rows: np.ndarray, fmt: str) -> str:
    """Rows formatted line by line (floats as %.14g: ccx reads at most 20 characters a field)."""
    return "".join(fmt % tuple(r) for r in rows.tolist())


def write_inp(path: str | os.PathLike, nodes: np.ndarray, elements: np.ndarray, material: Any,
              fixed: Any, nodal_forces: np.ndarray | Sequence[np.ndarray], *,
              equations: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]] = (),
              springs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
              gravity: Sequence[float] | None = None,
              pressure: tuple[np.ndarray, np.ndarray] | None = None, heading: str = "rigfem model") -> Path:
    """Write a CalculiX static deck of the model and return its path.

    ``nodes`` (N, 3) mm; ``elements`` (M, 10) C3D10 or (M, 4) C3D4, 0-based, in the order
    described in the module docstring; ``material`` has ``E`` (MPa), ``nu`` and optionally
    ``density`` (t/mm³), as attributes (:class:`rigfem.material.Material`) or a tuple;
    ``fixed`` is a (N, 3) bool mask or (K, 2) (node, dof) pairs held at zero;
    ``nodal_forces`` is one (N, 3) array (N) or a list of them, each one *STEP (load case);
    ``equations`` are homogeneous linear constraints ``sum c_i u[node_i, dof_i] = 0`` given
    as (nodes, dofs, coeffs), the first term being the dependent one (not also fixed);
    ``springs`` = (nodes, dofs, stiffness) are grounded SPRING1 elements (N/mm), one *SPRING
    card per distinct (dof, stiffness); ``gravity`` (3,) mm/s² adds ccx's own *DLOAD GRAV
    body load (needs ``density``) to every step; ``pressure`` = (triangles (K, ≥3) node
    indices of boundary faces, p (K,) MPa, positive into the material) adds ccx's own *DLOAD
    face pressure to every step.
    """
    nodes = np.asarray(nodes, dtype=float)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or not np.all(np.isfinite(nodes)):
        raise InputError(f"nodes must be a finite (N, 3) array, got shape {nodes.shape}")
    elements = np.asarray(elements)
    if elements.ndim != 2 or elements.shape[1] not in (4, 10) or not np.issubdtype(elements.dtype, np.integer):
        raise InputError(f"elements must be an integer (M, 10) or (M, 4) array, got {elements.shape}")
    n = len(nodes)
    if elements.size == 0 or elements.min() < 0 or elements.max() >= n:
        raise InputError(f"elements must be non-empty with node indices in [0, {n - 1}]")
    e_mod, nu, rho = _material(material)
    pairs = _fixed_pairs(fixed, n)
    cases = [nodal_forces] if isinstance(nodal_forces, np.ndarray) and nodal_forces.ndim == 2 else list(nodal_forces)
    if not cases:
        raise InputError("nodal_forces must hold at least one load case")
    cases = [np.asarray(f, dtype=float) for f in cases]
    for i, f in enumerate(cases):
        if f.shape != (n, 3) or not np.all(np.isfinite(f)):
            raise InputError(f"nodal_forces[{i}] must be a finite ({n}, 3) array, got {f.shape}")
    if gravity is not None:
        g = np.asarray(gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)) or not g.any() or rho is None:
            raise InputError("gravity must be 3 finite numbers, not all 0, with a material density")
    elements = _orient(nodes, elements)
    if pressure is not None:
        p_elem, p_face = face_owners(elements, np.asarray(pressure[0]), "pressure")
        p_face = p_face + 1  # ccx face numbers S1..S4
        p_val = np.broadcast_to(np.asarray(pressure[1], dtype=float), p_elem.shape)
        if not np.all(np.isfinite(p_val)):
            raise InputError("pressure values must be finite")
    etype = "C3D10" if elements.shape[1] == 10 else "C3D4"

    out = [f"*HEADING\n{heading.splitlines()[0] if heading else ''}\n", "*NODE, NSET=NALL\n"]
    out.append(_lines(np.column_stack([np.arange(1, n + 1), nodes]), "%d,%.14g,%.14g,%.14g\n"))
    out.append(f"*ELEMENT, TYPE={etype}, ELSET=EALL\n")
    out.append(_lines(np.column_stack([np.arange(1, len(elements) + 1), elements + 1]),
                      "%d" + ",%d" * elements.shape[1] + "\n"))
    out.append(f"*MATERIAL, NAME=MAT\n*ELASTIC\n{e_mod:.14g},{nu:.14g}\n")
    if rho is not None:
        out.append(f"*DENSITY\n{rho:.14g}\n")
    out.append("*SOLID SECTION, ELSET=EALL, MATERIAL=MAT\n")
    if len(pairs):
        out.append("*BOUNDARY\n" + _lines(np.column_stack([pairs[:, 0] + 1, pairs[:, 1] + 1, pairs[:, 1] + 1]),
                                          "%d,%d,%d\n"))
    for k, (eq_nodes, eq_dofs, eq_coef) in enumerate(equations):
        eq_nodes, eq_dofs = np.asarray(eq_nodes, int).ravel(), np.asarray(eq_dofs, int).ravel()
        eq_coef = np.asarray(eq_coef, float).ravel()
        if not (len(eq_nodes) == len(eq_dofs) == len(eq_coef) >= 1) or eq_coef[0] == 0.0:
            raise InputError(f"equations[{k}] needs equal-length nodes, dofs, coeffs with a nonzero first coefficient")
        if eq_nodes.min() < 0 or eq_nodes.max() >= n or eq_dofs.min() < 0 or eq_dofs.max() > 2:
            raise InputError(f"equations[{k}]: node outside [0, {n - 1}] or dof outside [0, 2]")
        terms = np.column_stack([eq_nodes + 1, eq_dofs + 1, eq_coef]).tolist()
        out.append(f"*EQUATION\n{len(terms)}\n")
        # at most 4 terms (12 entries) per line
        out.extend(",".join("%d,%d,%.14g" % tuple(t) for t in terms[i:i + 4]) + "\n" for i in range(0, len(terms), 4))
    if springs is not None:
        out.append(_springs(springs, n, len(elements)))
    for f in cases:
        idx = np.argwhere(f != 0.0)
        out.append("*STEP\n*STATIC\n*CLOAD, OP=NEW\n")
        out.append(_lines(np.column_stack([idx[:, 0] + 1, idx[:, 1] + 1, f[idx[:, 0], idx[:, 1]]]), "%d,%d,%.14g\n"))
        if pressure is not None:
            out.append("*DLOAD\n" + _lines(np.column_stack([p_elem + 1, p_face, p_val]), "%d,P%d,%.14g\n"))
        if gravity is not None:
            gn = float(np.linalg.norm(g))
            out.append(f"*DLOAD\nEALL,GRAV,{gn:.14g},{g[0] / gn:.14g},{g[1] / gn:.14g},{g[2] / gn:.14g}\n")
        out.append("*NODE FILE\nU\n*EL FILE\nS\n*END STEP\n")
    path = Path(path)
    with whole_file(path) as tmp:
        tmp.write_text("".join(out))
    return path


def _springs(springs: tuple[np.ndarray, np.ndarray, np.ndarray], n: int, first: int) -> str:
    """SPRING1 elements numbered after the ``first`` solid elements, one ELSET per (dof, k)."""
    sn, sd = np.asarray(springs[0], int).ravel(), np.asarray(springs[1], int).ravel()
    sk = np.asarray(springs[2], float).ravel()
    if not (len(sn) == len(sd) == len(sk)) or (len(sn) and (sn.min() < 0 or sn.max() >= n or sd.min() < 0
                                                          or sd.max() > 2 or not np.all(np.isfinite(sk)))):
        raise InputError(f"springs: equal-length nodes in [0, {n - 1}], dofs in [0, 2], finite stiffness")
    keys, group = np.unique(np.column_stack([sd, sk]), axis=0, return_inverse=True)
    ids = first + 1 + np.arange(len(sn))
    out = []
    for g, (dof, k) in enumerate(keys):
        sel = group.ravel() == g
        out.append(f"*ELEMENT, TYPE=SPRING1, ELSET=SPRING{g + 1}\n")
        out.append(_lines(np.column_stack([ids[sel], sn[sel] + 1]), "%d,%d\n"))
        out.append(f"*SPRING, ELSET=SPRING{g + 1}\n{int(dof) + 1}\n{k:.14g}\n")
    return "".join(out)


def _shaft_terms(fm: Any, hole: Any, s: Any, E: float) -> tuple[np.ndarray, ...]:
    """Rank-one terms c·(g·u)² of rigfem's ShaftInHole foundation, one per quadrature point and direction.

    From :func:`rigfem.fe.supports.shaft_terms`; :func:`export_model` checks that the terms sum
    to rigfem's spring matrix.  Returns points (P, 3), c (P, 3) for the radial, tangential and
    axial directions, g (P, 3, nloc, 3) and the surface nodes (P, nloc).
    """
    from rigfem.fe.supports import shaft_terms

    pts, k, dirs, w, N, tri = shaft_terms(fm, hole, s, E)
    c = k * w[..., None]  # (K, nq, 3)
    g = np.einsum("qa,kqdj->kqdaj", N, dirs)
    nodes = np.broadcast_to(tri[:, None, :], (*w.shape, tri.shape[1]))
    return pts.reshape(-1, 3), c.reshape(-1, 3), g.reshape(-1, 3, *g.shape[3:]), nodes.reshape(-1, tri.shape[1])


def export_model(model: Any, supports: list, cases: list | np.ndarray, path: str | os.PathLike,
                 heading: str = "rigfem model") -> Path:
    """Write rigfem's model (:class:`rigfem.fe.model.Model`, supports, load cases) as a ccx deck.

    ``cases`` are rigfem load cases (as for :func:`rigfem.fe.model.solve`) or nodal loads
    (3N, k), e.g. ``solution.F @ coef.T``.  Same nodes, C3D10/C3D4 elements, fixed DOFs and
    consistent nodal loads (one *STEP per case).  A ShaftInHole foundation is exported
    exactly: one auxiliary node per surface quadrature point whose three DOFs are tied by
    *EQUATION to √(c/k0)·(g·u) of the hole nodes and grounded by SPRING1 elements of
    stiffness k0.  FreeBody is exported as its 3-2-1 support; rigfem afterwards removes the
    rigid motion from its displacement, ccx does not.  Auxiliary nodes come after the mesh
    nodes and have no results.
    """
    from rigfem.fe.model import load_matrix
    from rigfem.fe.supports import ShaftInHole, constraints

    fm, n = model.mesh, len(model.mesh.nodes)
    fixed_dofs, spring_matrix, _ = constraints(fm, model.part.holes, supports, model.material.E)
    if isinstance(cases, np.ndarray):
        F = cases.reshape(len(cases), -1)
        if F.shape[0] != fm.ndof:
            raise InputError(f"cases: nodal loads must have {fm.ndof} rows (3 per node), got {cases.shape}")
    else:
        F = load_matrix(model, cases)
    fixed = np.column_stack([fixed_dofs // 3, fixed_dofs % 3])
    nodes, equations, springs = fm.nodes, [], None
    shafts = [s for s in supports if isinstance(s, ShaftInHole)]
    if shafts:
        parts = [_shaft_terms(fm, model.part.holes[s.hole], s, model.material.E) for s in shafts]
        pts = np.vstack([p[0] for p in parts])
        c = np.vstack([p[1] for p in parts])
        g = np.concatenate([p[2] for p in parts])
        tri = np.vstack([p[3] for p in parts])
        _check_springs(spring_matrix, c, g, tri, n)
        keep = c.max(axis=1) > 0
        pts, c, g, tri = pts[keep], c[keep], g[keep], tri[keep]
        k0 = float(np.median(c[c > 0]))
        aux = n + np.arange(len(pts))
        nodes = np.vstack([fm.nodes, pts])
        coef = np.sqrt(c / k0)[:, :, None, None] * g  # (P, 3 dirs, nloc, 3)
        sn, sd = [], []
        unused = np.argwhere(c == 0.0)  # aux DOFs without a spring (unloaded half of a bearing side)
        fixed = np.vstack([fixed, np.column_stack([aux[unused[:, 0]], unused[:, 1]])])
        for p in range(len(pts)):
            for d in range(3):
                if c[p, d] == 0.0:
                    continue
                nz = np.argwhere(coef[p, d] != 0.0)
                equations.append((np.r_[aux[p], tri[p][nz[:, 0]]], np.r_[d, nz[:, 1]],
                                  np.r_[-1.0, coef[p, d][nz[:, 0], nz[:, 1]]]))
                sn.append(aux[p])
                sd.append(d)
        springs = (np.array(sn), np.array(sd), np.full(len(sn), k0))
    pad = np.zeros((len(nodes) - n, 3))
    loads = [np.vstack([F[:, k].reshape(-1, 3), pad]) for k in range(F.shape[1])]
    return write_inp(path, nodes, fm.elements, model.material, fixed, loads, equations=equations, springs=springs,
                     heading=heading)


def _n_nodes(inp_text: str) -> int:
    """Largest node number in the *NODE block of a deck written by :func:`write_inp`."""
    m = re.search(r"^\*NODE[^\n]*\n(.*?)^\*", inp_text, flags=re.M | re.S)
    if not m:
        raise CalculixError("deck has no *NODE block")
    return max(int(line.split(",", 1)[0]) for line in m.group(1).splitlines() if line.strip())


def read_frd(path: str | os.PathLike, n_nodes: int | None = None) -> FrdResult:
    """Read the nodal DISP and STRESS blocks of an ASCII CalculiX .frd file."""
    blocks: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {"DISP": [], "STRESS": []}
    node_ids = np.zeros(0, int)
    with open(path) as fh:
        lines = iter(fh)
        for line in lines:
            if line[:6] == "    2C":  # node block: " -1" + I10 + 3 E12.5
                rows = []
                for rec in lines:
                    if rec.startswith(" -3"):
                        break
                    rows.append(int(rec[3:13]))
                node_ids = np.array(rows, int)
            elif line.startswith(" -4") and line[5:13].strip() in blocks:
                name = line[5:13].strip()
                ids, vals = [], []
                for rec in lines:
                    if rec.startswith(" -3"):
                        break
                    if rec.startswith(" -1"):
                        ids.append(int(rec[3:13]))
                        rec = rec.rstrip()
                        vals.append([float(rec[i:i + 12]) for i in range(13, len(rec), 12)])
                blocks[name].append((np.array(ids, int), np.array(vals, float)))
    if not blocks["DISP"]:
        raise CalculixError(f"{path}: no DISP block")
    n = int(n_nodes if n_nodes is not None else max(node_ids.max(initial=0), *(b[0].max() for b in blocks["DISP"])))

    def dense(items: list[tuple[np.ndarray, np.ndarray]], ncomp: int) -> np.ndarray:
        out = np.full((len(items), n, ncomp), np.nan)
        for s, (ids, vals) in enumerate(items):
            out[s, ids - 1] = vals[:, :ncomp]
        return out

    return FrdResult(dense(blocks["DISP"], 3), dense(blocks["STRESS"], 6), node_ids)


def run_ccx(inp_path: str | os.PathLike, threads: int = 1, workdir: str | os.PathLike | None = None,
            timeout: float | None = None) -> CcxResult:
    """Run ccx on a deck in a temporary directory (or ``workdir``, kept) and read its results.

    ``threads`` sets OMP_NUM_THREADS and CCX_NPROC_* for the run.  Raises
    :class:`CalculixError` with the tail of ccx's output when ccx fails.  Note that ccx
    solves an unsupported (singular) model without complaint: rigfem's support check is the guard.
    """
    exe = shutil.which("ccx")
    if exe is None:
        raise CalculixError("ccx not found on PATH (Debian/Ubuntu: apt-get install calculix-ccx)")
    threads = int(check_range("threads", threads, 1, 256))
    inp_path = Path(inp_path)
    text = inp_path.read_text()
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_STIFFNESS=str(threads),
               CCX_NPROC_EQUATION_SOLVER=str(threads), CCX_NPROC_RESULTS=str(threads))
    with tempfile.TemporaryDirectory(prefix="rigfem-ccx-") as tmp:
        wd = Path(workdir) if workdir is not None else Path(tmp)
        wd.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(inp_path, wd / "job.inp")
        t0 = time.perf_counter()
        try:
            proc = subprocess.run([exe, "-i", "job"], cwd=wd, env=env, capture_output=True, text=True,
                                  timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            raise CalculixError(f"ccx timed out after {timeout} s on {inp_path}") from exc
        wall = time.perf_counter() - t0
        log = proc.stdout + proc.stderr
        frd = wd / "job.frd"
        if proc.returncode != 0 or "*ERROR" in log or not frd.exists() or frd.stat().st_size == 0:
            tail = "\n".join(log.strip().splitlines()[-15:])
            raise CalculixError(f"ccx failed on {inp_path} (exit code {proc.returncode}):\n{tail}")
        res = read_frd(frd, _n_nodes(text))
    m = re.search(r"Total CalculiX Time:\s*([0-9.eE+-]+)", log)
    return CcxResult(res.displacement, res.stress, wall, float(m.group(1)) if m else float("nan"), threads, log)


def _check_springs(K: Any, c: np.ndarray, g: np.ndarray, tri: np.ndarray, n: int) -> None:
    """Raise CalculixError unless Σ c·g gᵀ equals rigfem's spring matrix ``K``."""
    import scipy.sparse as sp

    dofs = (3 * tri[:, :, None] + np.arange(3)).reshape(len(tri), -1)  # (P, 3 nloc)
    gv = g.reshape(len(g), 3, -1)  # (P, 3 dirs, 3 nloc)
    blocks = np.einsum("pd,pdi,pdj->pij", c, gv, gv)
    k = dofs.shape[1]
    mine = sp.csr_matrix((blocks.ravel(), (np.repeat(dofs, k, 1).ravel(), np.tile(dofs, (1, k)).ravel())),
                         shape=(3 * n, 3 * n))
    diff = abs(mine - K).max() if K is not None else np.inf
    if not diff <= 1e-9 * abs(K).max():
        raise CalculixError(f"ShaftInHole export does not reproduce rigfem's spring matrix (max diff {diff:.3g})")
