"""The linkage hands the dynamics its whole motion in one piece (rigfem.linkage.state): the
closed forms and the general solver give the same state, its centre-of-mass accelerations are
the derivatives of the centre-of-mass paths, and the dynamics computes on that data without
reaching back for the linkage's vector helpers or its solver internals."""

import ast
from pathlib import Path

import numpy as np
import pytest

from rigfem.linkage import crank_angles, four_bar, slider_crank
from rigfem.linkage.closed import closed_motion
from rigfem.linkage.state import linkage_state

ROOT = Path(__file__).resolve().parents[1]

CASES = {
    "rig-four-bar-gravity": lambda: four_bar(540, 840, 780, 1020, gravity_mm_s2=(0, -9810)),
    "rig-slider-offset": lambda: slider_crank(300, 840, 50),
}


@pytest.mark.parametrize("name", CASES)
def test_closed_and_general_state_agree(name):
    lk = CASES[name]()
    deg = crank_angles(72)
    fast = linkage_state(lk, deg, 1.5)
    slow = linkage_state(lk, deg, 1.5, general=True)
    assert fast.kind == lk.meta["type"] and fast.general is None and slow.general is not None
    for b in lk.bodies:
        f, s = fast.bodies[b.name], slow.bodies[b.name]
        assert f.mass_kg == s.mass_kg and f.inertia_kg_m2 == s.inertia_kg_m2
        for field in ("com", "com_acc", "origin"):
            ref = np.abs(getattr(s, field)).max() + 1e-12
            assert np.abs(getattr(f, field) - getattr(s, field)).max() < 1e-7 * ref, (b.name, field)
    for j in fast.joints:
        assert np.allclose(fast.joints[j], slow.joints[j], atol=1e-9)
    assert set(fast.histories) == set(slow.histories) == {b.name for b in lk.bodies}


def test_centre_of_mass_acceleration_is_the_second_derivative_of_its_path():
    lk = four_bar(540, 840, 780, 1020)
    speed = 2.0
    deg = crank_angles(3600)
    st = closed_motion(lk, np.radians(deg), 2 * np.pi * speed)
    dt = (deg[1] - deg[0]) / 360 / speed
    for b in st.bodies.values():
        p = b.origin + b.com
        acc = (np.roll(p, -1, 0) - 2 * p + np.roll(p, 1, 0)) / dt**2  # periodic: a full turn
        assert np.abs(acc - b.com_acc).max() < 1e-4 * np.abs(b.com_acc).max()


def test_the_dynamics_takes_the_motion_as_data():
    """No dynamics module imports the linkage's vector helpers or the solver's internals: the
    forces are balanced on the LinkageState, without calls back into the linkage."""
    internals = {"rotate", "perp", "Constraints", "positions", "rates", "trace", "conditioning", "body_motion"}
    found = []
    for f in sorted((ROOT / "rigfem" / "dynamics").glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("rigfem.linkage"):
                found += [f"{f.name}: {a.name}" for a in node.names if a.name in internals]
    assert not found
