"""FE building blocks against mathematics and closed forms (issue 39: the fe package's mutants).

* Quadrature: the tetrahedron and triangle rules integrate monomials exactly (∫ L1^a L2^b L3^c
  = a! b! c! / (a+b+c+n)! · n! |T|, the barycentric moment formula); P2 shape functions are 1
  at their node, 0 at the others, and sum to 1; a mesh's volume and its quadrature points are
  the box's.
* Invariants: von Mises from the principal stresses, principal stresses' sum and product are the
  trace and determinant; the chunked peak sweep equals the brute-force maximum over every node.
* A shaft in a hole (elastic foundation, radial modulus E/r, tangential and axial 1e-3 of it):
  a rigid translation u of the wall is resisted by (k_r + k_t)·π r h·u across the axis and
  k_a·2π r h·u along it; a rigid rotation about the axis by k_t·2π r³ h.
* Boundary corner nodes of a box are those on its faces (and every mid-edge node on a face); a solution kept to some combinations answers
  every figure of them as before; resultants are Σ f and Σ x × f.
"""

from math import factorial

import numpy as np
import pytest
from fe_shapes import bar_with_holes, box

from rigfem.errors import ComputeError
from rigfem.fe import Fixed, FreeBody, ShaftInHole, SurfaceForce, build_model, fe_mesh, solve
from rigfem.fe.assembly import NODE_BARY, points_at, shape_values, tet_quadrature, tri_quadrature, volume
from rigfem.fe.supports import shaft_springs, surface_quadrature
from rigfem.tensors import peak_von_mises, principal, von_mises
from rigfem.material import get_material

STEEL = get_material("rig_steel")
E_NU_LAME = (STEEL.E * STEEL.nu / ((1 + STEEL.nu) * (1 - 2 * STEEL.nu)), STEEL.E / (2 * (1 + STEEL.nu)))  # λ, μ


@pytest.mark.parametrize("degree", [1, 2, 3, 4])  # the rules rigfem uses: 2 (order − 1), 3
def test_tetrahedron_rules_integrate_monomials_exactly(degree):
    L, W = tet_quadrature(degree)
    assert W.sum() == pytest.approx(1 / 6, rel=1e-13) and np.allclose(L.sum(1), 1.0)
    for a in range(degree + 1):
        for b in range(degree + 1 - a):
            c = degree - a - b
            exact = factorial(a) * factorial(b) * factorial(c) * factorial(3) / factorial(a + b + c + 3) / 6
            assert (L[:, 1] ** a * L[:, 2] ** b * L[:, 3] ** c) @ W == pytest.approx(exact, rel=1e-12), (a, b, c)


@pytest.mark.parametrize("degree", [1, 2, 4, 6])
def test_triangle_rules_integrate_monomials_exactly(degree):
    L, W = tri_quadrature(degree)
    assert W.sum() == pytest.approx(0.5, rel=1e-13) and np.allclose(L.sum(1), 1.0)
    for a in range(degree + 1):
        b = degree - a
        exact = factorial(a) * factorial(b) * factorial(2) / factorial(a + b + 2) / 2
        assert (L[:, 1] ** a * L[:, 2] ** b) @ W == pytest.approx(exact, rel=1e-12), (a, b)


def test_p2_shape_functions_are_nodal_and_a_partition_of_unity():
    assert np.allclose(shape_values(NODE_BARY, 2), np.eye(10), atol=1e-15)
    assert np.allclose(shape_values(NODE_BARY[:4], 1), np.eye(4))
    L, _ = tet_quadrature(4)
    assert np.allclose(shape_values(L, 2).sum(1), 1.0)
    tri = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0.5, 0], [0, 0.5, 0.5], [0.5, 0, 0.5]], float)
    assert np.allclose(shape_values(tri, 2), np.eye(6), atol=1e-15)


@pytest.mark.parametrize("order", [1, 2])
def test_a_box_mesh_has_the_box_volume_and_points_inside(order):
    fm = fe_mesh(box(30.0, 20.0, 10.0, 3, 2, 1, jitter=0.2), order)
    assert volume(fm) == pytest.approx(6000.0, rel=1e-12)
    L, W = tet_quadrature(2)
    pts = points_at(fm, L)
    assert pts.min() >= -1e-12 and (pts.max(axis=(0, 1)) <= [30.0 + 1e-12, 20.0 + 1e-12, 10.0 + 1e-12]).all()
    centroid = (pts * W[None, :, None]).sum((0, 1)) / W.sum() / len(fm.elements)
    assert centroid == pytest.approx([15.0, 10.0, 5.0], rel=1e-9)  # equal-volume elements' mean: not exact


def test_principal_stresses_and_von_mises_are_the_invariants():
    rng = np.random.default_rng(7)
    s = rng.normal(0, 100, (50, 6))
    p = principal(s)
    T = np.stack([np.stack([s[:, 0], s[:, 3], s[:, 5]], -1), np.stack([s[:, 3], s[:, 1], s[:, 4]], -1),
                  np.stack([s[:, 5], s[:, 4], s[:, 2]], -1)], -2)
    assert np.all(p[:, 0] >= p[:, 1]) and np.all(p[:, 1] >= p[:, 2])
    assert np.allclose(p.sum(1), s[:, :3].sum(1)) and np.allclose(p.prod(1), np.linalg.det(T))
    vm = np.sqrt(((p[:, 0] - p[:, 1]) ** 2 + (p[:, 1] - p[:, 2]) ** 2 + (p[:, 2] - p[:, 0]) ** 2) / 2)
    assert np.allclose(von_mises(s), vm)
    assert von_mises(np.array([0.0, 0, 0, 0, 0, 40.0])) == pytest.approx(40 * np.sqrt(3))
    assert von_mises(np.array([0.0, 0, 0, 0, 40.0, 0])) == pytest.approx(40 * np.sqrt(3))
    assert von_mises(np.array([0.0, 50.0, 0, 0, 0, 0])) == pytest.approx(50.0)
    assert von_mises(np.array([0.0, 0, 60.0, 0, 0, 0])) == pytest.approx(60.0)


@pytest.mark.parametrize("chunk", [1, 3, 8])
def test_the_peak_sweep_is_the_brute_force_maximum(chunk):
    rng = np.random.default_rng(3)
    S = rng.normal(0, 1, (5, 400, 6))
    S[2] *= 10  # one dominant field
    C = rng.normal(0, 1, (23, 5))
    C[4] = 0.0  # a row without load
    C[:, 3] = 0.0  # a load no row uses
    vals, nodes = peak_von_mises(C, S, chunk=chunk)
    brute = von_mises(np.tensordot(C, S, 1))
    assert np.allclose(vals, brute.max(1), rtol=1e-12) and np.array_equal(nodes[C.any(1)], brute.argmax(1)[C.any(1)])
    assert vals[4] == 0.0
    assert np.allclose(peak_von_mises(C, S, von_mises(S), chunk)[0], vals)
    assert np.array_equal(peak_von_mises(np.zeros((2, 5)), S)[0], [0.0, 0.0])
    one = np.zeros_like(C)
    one[:, 2] = C[:, 2]  # a single load case in use
    assert np.allclose(peak_von_mises(one, S, chunk=chunk)[0], von_mises(np.tensordot(one, S, 1)).max(1), rtol=1e-12)
    few = S[:, :10]  # fewer nodes than the 16 the bound starts from
    assert np.allclose(peak_von_mises(C, few, chunk=chunk)[0], von_mises(np.tensordot(C, few, 1)).max(1), rtol=1e-12)


@pytest.fixture(scope="module")
def holed_part():
    """The gmsh mesh of a bar with a bore, made once (meshing is not the fe package's code)."""
    return bar_with_holes(60.0, 30.0, 8.0, 5.0, [30.0], size=4.0, h_hole=1.0)


@pytest.fixture  # per test: mutation testing credits the FE mesh (rigfem.fe) to every test that builds it
def holed(holed_part):
    return holed_part, fe_mesh(holed_part, 2)


def test_a_shaft_in_a_hole_resists_rigid_motions_as_its_foundation(holed):
    part, fm = holed
    hole = part.holes["h0"]
    r, h, E = hole.radius, 8.0, STEEL.E
    kr = E / r
    K = shaft_springs(fm, hole, ShaftInHole("h0"), E)
    c = np.asarray(hole.center, float)

    def force(u_of_x):
        U = u_of_x(fm.nodes).ravel()
        return (K @ U).reshape(-1, 3)

    across = force(lambda x: np.broadcast_to([1.0, 0.0, 0.0], x.shape)).sum(0)
    assert across == pytest.approx([(kr + 1e-3 * kr) * np.pi * r * h, 0.0, 0.0], rel=2e-3, abs=1e-6 * kr * r * h)
    along = force(lambda x: np.broadcast_to([0.0, 0.0, 1.0], x.shape)).sum(0)
    assert along == pytest.approx([0.0, 0.0, 1e-3 * kr * 2 * np.pi * r * h], rel=2e-3, abs=1e-9 * kr * r * h)
    twist = force(lambda x: np.stack([-(x[:, 1] - c[1]), x[:, 0] - c[0], 0 * x[:, 0]], 1))  # unit rotation about z
    moment = np.cross(fm.nodes - c, twist).sum(0)[2]
    assert moment == pytest.approx(1e-3 * kr * 2 * np.pi * r**3 * h, rel=5e-3)
    soft = shaft_springs(fm, hole, ShaftInHole("h0", k_radial=2.0, k_tangential=0.0, k_axial=0.0), E)
    U = np.tile([1.0, 0.0, 0.0], len(fm.nodes))
    assert (soft @ U).reshape(-1, 3).sum(0)[0] == pytest.approx(2.0 * np.pi * r * h, rel=2e-3)
    # moduli given are the moduli used: no tangential or axial spring when they are 0
    assert np.abs(soft @ np.tile([0.0, 0.0, 1.0], len(fm.nodes))).max() == pytest.approx(0.0, abs=1e-9)
    spin = np.stack([-(fm.nodes[:, 1] - c[1]), fm.nodes[:, 0] - c[0], 0 * fm.nodes[:, 0]], 1).ravel()
    assert np.abs(soft @ spin).max() < 1e-6 * np.abs(soft @ U).max() * r
    stiff = shaft_springs(fm, hole, ShaftInHole("h0", k_radial=2.0, k_tangential=0.5, k_axial=0.25), E)
    assert (stiff @ np.tile([0.0, 0.0, 1.0], len(fm.nodes))).reshape(-1, 3).sum(0)[2] == pytest.approx(
        0.25 * 2 * np.pi * r * h, rel=2e-3)
    pts, w, N, tri = surface_quadrature(fm, "h0", 4)
    assert w.sum() == pytest.approx(2 * np.pi * r * h, rel=1e-4)  # curved P2 wall: its true area
    assert np.allclose(np.hypot(*(pts[..., :2] - c[:2]).transpose(2, 0, 1)), r, atol=1e-3)


def test_a_one_sided_shaft_bears_on_the_half_it_faces(holed):
    """ShaftInHole(direction=d): radial springs only where the wall's normal has n·d > 0 (a shaft
    pressed one way), so a translation along d meets k_r ∫ cos²θ over half the wall, k_r π r h / 2,
    and the other half's nodes carry nothing (no tangential or axial springs here)."""
    part, fm = holed
    hole = part.holes["h0"]
    r, h, c = hole.radius, 8.0, np.asarray(hole.center, float)
    for d in ((1.0, 0.0, 0.0), (0.0, -2.0, 0.0), (0.6, 0.8, 0.5)):  # any length; a part along the axis is ignored
        K = shaft_springs(fm, hole, ShaftInHole("h0", k_radial=2.0, k_tangential=0.0, k_axial=0.0, direction=d), STEEL.E)
        u = np.array(d[:2] + (0.0,)) / np.linalg.norm(d[:2])
        f = (K @ np.tile(u, len(fm.nodes))).reshape(-1, 3)
        assert f.sum(0) @ u == pytest.approx(2.0 * np.pi * r * h / 2, rel=2e-2), d
        behind = (fm.nodes - c) @ u < -0.3 * r
        assert np.abs(f[behind]).max() < 1e-12 * np.abs(f).max(), d


def test_a_solution_kept_to_its_combinations_answers_the_same(holed):
    part, _ = holed
    model = build_model(part, STEEL, 2)
    sol = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0)), SurfaceForce("xmax", (50.0, 0, 0)),
                                         SurfaceForce("xmax", (0, 0, 10.0))])
    C = np.array([[1.0, 0.5, 0.0], [0.0, 2.0, 1.0]])
    brute = [sol.von_mises(c).max() for c in C]
    assert np.allclose(sol.peak_sweep(C)[0], brute, rtol=1e-12)  # the unit fields' von Mises, computed now,
    kept = sol.kept(C)  # are not the kept cases': a kept solution computes its own
    assert kept.cases == 3
    funcs = ("displacement", "stress", "loads", "reaction", "von_mises", "principal")
    for c in C:
        for f in funcs:
            assert np.allclose(getattr(kept, f)(c), getattr(sol, f)(c), rtol=1e-12, atol=1e-12), f
        assert kept.peak(c) == sol.peak(c)
    assert np.allclose(kept.peak_sweep(C)[0], brute, rtol=1e-12)
    assert np.array_equal(kept.equilibrium_error, sol.equilibrium_error)
    again = kept.kept(C[:1])  # a kept solution kept again: its cases copied, not recombined
    for f in funcs:
        assert np.allclose(getattr(again, f)(C[0]), getattr(sol, f)(C[0]), rtol=1e-12, atol=1e-12), f
    assert np.allclose(again.peak_sweep(C[:1])[0], brute[:1], rtol=1e-12)
    for bad in (np.ones((1, 2)), np.array([[np.nan, 1.0, 0.0]])):  # wrong length, not finite: no numbers
        with pytest.raises(ComputeError, match="combination matrix"):
            sol.peak_sweep(bad)
    with pytest.raises(ValueError, match="kept"):
        kept.stress(np.array([1.0, 0.0, 0.0]))
    R = sol.support_reactions["Fixed(xmin)"]  # statics: the clamp carries every load
    assert R[:, :3] == pytest.approx(-np.array([[0, 100.0, 0], [50.0, 0, 0], [0, 0, 10.0]]), abs=1e-6)


def test_boundary_nodes_of_a_box_are_those_on_its_faces():
    model = build_model(box(30.0, 20.0, 10.0, 3, 2, 2), STEEL, 2)
    sol = solve(model, [FreeBody()], [SurfaceForce("xmax", (1.0, 0, 0)), SurfaceForce("xmin", (-1.0, 0, 0))])
    x = model.mesh.nodes
    on_face = (np.isclose(x, 0.0) | np.isclose(x, [30.0, 20.0, 10.0])).any(1)
    b = sol._boundary_nodes()
    nv = model.mesh.n_vertices
    assert {n for n in b if n < nv} == set(np.flatnonzero(on_face[:nv]).tolist())  # corners: exactly the faces'
    assert set(np.flatnonzero(on_face).tolist()) <= b  # mid-edge nodes: every one on a face (and chords between)
    corner = int(np.flatnonzero(np.all(np.isclose(x, [30.0, 20.0, 10.0]), 1))[0])
    assert set(sol.surfaces_of(corner)) == {"xmax", "ymax", "zmax"}
    inner = np.flatnonzero(~on_face)
    assert len(inner) and sol.surfaces_of(int(inner[0])) == ()


def test_boundary_nodes_of_a_meshed_bar_are_those_on_its_walls():
    """An unstructured gmsh mesh (every face orientation of a tet occurs): the corner nodes
    rigfem counts as boundary are exactly those on the bar's walls or its holes' bores, and a
    mid-edge node only where both its corners are."""
    from rigfem.fe.assembly import TET_EDGES

    length, width, thick, radius, xs = 60.0, 20.0, 10.0, 4.0, [20.0, 40.0]
    model = build_model(bar_with_holes(length, width, thick, radius, xs, 5.0), STEEL, 2)
    sol = solve(model, [FreeBody()], [SurfaceForce("xmax", (1.0, 0, 0)), SurfaceForce("xmin", (-1.0, 0, 0))])
    x, el, nv = model.mesh.nodes, model.mesh.elements, model.mesh.n_vertices
    wall = (np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], length) | np.isclose(np.abs(x[:, 1]), width / 2)
            | np.isclose(x[:, 2], 0.0) | np.isclose(x[:, 2], thick)
            | np.any([np.isclose(np.hypot(x[:, 0] - c, x[:, 1]), radius, rtol=1e-6) for c in xs], axis=0))
    b = sol._boundary_nodes()
    assert {n for n in b if n < nv} == set(np.flatnonzero(wall[:nv]).tolist())
    both = {int(el[e, 4 + a]) for a, (i, j) in enumerate(TET_EDGES) for e in np.flatnonzero(wall[el[:, i]] & wall[el[:, j]])}
    assert {n for n in b if n >= nv} == both


def test_resultants_are_the_sum_of_forces_and_of_their_moments():
    """Σ f and Σ x × f about the origin, by hand, of k = 3 load vectors: over every DOF, over a
    support's DOFs in any order, and over single components (a DOF list need not hold whole nodes)."""
    model = build_model(box(30.0, 20.0, 10.0, 3, 2, 2), STEEL, 2)
    sol = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0)), SurfaceForce("ymax", (50.0, 0, 10.0)),
                                         SurfaceForce("zmax", (0, 0, -30.0))])
    x = model.mesh.nodes

    def by_hand(dofs, vec):
        f = np.zeros((len(x), 3, vec.shape[1]))
        f.reshape(-1, vec.shape[1])[dofs] = vec[dofs]
        fc = f.transpose(2, 0, 1)  # (k, n, 3)
        return np.hstack([fc.sum(1), np.cross(x, fc).sum(1)])

    every = np.arange(3 * len(x))
    for dofs in (every, np.random.default_rng(5).permutation(every), sol.support_dofs["Fixed(xmin)"][::-1],
                 every[1::3]):
        for vec in (sol.F, sol.reactions):
            assert np.allclose(sol.resultants(dofs, vec), by_hand(dofs, vec), rtol=1e-12, atol=1e-9)
    assert np.allclose(sol.resultants(every, sol.F)[:, :3], [[0, 100.0, 0], [50.0, 0, 10.0], [0, 0, -30.0]])


@pytest.mark.parametrize("order", [1, 2])
def test_a_nodes_patch_is_the_elements_around_it(order):
    """The ZZ patch of every node (the last ones too) by brute force: the elements holding it."""
    from rigfem.fe.stress import patch

    fm = fe_mesh(box(20.0, 10.0, 10.0, 2, 1, 1), order)
    for node in range(len(fm.nodes)):
        elems, nodes, local = patch(fm, node)
        assert np.array_equal(elems, np.flatnonzero((fm.elements == node).any(1))), node
        assert np.array_equal(nodes, np.unique(fm.elements[elems])) and np.array_equal(nodes[local], fm.elements[elems])


def test_a_peak_names_where_it_is():
    """The peak's surface: a named surface it lies on, else "(unnamed boundary)" on the part's skin,
    else "(interior)" (a box whose y and z faces are not named; the peak placed at chosen nodes)."""
    import dataclasses

    whole = box(30.0, 20.0, 20.0, 3, 2, 2)
    part = dataclasses.replace(whole, surfaces={k: whole.surfaces[k] for k in ("xmin", "xmax")})
    model = build_model(part, STEEL, 2)
    sol = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0))])
    x = model.mesh.nodes

    def at(p):
        return int(np.flatnonzero(np.all(np.isclose(x, p), 1))[0])

    for p, surface, surfaces in (((10.0, 10.0, 10.0), "(interior)", ()), ((10.0, 20.0, 10.0), "(unnamed boundary)", ()),
                                 ((30.0, 10.0, 10.0), "xmax", ("xmax",)), ((5.0, 10.0, 10.0), "(interior)", ())):
        s = sol.nodal_stress.copy()
        s[0, at(p)] = [1e4, 0, 0, 0, 0, 0]
        pk = dataclasses.replace(sol, nodal_stress=s).peak()
        assert (pk.node, pk.surface, pk.surfaces) == (at(p), surface, surfaces), p


def test_a_node_on_a_hole_and_a_face_names_the_hole_first(holed):
    """Where a bore meets a named face, the hole comes first (the peak's surface is the hole, as the
    report locates a pin's stress), even when the face's name sorts before it."""
    import dataclasses

    from rigfem.mesh.partmesh import boundary_faces

    part, _ = holed
    faces = boundary_faces(part.tets)
    bottom = faces[np.all(np.isclose(part.points[faces, 2], 0.0), 1)]
    model = build_model(dataclasses.replace(part, surfaces={**part.surfaces, "a_bottom": bottom}), STEEL, 2)
    sol = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0))])
    x, c = model.mesh.nodes, part.holes["h0"].center
    rim = np.flatnonzero(np.isclose(np.hypot(x[:, 0] - c[0], x[:, 1] - c[1]), part.holes["h0"].radius, rtol=1e-6)
                         & np.isclose(x[:, 2], 0.0))
    assert len(rim) and all(sol.surfaces_of(int(n)) == ("h0", "a_bottom") for n in rim)


def test_the_zz_estimate_is_free_of_scale_and_zero_without_stress(holed):
    """The estimate is a ratio of stresses, so loads a million times smaller (a peak under 1 MPa)
    give the same figure; an unstressed patch has none (0, not a division by zero)."""
    from rigfem.fe.stress import zz_error

    part, _ = holed
    model = build_model(part, STEEL, 2)
    sol = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0))])
    fm, u, s = model.mesh, sol.U[:, 0], sol.nodal_stress[0]
    n = sol.peak().node
    e = zz_error(fm, STEEL.E, STEEL.nu, u, n, s)
    assert 0 < e < 1 and s[n].any()
    assert zz_error(fm, STEEL.E, STEEL.nu, 1e-6 * u, n, 1e-6 * s) == pytest.approx(e, rel=1e-9)
    assert zz_error(fm, STEEL.E, STEEL.nu, 0 * u, n, 0 * s) == 0.0


def test_a_combination_scales_and_is_checked():
    """Linearity: the combination c of one load case is c times it (not the case itself), and a
    combination of the wrong length or not finite gives no numbers."""
    model = build_model(box(30.0, 20.0, 10.0, 3, 2, 2), STEEL, 1)
    one = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0))])
    for f in ("stress", "displacement", "loads", "reaction"):
        assert np.allclose(getattr(one, f)(np.array([-2.5])), -2.5 * getattr(one, f)(), rtol=1e-12, atol=1e-12), f
    two = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 100.0, 0)), SurfaceForce("xmax", (0, 0, 10.0))])
    for bad in (np.ones(3), np.array([np.nan, 1.0]), np.array([1.0, np.inf])):
        with pytest.raises(ComputeError, match="combination coefficients"):
            two.stress(bad)


@pytest.mark.parametrize("order", [1, 2])
def test_nodal_stress_in_batches_is_the_same(order):
    """Batching the elements (chunk) and the load columns (mem) only splits the sums: the same nodal
    stresses as one batch, for a mesh whose last batch is partial."""
    from rigfem.fe.stress import nodal_stress

    fm = fe_mesh(box(20.0, 10.0, 10.0, 4, 2, 2, jitter=0.2), order)
    U = np.random.default_rng(2).normal(0, 1e-3, (fm.ndof, 3))
    whole = nodal_stress(fm, STEEL.E, STEEL.nu, U)
    assert len(fm.elements) % 7 and np.abs(whole).max() > 0
    assert np.allclose(nodal_stress(fm, STEEL.E, STEEL.nu, U, chunk=7, mem=1.0), whole, rtol=1e-12, atol=1e-9)


def test_element_node_stress_is_the_linear_fit_through_the_stiffness_points(holed):
    """On curved P2 elements (a bore's wall) the element's nodal stresses are the linear field
    through its four stiffness quadrature points' stresses (as CalculiX extrapolates C3D10), not a
    fit through another rule's points."""
    from rigfem.fe.stress import element_node_stress, quadrature_stress

    _, fm = holed
    U = np.random.default_rng(4).normal(0, 1e-3, (fm.ndof, 2))
    S, _ = quadrature_stress(fm, STEEL.E, STEEL.nu, U)
    L, _ = tet_quadrature(2)
    assert S.shape[1] == len(L) == 4
    through = NODE_BARY @ np.linalg.inv(L)  # (10, 4): the linear field through the 4 points, at the nodes
    assert np.allclose(element_node_stress(fm, STEEL.E, STEEL.nu, U), np.einsum("aq,mqkc->makc", through, S),
                       rtol=1e-10, atol=1e-6)


def test_principal_stresses_of_stacked_fields():
    """(..., 6) in, (..., 3) out: a (cases, nodes, 6) stack gives each tensor's own eigenvalues."""
    rng = np.random.default_rng(11)
    s = rng.normal(0, 50, (3, 40, 6))
    p = principal(s)
    assert p.shape == (3, 40, 3)
    flat = principal(s.reshape(-1, 6)).reshape(3, 40, 3)
    assert np.allclose(p, flat) and np.all(np.diff(p, axis=-1) <= 0)
    assert np.allclose(von_mises(s), von_mises(s.reshape(-1, 6)).reshape(3, 40))


@pytest.mark.parametrize("order", [1, 2])
def test_stress_at_the_quadrature_points_of_a_uniform_strain(order):
    """u = ε x (two strain states at once): Hooke's uniform stress at each of the stiffness rule's
    points (degree 2(order − 1): 1 point for P1, 4 for P2), which lie where the rule puts them."""
    from rigfem.fe.stress import element_node_stress, quadrature_stress

    fm = fe_mesh(box(20.0, 10.0, 10.0, 2, 1, 1, jitter=0.2), order)
    eps = [np.array([[1e-3, 2e-4, 0], [2e-4, -3e-4, 1e-4], [0, 1e-4, 5e-4]]), np.diag([0.0, 0.0, 1e-3])]
    U = np.stack([(fm.nodes @ e.T).ravel() for e in eps], axis=1)
    lam, mu = E_NU_LAME
    S, X = quadrature_stress(fm, STEEL.E, STEEL.nu, U)
    L, _ = tet_quadrature(2 * (order - 1))
    assert S.shape == (len(fm.elements), len(L), 2, 6) and np.allclose(X, points_at(fm, L))
    for k, e in enumerate(eps):
        sig = lam * np.trace(e) * np.eye(3) + 2 * mu * e
        voigt = [sig[0, 0], sig[1, 1], sig[2, 2], sig[0, 1], sig[1, 2], sig[0, 2]]
        assert np.allclose(S[:, :, k], voigt, rtol=1e-10, atol=1e-9)
        assert np.allclose(element_node_stress(fm, STEEL.E, STEEL.nu, U)[:, :, k], voigt, rtol=1e-10, atol=1e-9)
