"""Constant-strain patch test: a distorted mesh must reproduce a uniform stress state exactly."""

import numpy as np
import pytest
from fe_shapes import box

from rigfem.fe import SurfaceForce, Symmetry, build_model, quadrature_stress, solve
from rigfem.material import get_material


@pytest.mark.parametrize("order", [1, 2])
def test_patch_triaxial_uniform_stress_exact(order):
    # faces x=2, y=1, z=1 pulled with uniform tractions 30, -20, 10 MPa; symmetry on x=0, y=0, z=0.
    lx, ly, lz = 2.0, 1.0, 1.0
    sx, sy, sz = 30.0, -20.0, 10.0
    mat = get_material("rig_steel")
    model = build_model(box(lx, ly, lz, 4, 2, 2, jitter=0.25, seed=3), mat, order)
    sol = solve(model, [Symmetry("xmin"), Symmetry("ymin"), Symmetry("zmin")],
                [[SurfaceForce("xmax", (sx * ly * lz, 0, 0)), SurfaceForce("ymax", (0, sy * lx * lz, 0)),
                  SurfaceForce("zmax", (0, 0, sz * lx * ly))]])
    exact = np.array([sx, sy, sz, 0, 0, 0])
    s_q, _ = quadrature_stress(model.mesh, mat.E, mat.nu, sol.U)
    assert np.abs(s_q[:, :, 0] - exact).max() <= 1e-9 * 30
    assert np.abs(sol.stress() - exact).max() <= 1e-9 * 30
    # Hooke's law: u = ε x, exactly at every node
    E, nu = mat.E, mat.nu
    eps = np.array([sx - nu * (sy + sz), sy - nu * (sx + sz), sz - nu * (sx + sy)]) / E
    assert np.abs(sol.displacement() - model.mesh.nodes * eps).max() <= 1e-9 * np.abs(eps).max() * lx
    assert sol.peak().zz_error <= 1e-9 and sol.peak().error_pct <= 1e-7
