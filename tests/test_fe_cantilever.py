"""Cantilever vs beam theory, unit-system invariance, linearity, and support errors."""

import dataclasses

import numpy as np
import pytest
from fe_shapes import box

from rigfem.errors import InputError
from rigfem.fe import Fixed, SurfaceForce, Symmetry, build_model, solve
from rigfem.material import Material, get_material

L, B, H, F = 200.0, 10.0, 10.0, -100.0  # mm, N; L/H = 20


@pytest.fixture(scope="module")
def cantilever():
    model = build_model(box(L, B, H, 40, 2, 2), get_material("rig_steel"), 2)
    return model, solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 0, F))])


def test_tip_deflection_timoshenko(cantilever):
    """Tip deflection vs Timoshenko beam FL³/3EI + FL/κGA (κ = 10(1+ν)/(12+11ν), Cowper 1966): ≤ 1 %."""
    model, sol = cantilever
    E, nu = model.material.E, model.material.nu
    I, G = B * H**3 / 12, E / (2 * (1 + nu))
    kappa = 10 * (1 + nu) / (12 + 11 * nu)
    exact = F * L**3 / (3 * E * I) + F * L / (kappa * G * B * H)
    tip = np.isclose(model.mesh.nodes[:, 0], L)
    assert sol.displacement()[tip, 2].mean() == pytest.approx(exact, rel=0.01)


def test_root_bending_stress(cantilever):
    """σxx = M c / I on the top fibre near the root, at x = L/4 (5 depths from the clamp): ≤ 1 %.

    At x = 0 itself a fully clamped face has corner singularities (ν ≠ 0); the
    error estimate of the peak there must say so (> 5 %).
    """
    model, sol = cantilever
    x = model.mesh.nodes
    xs = L / 4
    top = np.isclose(x[:, 0], xs) & np.isclose(x[:, 2], H)
    assert sol.stress()[top, 0].mean() == pytest.approx(-F * (L - xs) * (H / 2) / (B * H**3 / 12), rel=0.01)
    assert sol.peak().error_pct > 5
    assert sol.residuals.max() < 1e-8 and sol.equilibrium_error.max() < 1e-7
    assert np.allclose(sol.principal()[:, 0] + sol.principal()[:, 1] + sol.principal()[:, 2],
                       sol.stress()[:, :3].sum(1), atol=1e-9 * sol.peak().value)
    r = sol.support_reactions["Fixed(xmin)"][0]
    assert np.allclose(r[:3], [0, 0, -F], atol=1e-8 * abs(F))


def test_unit_system_invariance():
    """The same cantilever in mm–N–MPa and m–N–Pa gives the same physical answers."""
    part = box(L, B, H, 10, 2, 2)
    mat = get_material("rig_steel")
    sol_mm = solve(build_model(part, mat, 2), [Fixed("xmin")], [SurfaceForce("xmax", (0, 30, F))])
    part_m = dataclasses.replace(part, points=part.points / 1000)
    mat_si = Material("steel_si", mat.E * 1e6, mat.nu, mat.sigma_u * 1e6, mat.density * 1e12)
    sol_m = solve(build_model(part_m, mat_si, 2), [Fixed("xmin")], [SurfaceForce("xmax", (0, 30, F))])
    assert np.allclose(sol_m.U * 1000, sol_mm.U, rtol=1e-8, atol=1e-10 * abs(sol_mm.U).max())
    assert np.allclose(sol_m.nodal_stress / 1e6, sol_mm.nodal_stress, rtol=1e-8,
                       atol=1e-9 * abs(sol_mm.nodal_stress).max())
    assert sol_m.peak().value / 1e6 == pytest.approx(sol_mm.peak().value, rel=1e-8)


def test_linearity_over_twelve_decades():
    """Loads 1e-6 … 1e6 N give proportional displacements (to 1e-8, the round-off of the solve)."""
    model = build_model(box(L, B, H, 10, 2, 2), get_material("rig_steel"), 2)
    mags = [1e-6, 1e-3, 1.0, 1e3, 1e6]
    sol = solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, m, -m)) for m in mags])
    ref = sol.U[:, 2] / mags[2]
    for k, m in enumerate(mags):
        assert np.allclose(sol.U[:, k] / m, ref, rtol=1e-8, atol=1e-10 * abs(ref).max())
        assert np.isfinite(sol.nodal_stress[k]).all()


def test_missing_or_insufficient_supports_raise():
    model = build_model(box(L, B, H, 4, 1, 1), get_material("rig_steel"), 1)
    load = [SurfaceForce("xmax", (0, 0, F))]
    with pytest.raises(InputError, match="supports: none"):
        solve(model, [], load)
    with pytest.raises(InputError, match="rigid-body mode"):
        solve(model, [Symmetry("xmin")], load)  # y, z translations and x rotation free
    with pytest.raises(InputError, match="rigid-body mode"):
        solve(model, [Symmetry("xmin"), Symmetry("ymin")], load)
    with pytest.raises(InputError, match="not in the mesh"):
        solve(model, [Fixed("nowhere")], load)
