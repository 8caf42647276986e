"""Meshing: groups, hole geometry, refinement, quality, determinism, cache, memory guard, export."""

import math

import meshio
import numpy as np
import pytest

from rigfem.cache import NO_CACHE
from rigfem.errors import InputError
from rigfem.mesh import (
    MeshSettings,
    curvature_n,
    estimate,
    fit_cylinder,
    mesh_part,
    to_meshio,
    write_mesh,
)
from rigfem.rig import load_part
from said import one_line


@pytest.fixture(autouse=True)
def cache_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def rail700():
    """700 mm rail, coarse 8 mm, refined around the last two holes (a far-end coupling)."""
    part = load_part("rail_size25", {"length": 700})
    return part, mesh_part(part, MeshSettings(8.0, ("hole_10", "hole_11")), cache=NO_CACHE)


def tet_volumes(pm):
    d = pm.points[pm.tets[:, 1:]] - pm.points[pm.tets[:, :1]]
    return np.linalg.det(d) / 6


def tri_areas(pm, name):
    p = pm.points[pm.surfaces[name]]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def test_rail_every_group_present_and_nonempty(rail700):
    part, pm = rail700
    expected = {"ends", "bottom", "top", "sides", "grooves"}  # the default profile has raceway grooves
    for i in range(12):
        expected |= {f"hole_{i:02d}", f"cbore_{i:02d}", f"cbore_floor_{i:02d}"}
    assert set(pm.surfaces) == expected
    assert all(len(t) > 0 for t in pm.surfaces.values())
    assert set(pm.holes) == {k for k in expected if k.startswith(("hole_", "cbore_")) and "floor" not in k}


def test_rail_holes_in_mesh_where_the_part_says(rail700):
    """Cylinders fitted to the meshed hole walls (independent of the analytic Hole records)."""
    part, pm = rail700
    xs = 20 + 60 * np.arange(12)
    for i, x in enumerate(xs):
        fit = fit_cylinder(pm.points, pm.surfaces[f"hole_{i:02d}"])
        assert fit is not None
        np.testing.assert_allclose(fit.center, [x, 0, 7.5], atol=1e-6)
        assert abs(abs(fit.axis[2]) - 1) < 1e-9
        assert fit.radius == pytest.approx(3.5, abs=1e-6) and fit.depth == pytest.approx(15, abs=1e-6)
        h = pm.holes[f"hole_{i:02d}"]
        np.testing.assert_allclose(h.center, fit.center, atol=1e-6)
        c = fit_cylinder(pm.points, pm.surfaces[f"cbore_{i:02d}"])
        assert c.radius == pytest.approx(5.5, abs=1e-6) and c.center[2] == pytest.approx(19.5, abs=1e-6)
    assert fit_cylinder(pm.points, pm.surfaces["top"]) is None  # a plane is no cylinder


def test_rail_mesh_volume_and_areas_against_hand_calculation(rail700):
    """Faceted holes and grooves (inscribed polygons) remove less: the mesh is a little larger."""
    part, pm = rail700
    vols = tet_volumes(pm)
    assert (vols > 0).all()
    holes = 12 * (math.pi / 4 * 7**2 * 15 + math.pi / 4 * 11**2 * 9)
    hand = 700 * (23 * 24 - 2 * math.pi * 4.6**2) - holes
    # at 8 mm curvature sizing gives each half-disc groove 6/2 = 3 or more chords: the mesh lies
    # between the exact grooves and 3-chord polygons (area 3 * r^2/2 * sin 60 deg each)
    coarse = 700 * (23 * 24 - 4 * 3 * 4.6**2 / 2 * math.sin(math.pi / 3)) - holes
    assert hand < vols.sum() <= coarse * (1 + 1e-9)
    end, end_coarse = hand / 700 + holes / 700, coarse / 700 + holes / 700  # the section, both bounds
    assert 2 * end < tri_areas(pm, "ends").sum() <= 2 * end_coarse * (1 + 1e-9)
    assert tri_areas(pm, "sides").sum() == pytest.approx(2 * 700 * (24 - 4 * 4.6), rel=1e-9)
    assert tri_areas(pm, "bottom").sum() == pytest.approx(700 * 23 - 12 * math.pi * 3.5**2, rel=1e-2)


def test_refinement_only_at_the_loaded_holes(rail700):
    part, pm = rail700

    def mean_edge(name):
        t = pm.surfaces[name]
        return np.linalg.norm(pm.points[t] - pm.points[np.roll(t, 1, axis=1)], axis=2).mean()

    assert mean_edge("hole_11") < 0.75 * mean_edge("hole_05")
    assert mean_edge("hole_10") < 0.75 * mean_edge("hole_00")
    assert mean_edge("hole_11") == pytest.approx(2.0, rel=0.3)  # refine size = 8/4 mm


@pytest.mark.parametrize("name, refine", [("PF_4b_006", ("bore", "screw_1", "screw_2")),
                                          ("PF_4b_003_v2", ("screw_1", "screw_2", "screw_3", "screw_4"))])
def test_plate_and_iprofile_groups_quality_and_volume(name, refine):
    part = load_part(name)
    pm = mesh_part(part, MeshSettings(8.0, refine), cache=NO_CACHE)
    assert all(len(t) > 0 for t in pm.surfaces.values())
    assert set(refine) <= set(pm.holes) and set(refine) <= set(pm.surfaces)
    assert pm.quality["min"] >= 0.1
    from rigfem.mesh import volume_mm3
    assert tet_volumes(pm).sum() == pytest.approx(volume_mm3(part), rel=1e-2)
    for g in refine:  # the analytic hole records agree with the meshed walls
        fit = fit_cylinder(pm.points, pm.surfaces[g])
        h = pm.holes[g]
        np.testing.assert_allclose(fit.center, h.center, atol=1e-6)
        assert fit.radius == pytest.approx(h.radius, abs=1e-6) and fit.depth == pytest.approx(h.depth, abs=1e-6)


def test_filleted_iprofile_where_hxt_leaves_a_flat_tet_still_meshes():
    """Height 70, size 6: HXT puts a zero-volume tet across the 6 mm web (mirrored face meshes);
    mesh_part falls back to gmsh's Delaunay and meets the quality threshold."""
    part = load_part("PF_4b_003_v2", {"height": 70})
    assert part["fillet_radius"] == 3
    pm = mesh_part(part, MeshSettings(6.0), cache=NO_CACHE)
    assert pm.quality["min"] >= 0.1 and (tet_volumes(pm) > 0).all()
    # the fillet group: four quarter cylinders r = 3 along the 40 mm length, (pi/2)*3*40 each
    tri = pm.points[pm.surfaces["fillets"]]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    exact = 4 * math.pi / 2 * 3 * 40
    assert area == pytest.approx(exact, rel=5e-2) and area < exact  # flat facets are chords of the arc


def test_plate_screws_on_x_axis_at_two_pitches():
    pm = mesh_part(load_part("PF_4b_006"), MeshSettings(10.0), cache=NO_CACHE)
    assert pm.holes["screw_1"].center[0] == pytest.approx(-60) and pm.holes["screw_2"].center[0] == pytest.approx(60)
    assert pm.holes["bore"].radius == pytest.approx(26) and pm.holes["bore"].depth == pytest.approx(15)


def test_quality_reported_and_above_threshold(rail700):
    _, pm = rail700
    q = pm.quality
    assert 0.1 <= q["min"] <= q["p01"] <= q["p05"] <= q["median"] <= 1


def test_quality_below_threshold_names_part_and_parameter():
    part = load_part("PF_4b_003_v2")
    with pytest.raises(InputError, match=r"PF_4b_003_v2.*size"):
        mesh_part(part, MeshSettings(10.0, min_quality=0.99), cache=NO_CACHE)


def test_identical_input_gives_identical_mesh():
    part = load_part("PF_4b_003_v2")
    a = mesh_part(part, MeshSettings(6.0, ("screw_1",)), cache=NO_CACHE)
    b = mesh_part(part, MeshSettings(6.0, ("screw_1",)), cache=NO_CACHE)
    assert np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)
    assert all(np.array_equal(a.surfaces[k], b.surfaces[k]) for k in a.surfaces)


def test_cache_hit_on_repeat_and_miss_on_change(tmp_path):
    part = load_part("PF_4b_003_v2")
    a = mesh_part(part, MeshSettings(6.0))
    b = mesh_part(part, MeshSettings(6.0))
    assert (a.meta["cache"], b.meta["cache"]) == ("miss", "hit")
    assert np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)
    assert b.holes["screw_3"].radius == a.holes["screw_3"].radius and b.quality == a.quality
    assert len(list((tmp_path / "cache").rglob("*.npz"))) == 1
    c = mesh_part(load_part("PF_4b_003_v2", {"height": 70}), MeshSettings(6.0))
    assert c.meta["cache"] == "miss" and c.meta["hash"] != a.meta["hash"]


def test_memory_guard_refuses_before_meshing():
    part = load_part("rail_size25", {"length": 1000})
    with pytest.raises(InputError, match=r"increase size_mm \(--size\)"):
        mesh_part(part, MeshSettings(0.1), cache=NO_CACHE)


def test_estimate_within_factor_two_of_actual(rail700):
    _, pm = rail700
    assert 0.5 < pm.meta["estimate_tets"] / len(pm.tets) < 2
    assert estimate(10**6).gib > estimate(10**5).gib > 0


def test_unknown_refine_group_is_input_error():
    with pytest.raises(InputError, match="hole_99"):
        mesh_part(load_part("rail_size25", {"length": 700}), MeshSettings(8.0, ("hole_99",)), cache=NO_CACHE)


def test_quadratic_export_puts_midnodes_on_the_hole_walls_geometry(rail700, tmp_path):
    _, pm = rail700
    m = to_meshio(pm, order=2)
    tet10 = m.cells_dict["tetra10"]
    assert len(tet10) == len(pm.tets)
    tri6 = m.cells[1 + sorted(pm.surfaces).index("hole_11")].data
    mid = m.points[np.unique(tri6[:, 3:])]
    chord = 0.5 * (m.points[tri6[:, [0, 1, 2]]] + m.points[tri6[:, [1, 2, 0]]]).reshape(-1, 3)
    off_straight = np.abs(np.hypot(chord[:, 0] - 680, chord[:, 1]) - 3.5).max()
    off = np.abs(np.hypot(mid[:, 0] - 680, mid[:, 1]) - 3.5).max()
    # on the CAD cylinder, except offsets below 1e-3 of the edge length, which are kept straight
    assert off < 0.02 * off_straight and off < 2e-3
    for suffix in (".vtu", ".msh"):
        write_mesh(pm, tmp_path / f"rail{suffix}", order=1)
        back = meshio.read(tmp_path / f"rail{suffix}")
        assert len(back.cells_dict["tetra"]) == len(pm.tets)
    assert "hole_11" in meshio.read(tmp_path / "rail.msh").field_data


def test_custom_geo_part_with_physical_groups(tmp_path):
    """A box 40 x 20 x 10 with a Ø8 hole at (20, 10), groups from the .geo file."""
    geo = tmp_path / "block.geo"
    geo.write_text('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 40, 20, 10};\n'
                   'Cylinder(2) = {20, 10, -1, 0, 0, 12, 4};\nBooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};\n'
                   'Physical Surface("pin") = {7};\nPhysical Surface("base") = {5};\nPhysical Volume("block") = {3};\n')
    part = load_part(str(geo))
    assert part.kind == "custom"
    pm = mesh_part(part, MeshSettings(3.0, ("pin",)), cache=NO_CACHE)
    assert set(pm.surfaces) == {"pin", "base"}
    assert tet_volumes(pm).sum() == pytest.approx(40 * 20 * 10 - math.pi * 16 * 10, rel=5e-3)
    h = pm.holes["pin"]  # fitted cylinder
    np.testing.assert_allclose(h.center, [20, 10, 5], atol=1e-6)
    assert h.radius == pytest.approx(4, abs=1e-6) and "base" not in pm.holes


def test_cli_mesh_writes_file_and_reports(tmp_path, capsys):
    from rigfem.cli import main

    out = tmp_path / "rail.vtu"
    args = ["mesh", "rail_size25", "--length", "460", "--size", "8", "--refine", "hole_06,hole_07", "--out", str(out)]
    assert main(args) == 0
    m = meshio.read(out)
    assert len(m.cells_dict["tetra"]) > 1000
    text = capsys.readouterr().out
    assert "length 460 mm" in text and "cache miss" in text and "hole_07" in text
    assert main(args[:-1] + [str(tmp_path / "rail2.msh"), "--order", "2"]) == 0
    assert "cache hit" in capsys.readouterr().out
    assert "tetra10" in meshio.read(tmp_path / "rail2.msh").cells_dict


@pytest.mark.parametrize("part, args, field", [
    ("PF_4b_006", ["--set", "thickness=-3"], "thickness"),
    ("PF_4b_006", ["--length", "100"], "length"),  # a plate has no length
    ("rail_size25", ["--length", "30"], "length"),  # shorter than two end distances
    ("PF_4b_003_v2", ["--size", "0"], "--size"),
    ("PF_4b_003_v2", ["--refine", "nothere"], "refine"),
])
def test_cli_mesh_bad_input_exit_2_naming_field(tmp_path, capsys, part, args, field):
    from rigfem.cli import main

    assert main(["mesh", part, *args, "--out", str(tmp_path / "x.vtu")]) == 2
    err = capsys.readouterr().err
    assert one_line(err).startswith("rigfem: error:") and field in err


def test_custom_brep_wrapped_in_geo_and_unnamed_brep_rejected(tmp_path):
    """A BREP has no names: used through a .geo wrapper that names its faces; alone it is refused."""
    import gmsh

    from rigfem.mesh import gmsh_session

    with gmsh_session():
        box = gmsh.model.occ.addBox(0, 0, 0, 30, 30, 8)
        gmsh.model.occ.cut([(3, box)], [(3, gmsh.model.occ.addCylinder(15, 15, -1, 0, 0, 10, 5))])
        gmsh.model.occ.synchronize()
        gmsh.write(str(tmp_path / "washer.brep"))
    with pytest.raises(InputError, match="no named surface"):
        mesh_part(load_part(str(tmp_path / "washer.brep")), MeshSettings(4.0), cache=NO_CACHE)
    geo = tmp_path / "washer.geo"
    geo.write_text('SetFactory("OpenCASCADE");\nMerge "washer.brep";\n'
                   'Physical Surface("bore") = {7};\nPhysical Volume("washer") = {1};\n')
    pm = mesh_part(load_part(str(geo)), MeshSettings(4.0, ("bore",)), cache=NO_CACHE)
    assert tet_volumes(pm).sum() == pytest.approx(30 * 30 * 8 - math.pi * 25 * 8, rel=5e-3)
    assert pm.holes["bore"].radius == pytest.approx(5, abs=1e-6)


def test_concentrators_meshed_at_half_the_refined_size():
    """The post's root fillets as concentrators: their triangles' edges are about half as long
    as with the fillets merely refined, and the estimate still tracks the mesh."""
    post = load_part("PF_4b_003_v2")

    def fillet_edge(pm):
        p = pm.points[pm.surfaces["fillets"]]
        return np.median(np.linalg.norm(p[:, 1] - p[:, 0], axis=1))

    loaded = ("screw_3", "screw_4")
    plain = mesh_part(post, MeshSettings(6.0, loaded + ("fillets",), 1.2), cache=NO_CACHE)
    conc = mesh_part(post, MeshSettings(6.0, loaded, 1.2, concentrate=("fillets",)), cache=NO_CACHE)
    assert 0.35 < fillet_edge(conc) / fillet_edge(plain) < 0.7
    assert 0.5 < conc.meta["estimate_tets"] / len(conc.tets) < 2


def test_curved_surfaces_refine_with_the_global_size():
    """Curvature sizing follows the global size (48 mm / size elements per 2 pi, at least 6)."""
    assert [curvature_n(MeshSettings(s)) for s in (11.3, 8.0, 6.0, 4.0, 2.0)] == [6, 6, 8, 12, 24]


def test_the_mesher_runs_in_this_process_only_when_asked(monkeypatch):
    """make_mesh meshes in a child process (gmsh is interruptible and returns its memory), and in
    this one with RIGFEM_MESH_IN_PROCESS set (a profiler's or mutation testing's); a job cancelled
    while it waits for this process is not meshed."""
    import os
    import threading

    from rigfem.cache import NO_CACHE
    from rigfem.errors import ComputeError
    from rigfem.mesh import mesher, worker

    monkeypatch.setattr(mesher, "_mesh", lambda part, settings, limit, key: os.getpid())
    monkeypatch.setattr(worker, "call", lambda fn, *args, **kw: "child")  # what the mesher process runs
    monkeypatch.delenv(mesher.IN_PROCESS_ENV, raising=False)
    assert mesher.make_mesh(None, None, "k", {}, NO_CACHE) == "child"
    monkeypatch.setenv(mesher.IN_PROCESS_ENV, "0")
    assert mesher.make_mesh(None, None, "k", {}, NO_CACHE) == "child"
    monkeypatch.setenv(mesher.IN_PROCESS_ENV, "1")
    assert mesher.make_mesh(None, None, "k", {}, NO_CACHE) == os.getpid()
    cancelled = threading.Event()
    cancelled.set()
    with pytest.raises(ComputeError, match="cancelled"):
        mesher.make_mesh(None, None, "k", {}, NO_CACHE, cancel=cancelled)
