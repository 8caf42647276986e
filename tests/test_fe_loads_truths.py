"""Load vectors against independent truths, with a general rotation and on curved P2 surfaces.

* Rigid-body d'Alembert load on a box (ρ in t/mm³, accelerations in mm/s², so N): the
  resultant of −ρ·a(x), a(x) = a0 + α×(x − o) + ω×(ω×(x − o)), is −m·a(G), and its moment about
  the centroid G is −(J_G α + ω × J_G ω), J_G = m/12·diag(b² + h², l² + h², l² + b²).  The field
  is linear, so the consistent P2 vector gives both exactly; α has three non-zero, unequal
  components so every entry of the cross-product matrix [α]× counts.
* A SurfaceForce's resultant is its force F exactly on any surface, curved or flat (the P2
  shape functions sum to 1 and the traction is F divided by the area of the same rule).
* The resultant of a pressure p on an open surface S is −p ∫_S n dA, and the vector area
  ∫_S n dA = ½ ∮ x × dx depends only on the boundary curve.  The inner (outer) wall of a
  quarter tube a < r < b, 0 < z < h has for boundary two straight vertical sides and the same
  planar curve at z = 0 and z = h, so its vector area is −a·h·(1, 1, 0) (b·h·(1, 1, 0))
  whatever the curve between the corners: also for the P2 wall, whose area-weighted normal
  (∂x/∂ξ1 × ∂x/∂ξ2, degree 2) the degree-2 rule integrates exactly.
"""

import numpy as np
import pytest
from fe_shapes import box, quarter_ring

from rigfem.fe import Inertia, Pressure, SurfaceForce, build_model, fe_mesh, load_matrix, load_vector
from rigfem.material import get_material

A, B, H = 10.0, 20.0, 8.0  # quarter tube: inner radius, outer radius, height (mm)


@pytest.fixture(scope="module")
def tube():
    """The quarter tube in P2, its walls curved (mid-side nodes on the cylinders, off the chords)."""
    part = quarter_ring(A, B, H, size=6.0)
    fm = fe_mesh(part, 2)
    x = fm.nodes[fm.surfaces["inner"]]
    assert np.abs(x[:, 3:] - 0.5 * (x[:, [0, 1, 2]] + x[:, [1, 2, 0]])).max() > 0.1  # really curved
    return part, fm


def resultant(nodes, f, about):
    F = f.reshape(-1, 3)
    return F.sum(0), np.cross(nodes - about, F).sum(0)


def close(v, truth, rel=1e-12):
    return np.linalg.norm(np.asarray(v) - truth) <= rel * np.linalg.norm(truth)


def test_inertia_with_a_general_angular_acceleration_matches_rigid_body_dynamics():
    """Force −m·a(G) and moment −(J_G α + ω×J_G ω) about G of a box, α = (30, −70, 110) rad/s²
    (all three components, unequal), ω = 0 and ω general: through a model's load matrix (the
    12 body-basis weights of body_coefficients) and through load_vector (direct integration)."""
    lx, ly, lz = 40.0, 30.0, 20.0
    steel = get_material("rig_steel")  # density in t/mm³: with mm/s² the loads are in N
    model = build_model(box(lx, ly, lz, 3, 2, 2, jitter=0.2), steel, 2)
    m = steel.density * lx * ly * lz
    G = np.array([lx, ly, lz]) / 2
    J = m / 12 * np.diag([ly**2 + lz**2, lx**2 + lz**2, lx**2 + ly**2])
    a0, al, o = np.array([1e3, -2e3, 500.0]), np.array([30.0, -70.0, 110.0]), np.array([5.0, -3.0, 1.0])
    cases = [(a0, al, np.zeros(3)), (a0, al, np.array([2.0, -1.5, 4.0]))]
    loads = [Inertia(tuple(a0), tuple(al), tuple(om), tuple(o)) for a0, al, om in cases]
    F = load_matrix(model, loads)
    r = G - o
    for k, (load, (a0, al, om)) in enumerate(zip(loads, cases)):
        force_truth = -m * (a0 + np.cross(al, r) + np.cross(om, np.cross(om, r)))
        moment_truth = -(J @ al + np.cross(om, J @ om))
        for f in (F[:, k], load_vector(model.mesh, {}, steel.density, load)):
            force, moment = resultant(model.mesh.nodes, f, G)
            assert close(force, force_truth), (force, force_truth)
            assert close(moment, moment_truth), (moment, moment_truth)


@pytest.mark.parametrize("wall", ["inner", "outer"])
def test_a_surface_force_on_a_curved_wall_has_resultant_exactly_its_force(tube, wall):
    """ΣF of a SurfaceForce on a curved P2 wall is F to 1e-12: the traction F / (area) must be
    divided by the area of the rule it is integrated with (another rule's area differs on curved
    triangles, by 3e-6 relative on the inner wall here)."""
    part, fm = tube
    F = np.array([3.0, -5.0, 7.0])
    force, _ = resultant(fm.nodes, load_vector(fm, part.holes, 0.0, SurfaceForce(wall, tuple(F))), 0.0)
    assert close(force, F), force - F


@pytest.mark.parametrize(("wall", "vector_area"), [("inner", -A * H * np.array([1.0, 1.0, 0.0])),
                                                   ("outer", B * H * np.array([1.0, 1.0, 0.0]))])
def test_a_pressure_on_a_curved_wall_gives_p_times_its_vector_area(tube, wall, vector_area):
    """Σf = −p ∫ n dA = −p·(vector area from the boundary), to 1e-12, on the curved P2 walls of a
    quarter tube: exact only if the curved surface's normals are integrated exactly (a constant
    normal per triangle is off by ~1e-6 relative here)."""
    part, fm = tube
    p = 2.0
    force, _ = resultant(fm.nodes, load_vector(fm, part.holes, 0.0, Pressure(wall, p)), 0.0)
    assert close(force, -p * vector_area), (force, -p * vector_area)
