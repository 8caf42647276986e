"""Load vectors: resultants against the applied forces and closed-form body loads."""

import re

import numpy as np
import pytest
from fe_shapes import bar_with_holes, box

from rigfem.errors import InputError
from rigfem.fe import (
    BearingLoad,
    BoltCircleTorque,
    Gravity,
    Inertia,
    Pressure,
    SurfaceForce,
    Symmetry,
    Torque,
    Traction,
    build_model,
    fe_mesh,
    load_matrix,
    load_vector,
    solve,
)
from rigfem.material import get_material

RHO = 7.85e-9


@pytest.fixture(scope="module")
def bar():
    part = bar_with_holes(120, 25, 10, 4, [20, 60, 100], size=5, h_hole=1.5)
    return part, fe_mesh(part, 2)


def resultant(fm, f, about):
    F = f.reshape(-1, 3)
    return F.sum(0), np.cross(fm.nodes - about, F).sum(0)


def test_bearing_load_resultant_equals_force(bar):
    part, fm = bar
    F = np.array([300.0, -400.0, 0.0])
    f = load_vector(fm, part.holes, RHO, BearingLoad("h0", F))
    c = part.holes["h0"].center
    force, moment = resultant(fm, f, c)
    assert np.allclose(force, F, rtol=0, atol=1e-12 * 500)
    assert abs(moment[2]) < 1e-3 * 500 * 4  # radial pressure: no moment about the pin axis
    # pressure acts only on the half of the wall the pin pushes on (up to the 90°-turned correction)
    x = fm.nodes - c
    fn = f.reshape(-1, 3)
    back = (x[:, :2] @ (F[:2] / 500)) < -2.0  # cos θ < -1/2
    assert np.abs(fn[back]).sum() < 1e-3 * np.abs(fn).sum()
    with pytest.raises(InputError, match="perpendicular"):
        load_vector(fm, part.holes, RHO, BearingLoad("h0", (0, 0, 10)))
    with pytest.raises(InputError, match="not in the part"):
        load_vector(fm, part.holes, RHO, BearingLoad("h9", F))


def test_a_bearing_load_is_the_cosine_pressure_up_to_tiny_corrections(bar):
    """The exact-resultant corrections only cancel the cosine pressure's discretisation error: the
    load is p0·max(cos θ, 0) on the wall to 1e-4 of itself (1.7e-5 on this mesh)."""
    from rigfem.fe.forces import _cosine

    part, fm = bar
    h = part.holes["h0"]
    F = np.array([300.0, -400.0, 0.0])
    f = load_vector(fm, part.holes, RHO, BearingLoad("h0", F))
    f0 = _cosine(fm, "h0", np.asarray(h.center, float), np.asarray(h.axis, float), F / 500.0, h.depth)
    assert np.linalg.norm(f - (f @ f0) / (f0 @ f0) * f0) < 1e-4 * np.linalg.norm(f)


def test_torque_and_bolt_circle_resultants(bar):
    part, fm = bar
    c = part.holes["h1"].center
    for load in (Torque("h1", 2500.0), BoltCircleTorque(("h0", "h2"), 2500.0)):
        force, moment = resultant(fm, load_vector(fm, part.holes, RHO, load), c)
        assert np.allclose(force, 0, atol=1e-11 * 2500)
        assert moment[2] == pytest.approx(2500.0, rel=1e-12)
    # bolt circle: each bolt bears T / (n r) tangentially (r = 40 mm, n = 2)
    f0 = load_vector(fm, part.holes, RHO, BoltCircleTorque(("h0", "h2"), 2500.0)).reshape(-1, 3)
    on_h0 = np.linalg.norm(fm.nodes[:, :2] - [20, 0], axis=1) < 4.5
    assert np.allclose(f0[on_h0].sum(0), [0, -2500 / 80, 0], atol=1e-9)


def test_a_bolt_circle_turns_about_its_first_holes_axis(bar):
    """A bolt circle's holes may face either way (parallel or opposite axes): the torque is
    right-handed about the first hole's axis, whichever way the others face."""
    import dataclasses

    part, fm = bar
    h2 = part.holes["h2"]
    holes = dict(part.holes, h2=dataclasses.replace(h2, axis=-np.asarray(h2.axis)))
    for names, sign in ((("h0", "h2"), 1.0), (("h2", "h0"), -1.0)):  # h0 faces +z, the turned h2 -z
        f = load_vector(fm, holes, RHO, BoltCircleTorque(names, 2500.0))
        force, moment = resultant(fm, f, part.holes["h1"].center)
        assert np.allclose(force, 0, atol=1e-11 * 2500)
        assert moment[2] == pytest.approx(sign * 2500.0, rel=1e-12)


def test_a_torque_is_a_uniform_shear_along_the_bore(bar):
    """Not just its resultant: the work of the torque's nodal forces on the twist u = ζ² a × (x − c)
    (ζ = axial distance / depth from mid-depth) is that of the uniform shear τ = T / (2π R² h),
    ∫ ζ² τ R dA = T / 12 (a shear concentrated towards mid-depth gives less), and every nodal force
    points along the tangent in the torque's sense."""
    part, fm = bar
    h = part.holes["h1"]
    c, a = np.asarray(h.center), np.asarray(h.axis)
    f = load_vector(fm, part.holes, RHO, Torque("h1", 2500.0)).reshape(-1, 3)
    d = fm.nodes - c
    u = ((d @ a) / h.depth)[:, None] ** 2 * np.cross(a, d)
    assert (f * u).sum() == pytest.approx(2500.0 / 12, rel=1e-3)
    on = np.linalg.norm(f, axis=1) > 0  # the bore's nodes: each force along the tangent, in T's sense
    r = d[on] - np.outer(d[on] @ a, a)
    tangent = np.einsum("ij,ij->i", f[on], np.cross(a, r / np.linalg.norm(r, axis=1, keepdims=True)))
    radial = np.einsum("ij,ij->i", f[on], r / np.linalg.norm(r, axis=1, keepdims=True))
    assert tangent.min() > 0 and np.abs(radial).sum() < 0.02 * tangent.sum()


@pytest.mark.parametrize("turn", [[2, 0, 1], [1, 2, 0]])  # the bores' axis along x, along y
def test_a_torque_about_a_bore_along_any_axis(bar, turn):
    """The same bar turned (a cyclic permutation of the axes, a rotation): the torque's resultant is
    T about the bore's axis and no force, whichever axis the bore has."""
    import dataclasses

    from rigfem.mesh.partmesh import Hole

    part, _ = bar
    turned = dataclasses.replace(part, points=part.points[:, turn],
                                 curved_points=part.curved_points[:, turn] if len(part.curved_points) else part.curved_points,
                                 holes={k: Hole(h.center[turn], h.axis[turn], h.radius, h.depth) for k, h in part.holes.items()})
    fm = fe_mesh(turned, 2)
    hole = turned.holes["h1"]
    force, moment = resultant(fm, load_vector(fm, turned.holes, RHO, Torque("h1", 2500.0)), hole.center)
    assert np.allclose(force, 0, atol=1e-11 * 2500)
    assert moment == pytest.approx(2500.0 * hole.axis, abs=1e-9 * 2500)


def test_surface_force_and_pressure_resultants():
    fm = fe_mesh(box(3, 2, 1, 3, 2, 2), 2)
    force, _ = resultant(fm, load_vector(fm, {}, RHO, SurfaceForce("xmax", (1, 2, 3))), 0)
    assert np.allclose(force, [1, 2, 3], atol=1e-13)
    force, _ = resultant(fm, load_vector(fm, {}, RHO, Pressure("ymax", 5.0)), 0)
    assert np.allclose(force, [0, -5.0 * 3 * 1, 0], atol=1e-12)  # p·A into the body (−y on the y=2 face)


def test_traction_in_mpa_is_force_per_area(bar):
    """A traction t (MPa) on a face of area A gives the resultant t·A (N): on a flat face and on
    a curved hole wall (π d t of the bar's hole, followed by the curved P2 faces)."""
    fm = fe_mesh(box(3, 2, 1, 3, 2, 2), 2)
    force, _ = resultant(fm, load_vector(fm, {}, RHO, Traction("xmax", (10.0, -4.0, 2.5))), 0)
    assert np.allclose(force, np.array([10.0, -4.0, 2.5]) * 2 * 1, atol=1e-12)
    part, fm = bar
    force, _ = resultant(fm, load_vector(fm, part.holes, RHO, Traction("h1", (0, 0, 3.0))), 0)
    assert force[2] == pytest.approx(3.0 * np.pi * 8 * 10, rel=1e-4)
    with pytest.raises(InputError, match="traction_mpa"):
        load_vector(fm, part.holes, RHO, Traction("h1", (np.nan, 0, 0)))


def test_bar_in_tension_by_a_traction_has_uniform_stress():
    """Bar 40 × 6 × 4 mm, end face pulled by σ = 50 MPa, held by symmetry planes at the other end:
    σxx = σ everywhere, the other components 0, end displacement σL/E (exact for a linear field)."""
    sigma, L = 50.0, 40.0
    steel = get_material("rig_steel")
    model = build_model(box(L, 6, 4, 8, 2, 2), steel, 2)
    sol = solve(model, [Symmetry("xmin"), Symmetry("ymin"), Symmetry("zmin")], [Traction("xmax", (sigma, 0, 0))])
    s = sol.stress()
    assert np.allclose(s[:, 0], sigma, rtol=1e-8) and np.abs(s[:, 1:]).max() < 1e-8 * sigma
    tip = np.isclose(model.mesh.nodes[:, 0], L)
    assert np.allclose(sol.displacement()[tip, 0], sigma * L / steel.E, rtol=1e-8)


def test_gravity_and_inertia_match_rigid_body_dynamics():
    """Σf = −m(a0 + α×rG + ω×(ω×rG)), moment about G = −(I_G α + ω×I_G ω) for a box; exact (polynomial)."""
    a, b, h = 100.0, 20.0, 10.0
    fm = fe_mesh(box(a, b, h, 6, 2, 2, jitter=0.2), 2)
    m = RHO * a * b * h
    G = np.array([a, b, h]) / 2
    g = np.array([0, 0, -9810.0])
    force, _ = resultant(fm, load_vector(fm, {}, RHO, Gravity(g)), 0)
    assert np.allclose(force, m * g, rtol=1e-12)
    o = np.array([5.0, -3.0, 1.0])
    a0, al, om = np.array([1e3, -2e3, 0]), np.array([0, 0, 50.0]), np.array([0, 0, 2 * np.pi])
    f = load_vector(fm, {}, RHO, Inertia(tuple(a0), tuple(al), tuple(om), tuple(o)))
    force, moment = resultant(fm, f, G)
    r = G - o
    assert np.allclose(force, -m * (a0 + np.cross(al, r) + np.cross(om, np.cross(om, r))), rtol=1e-12)
    Iz = m * (a**2 + b**2) / 12
    assert moment[2] == pytest.approx(-Iz * al[2], rel=1e-12)
    # the same closed forms through a model's load matrix, which combines 12 body-force basis
    # vectors built once per mesh and density (rigfem.fe.forces.body_basis) instead of integrating
    steel = get_material("rig_steel")
    model = build_model(box(a, b, h, 6, 2, 2, jitter=0.2), steel, 2)
    ms = steel.density * a * b * h
    F = load_matrix(model, [Gravity(g), Inertia(tuple(a0), tuple(al), tuple(om), tuple(o))])
    force, _ = resultant(model.mesh, F[:, 0], 0)
    assert np.allclose(force, ms * g, rtol=1e-12)
    force, moment = resultant(model.mesh, F[:, 1], G)
    assert np.allclose(force, -ms * (a0 + np.cross(al, r) + np.cross(om, np.cross(om, r))), rtol=1e-12)
    assert moment[2] == pytest.approx(-ms * (a**2 + b**2) / 12 * al[2], rel=1e-12)
    from rigfem.fe.forces import body_basis

    assert np.allclose(body_basis(model.mesh, 2 * steel.density)[0], 2 * body_basis(model.mesh, steel.density)[0])


def test_a_surface_the_checks_missed_is_a_compute_error_naming_the_surfaces(bar):
    """Inside the FE a surface name is trusted (rigfem.fe.inputs checked it): one that is not in
    the mesh is a bug, reported as a ComputeError that lists the mesh's surfaces."""
    from rigfem.errors import ComputeError
    from rigfem.fe.supports import _triangles

    _, fm = bar
    with pytest.raises(ComputeError, match=re.escape(f"available: {', '.join(fm.surfaces)}")):
        _triangles(fm, "no_such_face")
