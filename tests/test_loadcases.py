"""Unit-load decomposition used for superposition over the crank cycle."""

import numpy as np
import pytest

from rigfem.errors import InputError
from rigfem.loadcases import coupling_holes, direction_weights, directions, rotate_into, screw_forces


@pytest.mark.parametrize("n_dir", [4, 8, 12, 24])
def test_direction_weights_reproduce_vector_and_stay_nonnegative(n_dir):
    rng = np.random.default_rng(1)
    v = rng.normal(size=(500, 2)) * 10.0 ** rng.uniform(-6, 6, size=(500, 1))
    v = np.vstack([v, [[1, 0], [0, -1], [-1, 0], [0, 0]]])  # exactly on directions, and zero
    w = direction_weights(v, n_dir)
    e = np.array(directions(n_dir))[:, :2]
    np.testing.assert_allclose(w @ e, v, rtol=1e-12, atol=1e-12 * np.abs(v).max())
    assert (w >= 0).all()
    assert ((w > 0).sum(axis=1) <= 2).all()


def test_screw_forces_carry_force_and_torque():
    f = np.array([[100.0, -40.0]])
    t = np.array([6000.0])  # N·mm about +z
    a, b = screw_forces(f, t, 60.0)
    np.testing.assert_allclose(a + b, f)
    moment = -30.0 * a[:, 1] + 30.0 * b[:, 1]  # x × F about the coupling centre
    np.testing.assert_allclose(moment, t)


def test_rotate_into_frame():
    v = np.array([[0.0, 1.0]])
    np.testing.assert_allclose(rotate_into(v, np.array([np.pi / 2])), [[1.0, 0.0]], atol=1e-15)


def test_coupling_holes_range():
    assert coupling_holes(540.0, 12, 60.0, "crank") == (9, 10)
    with pytest.raises(InputError, match="crank: joint at 720 mm"):
        coupling_holes(720.0, 12, 60.0, "crank")
