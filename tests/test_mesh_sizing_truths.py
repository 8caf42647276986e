"""Mesh sizing against truths worked out by hand, not against the code's own earlier output:
the tet estimate as the docstring's graded-layer integral (integrated numerically here) and
within a factor two of the tets gmsh makes; curvature sizes as radius x angle per element on a
circular hole and from the analytic curvature of an ellipse; P2 mid-edge nodes on the true
cylinder, in the plane of a flat face and, for a smoothed part, moved inside; the memory guard's
lower bound from the part's dimensions before gmsh starts; mesh_state and prefetch as documented.

Small custom parts at coarse sizes: the whole file runs in about ten seconds.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.integrate import quad

from rigfem.cache import NO_CACHE, Cache
from rigfem.errors import InputError
from rigfem.mesh import MeshSettings, mesh_part, mesher
from rigfem.mesh.partmesh import quadratic
from rigfem.rig import load_part

#: the block of tests/test_mesh.py: 40 x 20 x 10 mm, a through hole of radius 4 at (20, 10)
BLOCK_GEO = ('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 40, 20, 10};\n'
             'Cylinder(2) = {20, 10, -1, 0, 0, 12, 4};\nBooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};\n'
             'Physical Surface("pin") = {7};\nPhysical Surface("base") = {5};\nPhysical Volume("block") = {3};\n')
R, AXIS = 4.0, np.array([20.0, 10.0])
BLOCK_VOLUME = 40 * 20 * 10 - math.pi * R**2 * 10
PIN_AREA = 2 * math.pi * R * 10

#: the same box in gmsh's built-in kernel (no OpenCASCADE): points, lines, one face extruded
BUILTIN_GEO = """Point(1) = {0, 0, 0}; Point(2) = {40, 0, 0}; Point(3) = {40, 20, 0}; Point(4) = {0, 20, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
out[] = Extrude {0, 0, 10} { Surface{1}; };
Physical Surface("base") = {1}; Physical Surface("top") = {out[0]}; Physical Volume("box") = {out[1]};
"""

TETS_PER_H3 = 8.4  # the calibration constant the estimate is documented with


def layer_integral(near: float, size: float, dist: float) -> float:
    """estimate_tets' docstring: extra tets per mm^2 of a refined surface, the integral over
    0..dist of 1/h(d)^3 - 1/size^3 with h growing linearly from near to size (near >= size: none)."""
    near = min(near, size)
    return quad(lambda d: 1 / (near + (size - near) * d / dist) ** 3 - 1 / size**3, 0, dist)[0]


def expected_tets(volume, area, s: MeshSettings, conc_area=0.0) -> float:
    """The estimate written out from the docstring: volume/h^3 plus the graded layers, at most the
    whole volume at the finest size."""
    h, near = s.size_mm, min(s.near_mm, s.size_mm)
    extra = area * layer_integral(near, h, s.dist_mm) + conc_area * layer_integral(near / 2, h, s.dist_mm)
    finest = near / 2 if conc_area else near
    return TETS_PER_H3 * min(volume / h**3 + extra, volume / finest**3)


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    geo = tmp_path_factory.mktemp("block") / "block.geo"
    geo.write_text(BLOCK_GEO)
    return load_part(str(geo))


@pytest.fixture
def coarse(block):
    """The block at 5 mm, nothing refined: the hole is meshed by curvature sizing alone.  Meshed
    for each test (half a second): mutmut runs, for a mutant, only the tests that called the
    mutated function, and a module fixture's mesh is made in the first test that asks for it."""
    return mesh_part(block, MeshSettings(5.0), cache=NO_CACHE)


def edges_of(tris: np.ndarray) -> np.ndarray:
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0)


def p2_nodes(pm, edges: np.ndarray) -> np.ndarray:
    """The P2 node of each edge: its curved point if second_order listed it, else the chord midpoint."""
    node = 0.5 * (pm.points[edges[:, 0]] + pm.points[edges[:, 1]])
    listed = {tuple(sorted(e)): p for e, p in zip(pm.curved_edges.tolist(), pm.curved_points)}
    for i, e in enumerate(edges.tolist()):
        if tuple(e) in listed:
            node[i] = listed[tuple(e)]
    return node


def axis_distance(p: np.ndarray) -> np.ndarray:
    return np.hypot(p[:, 0] - AXIS[0], p[:, 1] - AXIS[1])


# --- tet estimate --------------------------------------------------------------------------------

@pytest.mark.parametrize("volume, area, conc, s", [
    (1e5, 500.0, 0.0, MeshSettings(4.0, local_size_mm=1.0)),  # refined, graded over 8 mm
    (1e5, 500.0, 0.0, MeshSettings(4.0, local_size_mm=2.0, refine_dist_mm=12.0)),
    (1e5, 500.0, 200.0, MeshSettings(4.0, local_size_mm=1.0)),  # and concentrators at 0.5 mm
    (1e5, 500.0, 200.0, MeshSettings(4.0, local_size_mm=4.0)),  # refined at the global size: no layer
    (1e5, 500.0, 200.0, MeshSettings(4.0, local_size_mm=6.0)),  # coarser than global: no layer either
    (50.0, 5000.0, 0.0, MeshSettings(4.0, local_size_mm=1.0)),  # capped: the whole volume at 1 mm
])
def test_tet_estimate_is_the_graded_layer_integral(volume, area, conc, s):
    got = mesher.estimate_tets(volume, area, s, conc)
    assert abs(got - expected_tets(volume, area, s, conc)) <= 1


def test_refined_block_estimate_from_its_volume_and_hole_area_and_near_its_mesh(block):
    """The built geometry's estimate: the block's volume and the refined hole wall's area 2 pi r L
    (no other curved surface), within a factor two of the tets gmsh makes."""
    s = MeshSettings(5.0, ("pin",))
    pm = mesh_part(block, s, cache=NO_CACHE)
    assert abs(pm.meta["estimate_tets"] - expected_tets(BLOCK_VOLUME, PIN_AREA, s)) <= 1
    assert 0.5 < pm.meta["estimate_tets"] / len(pm.tets) < 2


def test_builtin_kernel_part_estimated_from_its_bounding_box(tmp_path):
    """A .geo in gmsh's built-in kernel: volume and refined area from bounding boxes (exact for
    this box), and the mesh is made."""
    geo = tmp_path / "box.geo"
    geo.write_text(BUILTIN_GEO)
    s = MeshSettings(5.0, ("top",), local_size_mm=2.5)
    pm = mesh_part(load_part(str(geo)), s, cache=NO_CACHE)
    assert abs(pm.meta["estimate_tets"] - expected_tets(40 * 20 * 10, 40 * 20, s)) <= 1
    assert 0.5 < pm.meta["estimate_tets"] / len(pm.tets) < 2
    assert pm.meta["curved"] == {}


# --- curvature sizing ----------------------------------------------------------------------------

def test_hole_curvature_size_is_radius_times_angle_per_element(coarse, tmp_path, capsys):
    """At 5 mm curvature sizing gives round(48/5) = 10 elements per turn: the r = 4 hole is meshed
    finer than the global size, at 2 pi * 4 / 10 = 2.513 mm, and `rigfem mesh` says so."""
    n = round(48 / 5)
    assert coarse.meta["curved"] == {"pin": pytest.approx(2 * math.pi * R / n, abs=5e-4)}
    # gmsh made that: the hole's rim at z = 0 has n vertices
    rim = np.unique(coarse.surfaces["pin"])
    rim = rim[np.abs(coarse.points[rim, 2]) < 1e-9]
    assert len(rim) == n
    from rigfem.cli import main

    geo = tmp_path / "block.geo"
    geo.write_text(BLOCK_GEO)
    assert main(["mesh", str(geo), "--size", "5", "--no-cache", "--out", str(tmp_path / "b.vtu")]) == 0
    assert "finer by curvature on pin (2.5 mm)" in capsys.readouterr().out


def test_curvature_size_of_an_elliptic_wall_from_its_analytic_curvature():
    """_curvature_size's documented rule, 2 pi / (k n) with k the largest curvature on a 3 x 3 grid
    of parametric points (10 %, 50 %, 90 % of each range), on an elliptic wall x = 4 cos t,
    y = 2 sin t, t in [-pi/4, pi/2], z in [0, 10], whose curvature 1 / (a^2 b^2 (x^2/a^4 +
    y^2/b^4)^(3/2)) varies along it: at the grid points t = -0.55, 0.39, 1.34 the largest is
    0.579 (the wall's largest, 1 at t = 0, lies between them)."""
    import gmsh

    from rigfem.mesh import gmsh_session

    a, b = 4.0, 2.0
    with gmsh_session("ellipse"):
        occ = gmsh.model.occ
        arc = occ.addEllipse(0, 0, 0, a, b, angle1=-math.pi / 4, angle2=math.pi / 2)
        wall = [t for d, t in occ.extrude([(1, arc)], 0, 0, 10) if d == 2][0]
        occ.synchronize()
        lo, hi = gmsh.model.getParametrizationBounds(2, wall)
        grid = [[x + f * (y - x) for f in (0.1, 0.5, 0.9)] for x, y in zip(lo, hi)]
        uv = np.array([(u, v) for u in grid[0] for v in grid[1]], float).ravel()
        p = np.array(gmsh.model.getValue(2, wall, uv)).reshape(-1, 3)
        k = 1 / (a * a * b * b * (p[:, 0] ** 2 / a**4 + p[:, 1] ** 2 / b**4) ** 1.5)
        assert k.max() == pytest.approx(0.579, abs=1e-3)
        for n in (6, 10):
            assert mesher._curvature_size(wall, n) == pytest.approx(2 * math.pi / (k.max() * n), rel=1e-6)


# --- second-order nodes --------------------------------------------------------------------------

def test_p2_nodes_of_the_hole_wall_lie_on_the_cylinder(coarse):
    """Every edge of the hole wall has its P2 node on the cylinder r = 4, or within rtol = 1e-3 of
    its length of its chord's midpoint where that midpoint is itself that close (straight edges)."""
    e = edges_of(coarse.surfaces["pin"])
    node = p2_nodes(coarse, e)
    length = np.linalg.norm(coarse.points[e[:, 1]] - coarse.points[e[:, 0]], axis=1)
    assert np.all(np.abs(axis_distance(node) - R) <= 1e-3 * length + 1e-9)
    chord = 0.5 * (coarse.points[e[:, 0]] + coarse.points[e[:, 1]])
    bent = R - axis_distance(chord) > 1e-3 * length  # a chord across the wall: its node must move out
    assert bent.sum() >= 10 and np.all(np.abs(axis_distance(node[bent]) - R) < 1e-6)


def test_curved_edges_are_off_their_chord(coarse):
    """second_order lists an edge only if its P2 node is off the straight midpoint by more than
    1e-3 of the edge length (the chords across the hole wall are listed: the test above)."""
    a, b = coarse.points[coarse.curved_edges[:, 0]], coarse.points[coarse.curved_edges[:, 1]]
    off = np.linalg.norm(coarse.curved_points - 0.5 * (a + b), axis=1)
    assert len(off) and np.all(off > 1e-3 * np.linalg.norm(b - a, axis=1))


def test_p2_nodes_of_a_flat_face_stay_in_its_plane_at_the_midpoints(coarse):
    """The base z = 0: every P2 node in the plane; inside the face (not along the hole's rim
    circle) at the straight midpoint."""
    e = edges_of(coarse.surfaces["base"])
    node = p2_nodes(coarse, e)
    assert np.all(np.abs(node[:, 2]) < 1e-9)
    on_rim = (np.abs(axis_distance(coarse.points[e].reshape(-1, 3)).reshape(-1, 2) - R) < 1e-6).all(axis=1)
    chord = 0.5 * (coarse.points[e[:, 0]] + coarse.points[e[:, 1]])
    np.testing.assert_allclose(node[~on_rim], chord[~on_rim], atol=1e-9)
    assert on_rim.sum() == 10 and np.all(np.abs(axis_distance(node[on_rim]) - R) < 1e-6)


def test_smoothed_part_moves_interior_p2_nodes(coarse):
    """A custom part is smoothed (HighOrderElastic moves interior nodes so the elements along the
    curved wall stay valid): some P2 node off its chord belongs to an edge with a vertex inside
    the solid; and quadratic() gives one tetra10 per tet."""
    assert coarse.meta["smoothed"] is True
    t = coarse.tets
    faces = np.sort(np.concatenate([t[:, [0, 1, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 3]], t[:, [1, 2, 3]]]), axis=1)
    f, count = np.unique(faces, axis=0, return_counts=True)
    boundary = np.zeros(len(coarse.points), bool)
    boundary[f[count == 1]] = True
    inside = ~boundary[coarse.curved_edges].all(axis=1)
    assert inside.sum() > 0
    _, tet10, _ = quadratic(coarse)
    assert len(tet10) == len(t)


def test_mesh_cache_inputs_say_whether_the_mesh_is_smoothed(block):
    """The cache entry records the smoothing the kind gets (custom and rail yes, plate no)."""
    s = MeshSettings(5.0)
    assert mesher.mesh_inputs(block, s)[1]["smooth"] is True
    assert mesher.mesh_inputs(load_part("PF_4b_006"), s)[1]["smooth"] is False


# --- memory guard --------------------------------------------------------------------------------

def test_first_guard_refuses_from_the_dimensions_before_gmsh_starts(monkeypatch):
    """A 1000 mm rail (envelope 1000 x 23 x 24 mm) at 0.1 mm: at least 8.4 * 552000 / 0.001 tets
    from its dimensions alone; refused saying it is a lower bound, and no mesher is started."""
    rail = load_part("rail_size25", {"length": 1000})
    s = MeshSettings(0.1)
    tets = int(TETS_PER_H3 * 1000 * 23 * 24 / 0.1**3)
    assert mesher.estimate_part(rail, s).tets == tets
    monkeypatch.setattr(mesher, "make_mesh", lambda *a, **k: pytest.fail("the mesher was started"))
    with pytest.raises(InputError, match=r"size_mm = 0.1 mm .*would give at least about " + re.escape(f"{tets:.3g} tets")):
        mesh_part(rail, s, cache=NO_CACHE)


def test_second_guard_refuses_from_the_built_geometry(block):
    """A custom part has no dimensions: the guard after gmsh built it refuses with the estimate of
    that geometry (no 'at least': it is the full estimate): the volume at 5 mm, plus the unrefined
    hole wall as a layer one curvature size hc = 2 pi r / 10 thick, A hc / hc^3 tets instead of
    A hc / h^3."""
    s = MeshSettings(5.0)
    hc = 2 * math.pi * R / 10
    tets = int(expected_tets(BLOCK_VOLUME, 0.0, s)) + int(TETS_PER_H3 * PIN_AREA * (1 / hc**2 - hc / 5.0**3))
    with pytest.raises(InputError, match=rf"would give about {tets:.3g} tets") as err:
        mesh_part(block, s, cache=NO_CACHE, machine_gib=1e-6)
    assert "at least" not in str(err.value)


# --- mesh_state and prefetch ---------------------------------------------------------------------

def test_mesh_state_ready_once_cached_none_otherwise(block, tmp_path):
    cache = Cache(tmp_path / "c", 10**9)
    s, other = MeshSettings(5.0), MeshSettings(6.0)
    assert mesher.mesh_state(block, s, cache) == "none"
    mesh_part(block, s, cache=cache)
    assert mesher.mesh_state(block, s, cache) == "ready"
    assert mesher.mesh_state(block, other, cache) == "none"


def test_prefetched_mesh_is_made_ahead_and_found_by_mesh_part(block, tmp_path):
    """prefetch starts the job (1), mesh_part takes the mesh it made (the requested one, freshly
    meshed), and the cache holds it afterwards; a job already cached is not started again."""
    from rigfem.mesh import pool

    cache = Cache(tmp_path / "c", 10**9)
    s = MeshSettings(5.5)
    assert mesher.prefetch([(block, s)], cache) == 1
    key, _ = mesher.mesh_inputs(block, s)
    assert mesher.mesh_state(block, s, cache) in ("making", "ready")
    pm = mesh_part(block, s, cache=cache)
    assert pool.state(key) == "none"  # taken from the pool
    assert pm.meta["cache"] == "miss" and pm.meta["settings"]["size_mm"] == 5.5
    assert abs(np.linalg.det(pm.points[pm.tets[:, 1:]] - pm.points[pm.tets[:, :1]]).sum() / 6
               - BLOCK_VOLUME) < 5e-3 * BLOCK_VOLUME
    assert mesher.mesh_state(block, s, cache) == "ready"
    assert mesher.prefetch([(block, s)], cache) == 0
