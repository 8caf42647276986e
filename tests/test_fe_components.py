"""FixedComponents: chosen displacement components held on a surface or on the edge of two surfaces."""

from __future__ import annotations

import numpy as np
import pytest
from fe_shapes import box

from rigfem.errors import InputError
from rigfem.fe import FixedComponents, Pressure, build_model, solve
from rigfem.material import Material

MAT = Material("test", E=200e3, nu=0.3, sigma_u=500.0, density=7.85e-9)
P = 10.0  # MPa tension on xmax


def test_uniaxial_tension_held_on_a_face_and_two_edge_lines():
    """Box 0 < x < 40 pulled by p on xmax; held by u_x on xmin, u_y on the edge line xmin∩ymin and u_z
    on the edge line xmin∩zmin only.  Exact: σxx = p uniform, u = (p/E·x, −νp/E·y, −νp/E·z), which
    vanishes exactly where held, so P1 must reproduce it to round-off (a patch test of the support)."""
    part = box(40.0, 10.0, 8.0, 6, 3, 2)
    model = build_model(part, MAT, order=1)
    sup = [FixedComponents("xmin", "x"), FixedComponents("xmin", "y", edge_with="ymin"),
           FixedComponents("xmin", "z", edge_with="zmin")]
    sol = solve(model, sup, [Pressure("xmax", -P)])
    x = model.mesh.nodes
    eps = P / MAT.E
    exact = np.column_stack([eps * x[:, 0], -MAT.nu * eps * x[:, 1], -MAT.nu * eps * x[:, 2]])
    assert np.abs(sol.displacement() - exact).max() < 1e-9 * np.abs(exact).max()
    s = sol.stress()
    assert np.allclose(s[:, 0], P, rtol=1e-9) and np.abs(s[:, 1:]).max() < 1e-8 * P
    # the line supports hold exactly the nodes on their edge, one component each (4 nodes along z, 3 along y)
    dofs = sol.support_dofs
    line_y = dofs["FixedComponents(xmin, y, edge_with=ymin)"]
    line_z = dofs["FixedComponents(xmin, z, edge_with=zmin)"]
    face = dofs["FixedComponents(xmin, x)"]  # the face support, no edge: u_x of every node on x = 0
    assert np.array_equal(np.sort(face // 3), np.flatnonzero(x[:, 0] == 0)) and set(face % 3) == {0}
    assert len(line_y) == 3 and set(line_y % 3) == {1} and np.allclose(x[line_y // 3, :2], 0)
    assert len(line_z) == 4 and set(line_z % 3) == {2} and np.allclose(x[line_z // 3][:, [0, 2]], 0)


def test_bad_input():
    model = build_model(box(10.0, 10.0, 10.0, 2, 2, 2), MAT, order=1)
    for sup, match in ((FixedComponents("xmin", "w"), "components"), (FixedComponents("xmin", "xx"), "components"),
                       (FixedComponents("xmin", ""), "components"), (FixedComponents("nope", "x"), "nope"),
                       (FixedComponents("xmin", "x", edge_with="xmax"), "share 0 node")):
        with pytest.raises(InputError, match=match):
            solve(model, [sup], [Pressure("xmax", 1.0)])
    with pytest.raises(InputError, match="rigid-body"):  # u_x on a face alone leaves 3 modes free
        solve(model, [FixedComponents("xmin", "x")], [Pressure("xmax", 1.0)])
