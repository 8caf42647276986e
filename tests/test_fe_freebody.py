"""Free-body mode: self-equilibrated load sets give reactions ≈ 0 and no rigid motion."""

import numpy as np
import pytest
from fe_shapes import bar_with_holes

from rigfem.fe import (
    BearingLoad,
    FreeBody,
    Inertia,
    build_model,
    load_matrix,
    rigid_modes,
    solve,
)
from rigfem.material import get_material

A, B = np.array([20.0, 0, 5]), np.array([180.0, 0, 5])  # hole centres of the bar


@pytest.fixture(scope="module")
def model():
    return build_model(bar_with_holes(200, 25, 10, 5, [20, 180], size=7, h_hole=2.5), get_material("rig_steel"), 2)


def test_balanced_pin_forces_give_zero_reactions(model):
    F = 1000.0
    sol = solve(model, [FreeBody()], [[BearingLoad("h0", (-F, 0, 0)), BearingLoad("h1", (F, 0, 0))],
                                      [BearingLoad("h0", (0, F, 0)), BearingLoad("h1", (0, -F, 0)),
                                       BearingLoad("h1", (0, F, 0)), BearingLoad("h0", (0, -F, 0))]])
    r = sol.support_reactions["FreeBody(3-2-1)"]
    assert np.abs(r[:, :3]).max() < 1e-9 * F and np.abs(r[:, 3:]).max() < 1e-9 * F * 200
    assert np.abs(np.linalg.lstsq(rigid_modes(model.mesh.nodes), sol.U, rcond=None)[0]).max() < 1e-12
    # tension lug: mean axial stress across the mid-length section is F / area
    x = model.mesh.nodes
    mid = np.isclose(x[:, 0], 100.0, atol=6)
    assert np.median(sol.stress(np.array([1.0, 0]))[mid, 0]) == pytest.approx(F / 250, rel=0.05)
    assert sol.peak(np.array([1.0, 0])).surface in ("h0", "h1")


def test_bar_with_inertia_balanced_by_joint_forces(model):
    """A bar turning about joint A (ω, α about z) is balanced by the joint forces of rigid-body dynamics."""
    inertia = Inertia(a0=(0, 0, 0), alpha=(0, 0, 40.0), omega=(0, 0, 2 * np.pi), origin=tuple(A))
    f = load_matrix(model, [inertia])[:, 0].reshape(-1, 3)
    Rf = f.sum(0)
    Mz = np.cross(model.mesh.nodes - A, f).sum(0)[2]
    FB = np.array([0, -Mz / (B[0] - A[0]), 0])  # joint B balances the moment about A
    FA = -Rf - FB
    sol = solve(model, [FreeBody()], [[inertia, BearingLoad("h0", tuple(FA)), BearingLoad("h1", tuple(FB))]])
    r = sol.support_reactions["FreeBody(3-2-1)"][0]
    assert np.abs(r[:3]).max() < 1e-8 * np.abs(FA).max()
    assert sol.equilibrium_error[0] < 1e-7 and sol.backward_errors[0] < 1e-12


def test_unbalanced_loads_show_up_as_reactions(model):
    sol = solve(model, [FreeBody()], [BearingLoad("h1", (10.0, 0, 0))])
    assert sol.support_reactions["FreeBody(3-2-1)"][0, 0] == pytest.approx(-10.0, rel=1e-9)


@pytest.mark.parametrize("turn", [[0, 1, 2], [1, 2, 0], [2, 0, 1]])  # the bar along x, y, z
def test_the_free_body_support_is_a_3_2_1_on_far_apart_nodes(turn):
    """The free body's six DOFs: all three at the node A farthest from the centroid, two at the node B
    farthest from A (across AB's main direction), one at the node C farthest from the line AB (along
    C's motion under a rotation about AB) — they hold every rigid motion, and nothing else."""
    from rigfem.fe.supports import three_two_one

    x = bar_with_holes(200, 25, 10, 5, [20, 180], size=12).points[:, turn] + [3.0, -7.0, 11.0]
    dofs = three_two_one(x)
    nodes, comps = dofs // 3, dofs % 3
    A, B, C = nodes[0], nodes[3], nodes[5]
    assert list(nodes) == [A, A, A, B, B, C] and list(comps[:3]) == [0, 1, 2] and len({A, B, C}) == 3
    assert np.linalg.norm(x[A] - x.mean(0)) == pytest.approx(np.linalg.norm(x - x.mean(0), axis=1).max())
    assert np.linalg.norm(x[B] - x[A]) == pytest.approx(np.linalg.norm(x - x[A], axis=1).max())
    ab = (x[B] - x[A]) / np.linalg.norm(x[B] - x[A])
    off = np.linalg.norm(np.cross(x - x[A], ab), axis=1)
    assert off[C] == pytest.approx(off.max())
    assert np.argmax(np.abs(ab)) == turn.index(0) and np.argmax(np.abs(ab)) not in comps[3:5]
    assert comps[5] == np.argmax(np.abs(np.cross(ab, x[C] - x[A])))
    assert np.linalg.matrix_rank(rigid_modes(x)[dofs]) == 6
