"""Reference shapes with closed-form answers: boxes (skfem) and gmsh OCC parts with holes.

Used by the FE tests (tests/fe_shapes.py re-exports them) and by the band-coverage study
(:mod:`rigfem.verification.band_coverage`), so the meshes the closed forms are checked on have one home.
"""

from __future__ import annotations

import numpy as np
from skfem import MeshTet

from rigfem.mesh import Hole, PartMesh, second_order

__all__ = ["FACES", "box", "gmsh_part", "faces_at", "plate_with_hole", "quarter_ring", "bar_with_holes"]

FACES = {"xmin": (0, 0), "xmax": (0, 1), "ymin": (1, 0), "ymax": (1, 1), "zmin": (2, 0), "zmax": (2, 1)}


def box(lx: float, ly: float, lz: float, nx: int, ny: int, nz: int, jitter: float = 0.0, seed: int = 0) -> PartMesh:
    """Box [0,lx]×[0,ly]×[0,lz] with faces named xmin..zmax; interior nodes optionally jittered."""
    m = MeshTet.init_tensor(np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1), np.linspace(0, lz, nz + 1))
    p = m.p.copy()
    if jitter:
        h = np.array([lx / nx, ly / ny, lz / nz])[:, None]
        inner = np.ones(p.shape[1], bool)
        inner[m.boundary_nodes()] = False
        p[:, inner] += jitter * h * np.random.default_rng(seed).uniform(-1, 1, (3, inner.sum()))
    f = m.boundary_facets()
    xc = p[:, m.facets[:, f]].mean(1)
    L = (lx, ly, lz)
    surfaces = {name: m.facets[:, f[np.isclose(xc[ax], side * L[ax])]].T for name, (ax, side) in FACES.items()}
    return PartMesh("box", p.T, m.t.T, surfaces=surfaces)


def gmsh_part(build, size: float, refine: dict | None = None, name: str = "part") -> PartMesh:
    """Mesh an OCC model made by ``build(occ) -> dict[name -> (dim, tags)] or hole spec`` with gmsh
    (second order as rigfem's own meshes: curved walls followed by P2).

    ``build`` returns {surface_name: [surface tags]} and {hole_name: Hole}; ``refine`` maps
    surface names to a local mesh size.
    """
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        groups, holes = build(gmsh.model.occ)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", min([size] + list((refine or {}).values())))
        if refine:
            fields = []
            for nm, h in refine.items():
                d = gmsh.model.mesh.field.add("Distance")
                gmsh.model.mesh.field.setNumbers(d, "SurfacesList", groups[nm])
                t = gmsh.model.mesh.field.add("Threshold")
                gmsh.model.mesh.field.setNumber(t, "InField", d)
                for k, v in (("SizeMin", h), ("SizeMax", size), ("DistMin", 0), ("DistMax", 8 * size)):
                    gmsh.model.mesh.field.setNumber(t, k, v)
                fields.append(t)
            mn = gmsh.model.mesh.field.add("Min")
            gmsh.model.mesh.field.setNumbers(mn, "FieldsList", fields)
            gmsh.model.mesh.field.setAsBackgroundMesh(mn)
            gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.model.mesh.generate(3)
        pts, tets, surfaces, edges, mids = second_order(groups)
        return PartMesh(name, pts, tets, surfaces, holes, curved_edges=edges, curved_points=mids)
    finally:
        gmsh.finalize()


def faces_at(occ, dim_tags, test) -> list[int]:
    """Tags of the surfaces of a volume whose bounding box satisfies ``test(xmin, ymin, zmin, xmax, ymax, zmax)``."""
    import gmsh

    occ.synchronize()
    out = []
    for d, t in gmsh.model.getBoundary(dim_tags, oriented=False):
        if test(*gmsh.model.getBoundingBox(d, t)):
            out.append(t)
    return out


def plate_with_hole(length: float, width: float, thick: float, radius: float, size: float, h_hole: float,
                    quarter: bool = True) -> PartMesh:
    """Quarter (x ≥ 0, y ≥ 0) of a plate with a central hole; faces xsym, ysym, zsym, xmax, hole."""
    eps = 1e-6

    def build(occ):
        b = occ.addBox(0, 0, 0, length / 2, width / 2, thick)
        c = occ.addCylinder(0, 0, -1, 0, 0, thick + 2, radius)
        vol, _ = occ.cut([(3, b)], [(3, c)])
        g = {"xsym": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x1 < eps),
             "ysym": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: y1 < eps),
             "zsym": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: z1 < eps),
             "xmax": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x0 > length / 2 - eps),
             "hole": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x1 < radius + eps and y1 < radius + eps
                              and z1 - z0 > thick / 2)}
        return g, {"hole": Hole(np.array([0, 0, thick / 2]), np.array([0, 0, 1.0]), radius, thick)}

    return gmsh_part(build, size, {"hole": h_hole})


def quarter_ring(a: float, b: float, height: float, size: float, local: float | None = None) -> PartMesh:
    """Quarter (x, y ≥ 0) of a thick-walled tube a < r < b, 0 < z < height; faces xsym, ysym, zsym, inner, outer.

    ``local`` (optional) is the mesh size at the inner (loaded) wall."""
    eps = 1e-6

    def build(occ):
        o = occ.addCylinder(0, 0, 0, 0, 0, height, b, angle=np.pi / 2)
        i = occ.addCylinder(0, 0, -1, 0, 0, height + 2, a)
        vol, _ = occ.cut([(3, o)], [(3, i)])
        g = {"xsym": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x1 < eps),
             "ysym": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: y1 < eps),
             "zsym": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: z1 < eps),
             "inner": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x1 < a + eps and y1 < a + eps
                               and z1 - z0 > height / 2),
             "outer": faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x1 > b - eps and y1 > b - eps
                               and z1 - z0 > height / 2)}
        return g, {"inner": Hole(np.array([0, 0, height / 2]), np.array([0, 0, 1.0]), a, height)}

    return gmsh_part(build, size, {"inner": local} if local else None)


def bar_with_holes(length: float, width: float, thick: float, radius: float, xs: list[float], size: float,
                   h_hole: float | None = None) -> PartMesh:
    """Bar [0,length]×[-width/2,width/2]×[0,thick] with through holes (axis z) at x in ``xs``: h0, h1, …"""
    eps = 1e-6

    def build(occ):
        b = occ.addBox(0, -width / 2, 0, length, width, thick)
        cyl = [(3, occ.addCylinder(x, 0, -1, 0, 0, thick + 2, radius)) for x in xs]
        vol, _ = occ.cut([(3, b)], cyl)
        g, holes = {}, {}
        for k, x in enumerate(xs):
            g[f"h{k}"] = faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1, x=x: abs(x0 - (x - radius)) < eps
                                  and abs(x1 - (x + radius)) < eps and z1 - z0 > thick / 2)
            holes[f"h{k}"] = Hole(np.array([x, 0, thick / 2]), np.array([0, 0, 1.0]), radius, thick)
        g["xmax"] = faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x0 > length - eps)
        g["xmin"] = faces_at(occ, vol, lambda x0, y0, z0, x1, y1, z1: x1 < eps)
        return g, holes

    return gmsh_part(build, size, {f"h{k}": h_hole for k in range(len(xs))} if h_hole else None)
