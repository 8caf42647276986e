"""NAFEMS LE10, thick plate under pressure: the benchmark FE codes publish time-versus-DOF on.

Problem (NAFEMS, "The Standard NAFEMS Benchmarks", TNSB Rev. 3, 1990, test LE10), in mm, N,
MPa: a quarter of an elliptic annular plate, inner ellipse x²/2000² + y²/1000² = 1, outer
ellipse x²/3250² + y²/2750² = 1, thickness 600 mm (−300 ≤ z ≤ 300); E = 210 000 MPa, ν = 0.3;
uniform pressure 1 MPa on the upper face z = +300.  Points: A (0, 1000), B (0, 2750),
C (3250, 0), D (2000, 0).  Supports, as published with the problem statement by Seamplex's
FeenoX/Fino LE10 case (seamplex.com/fino/cases/012-nafems-le10) and CoFEA's CalculiX /
Code_Aster / Elmer comparison (github.com/spolanski/CoFEA, Benchmarks/01-LE10-Thick-Plate):

* face DCD'C' (y = 0): u_y = 0;
* face ABA'B' (x = 0): u_x = 0;
* outer curved face BCB'C': u_x = u_y = 0;
* its mid-plane line (z = 0) EE': u_z = 0.

Target: σyy at D (2000, 0, 300) = −5.38 MPa.

The geometry is built with gmsh's OpenCASCADE kernel as two half-thickness volumes
(z < 0, z > 0) so the outer face is split along the mid-plane line, which is then the line of
nodes the two outer half-faces share (:class:`rigfem.fe.FixedComponents` with ``edge_with``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rigfem.errors import ComputeError, check_range
from rigfem.material import Material

if TYPE_CHECKING:
    from rigfem.mesh.partmesh import PartMesh

INNER = (2000.0, 1000.0)  #: semi-axes (x, y) of the inner ellipse, mm
OUTER = (3250.0, 2750.0)  #: semi-axes (x, y) of the outer ellipse, mm
HALF_THICKNESS = 300.0  #: mm
PRESSURE = 1.0  #: MPa on the upper face
POINT_D = (2000.0, 0.0, 300.0)  #: where σyy is read, mm
TARGET_SYY = -5.38  #: MPa, NAFEMS reference value at D
STEEL = Material("le10_steel", 210e3, 0.3, 1.0, 7.85e-9)  #: E, ν of LE10 (σu and density unused)
#: surface groups: the supported faces, the loaded face
SURFACES = ("DC", "AB", "outer_upper", "outer_lower", "top")


def supports() -> list:
    """The LE10 supports on :func:`le10_mesh`'s named surfaces."""
    from rigfem.fe.supports import FixedComponents

    return [FixedComponents("DC", "y"), FixedComponents("AB", "x"), FixedComponents("outer_upper", "xy"),
            FixedComponents("outer_lower", "xy"), FixedComponents("outer_upper", "z", edge_with="outer_lower")]


def load(unit_mm: float = 1.0) -> list:
    """The LE10 load case: 1 MPa pressure on the upper face, in N per (mesh unit)²."""
    from rigfem.fe.forces import Pressure

    return [Pressure("top", PRESSURE * unit_mm**2)]


@dataclass(frozen=True)
class Le10Mesh:
    """The element size (10-2000 mm) and layers through the thickness (0-200, or None) of
    :func:`le10_mesh`, checked as they are made."""

    size: float
    layers: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", check_range("LE10 element size", self.size, 10.0, 2000.0, "mm"))
        if self.layers is not None:
            object.__setattr__(self, "layers", int(check_range("LE10 layers", self.layers, 0, 200)))


def le10_mesh(size: float, layers: int | None = None) -> PartMesh:
    """Quadratic-tet mesh of the LE10 quarter plate (a :class:`rigfem.mesh.PartMesh`, curved P2 nodes).

    ``size`` is the element size in mm; ``layers`` (default: about 600/size, at least 2; 0 = let
    gmsh choose) is the number of element layers through the thickness (the vertical edges are
    split evenly, rounded up to even), free tets otherwise.  gmsh is always finalized
    (:func:`rigfem.mesh.gmsh_session`).
    """
    import gmsh

    from rigfem.mesh.geometry import gmsh_session
    from rigfem.mesh.mesher import second_order
    from rigfem.mesh.partmesh import PartMesh

    spec = Le10Mesh(size, layers)  # a script's numbers, checked once
    size, layers = spec.size, spec.layers
    (a, b), (c, d), h = INNER, OUTER, HALF_THICKNESS
    with gmsh_session("le10"):
        occ = gmsh.model.occ
        ring = occ.cut([(2, occ.addDisk(0, 0, 0, c, d))], [(2, occ.addDisk(0, 0, 0, a, b))])[0]
        quarter = occ.intersect(ring, [(2, occ.addRectangle(0, 0, 0, c, d))])[0]
        up = [e for e in occ.extrude(quarter, 0, 0, h) if e[0] == 3]
        down = [e for e in occ.extrude(quarter, 0, 0, -h) if e[0] == 3]
        occ.fragment(up, down)
        occ.synchronize()
        eps = 1e-6 * c
        groups: dict[str, list[int]] = {k: [] for k in SURFACES}
        for _, t in gmsh.model.getEntities(2):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, t)
            if y1 < eps:
                groups["DC"].append(t)
            elif x1 < eps:
                groups["AB"].append(t)
            elif z0 > h - eps:
                groups["top"].append(t)
            elif x1 > c - eps and y1 > d - eps and z1 - z0 > eps:
                groups["outer_upper" if z0 > -eps else "outer_lower"].append(t)
        if any(len(v) != (2 if k in ("DC", "AB") else 1) for k, v in groups.items()):
            raise ComputeError(f"LE10 geometry: gmsh made unexpected faces {groups}")
        for k, v in groups.items():
            gmsh.model.addPhysicalGroup(2, v, name=k)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", size / 4)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 12)
        gmsh.option.setNumber("Mesh.Algorithm3D", 10)
        gmsh.option.setNumber("General.NumThreads", 1)
        layers = max(2, round(2 * h / size)) if layers is None else layers
        if layers:  # at least ``layers`` elements through the thickness: the edges along z set it
            for _, t in gmsh.model.getEntities(1):
                x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(1, t)
                if z1 - z0 > eps and max(x1 - x0, y1 - y0) < eps:
                    gmsh.model.mesh.setTransfiniteCurve(t, max(2, int(np.ceil(layers / 2))) + 1)
        gmsh.model.mesh.generate(3)
        pts, tets, surfaces, edges, mids = second_order(groups)
    return PartMesh("le10", pts, tets, surfaces, {}, curved_edges=edges, curved_points=mids,
                    meta={"size_mm": size, "layers": layers})


def node_at(points: np.ndarray, xyz_mm, unit_mm: float = 1.0) -> int:
    """Index of the mesh node at ``xyz_mm``; ComputeError if no node is there (:func:`le10_mesh`
    puts one at every point the benchmark reads, so a missing node is a fault of the mesh)."""
    target = np.asarray(xyz_mm, float) / unit_mm
    k = int(np.argmin(np.linalg.norm(points - target, axis=1)))
    if np.linalg.norm(points[k] - target) > 1e-6 * OUTER[0] / unit_mm:
        raise ComputeError(f"LE10: no mesh node at {tuple(xyz_mm)} mm")
    return k


def solve_le10(part: PartMesh, unit_mm: float = 1.0, solver: str = "auto") -> dict:
    """Solve LE10 on ``part`` (from :func:`le10_mesh`) with rigfem's P2 FE: σyy at D (MPa), DOFs,
    the model and the solution.  ``unit_mm`` is the length of the mesh's unit in mm (1000 for a
    mesh in metres): E and p are then given in N per unit², σyy converted back to MPa."""
    from rigfem.fe.model import build_model, solve

    check_range("LE10 unit_mm", unit_mm, 1e-6, 1e6, lo_open=True)
    mat = Material(STEEL.name, STEEL.E * unit_mm**2, STEEL.nu, STEEL.sigma_u, STEEL.density)
    model = build_model(part, mat, order=2)
    sol = solve(model, supports(), [load(unit_mm)], solver=solver)
    d = node_at(model.mesh.nodes, POINT_D, unit_mm)
    return {"syy_D": float(sol.stress()[d, 1]) / unit_mm**2, "dof": int(model.mesh.ndof),
            "model": model, "solution": sol, "node_D": d}
