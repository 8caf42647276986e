"""Stiffness kernel vs scikit-fem's generic assembly, and basic matrix properties."""

import numpy as np
import pytest
from fe_shapes import box
from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

from rigfem.assembly import fe_mesh, stiffness
from rigfem.errors import InputError
from rigfem.mesh import PartMesh
from rigfem.supports import rigid_modes


@pytest.mark.parametrize("order", [1, 2])
def test_stiffness_equals_skfem_generic(order):
    part = box(3, 2, 1, 3, 2, 2, jitter=0.2)
    fm = fe_mesh(part, order)
    K = stiffness(fm, 210e3, 0.3)
    el = ElementTetP1() if order == 1 else ElementTetP2()
    b = Basis(MeshTet(fm.nodes[:fm.n_vertices].T, fm.elements[:, :4].T), ElementVector(el))
    Ks = asm(linear_elasticity(*lame_parameters(210e3, 0.3)), b)
    perm = np.empty(b.N, dtype=np.int64)  # skfem DOF -> rigfem DOF 3*node + c
    n = fm.n_vertices
    for c in range(3):
        perm[b.nodal_dofs[c]] = 3 * np.arange(n) + c
        if order == 2:
            e = np.sort(b.mesh.edges, 0)
            key = e[0].astype(np.int64) * n + e[1]
            perm[b.edge_dofs[c]] = 3 * (n + np.searchsorted(np.unique(key), key)) + c
            assert np.allclose(fm.nodes[n + np.searchsorted(np.unique(key), key)], b.mesh.p[:, e].mean(1).T)
    assert abs(K[perm][:, perm] - Ks).max() <= 1e-13 * abs(Ks).max()


@pytest.mark.parametrize("order", [1, 2])
def test_stiffness_symmetric_and_rigid_modes_in_kernel(order):
    fm = fe_mesh(box(2, 1, 1, 4, 2, 2, jitter=0.2), order)
    K = stiffness(fm, 210e3, 0.3)
    assert abs(K - K.T).max() <= 1e-12 * abs(K).max()
    assert abs(K @ rigid_modes(fm.nodes)).max() <= 1e-10 * abs(K).max()


def test_bad_mesh_raises():
    with pytest.raises(InputError, match="order"):
        fe_mesh(box(1, 1, 1, 1, 1, 1), 3)
    p = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0.0]])
    with pytest.raises(InputError, match="degenerate"):
        fe_mesh(PartMesh("flat", np.vstack([p, [[0, 1, 0]]]), np.array([[0, 1, 2, 3], [0, 1, 2, 4]])), 2)
