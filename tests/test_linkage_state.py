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


def test_the_motion_carries_its_full_turn_and_transmission_angle():
    """What the dynamics and peaks used to ask the linkage for mid-work is data of the motion."""
    from rigfem.linkage import transmission_angle

    lk = four_bar(540, 840, 780, 1020)
    full = linkage_state(lk, crank_angles(360))
    part = linkage_state(lk, np.linspace(10.0, 80.0, 15))
    assert full.full_turn and not part.full_turn
    assert np.array_equal(full.mu_deg, transmission_angle(full.histories))
    general = linkage_state(lk, crank_angles(360), general=True)
    assert general.full_turn and np.allclose(general.mu_deg, full.mu_deg, atol=1e-7)
    assert linkage_state(slider_crank(300, 840, 50), crank_angles(36)).mu_deg is None


@pytest.mark.parametrize("model", ["rigid-body", "original"])
def test_the_dynamics_on_a_given_motion_never_solves_the_linkage(monkeypatch, model):
    """rigfem check hands the dynamics the motion the scene stage computed: the reactions (and the
    2013 program's kinematics) come from it and from its ``at``, never from a new linkage solve."""
    from rigfem.dynamics import cycle, original, simulate, solver
    from rigfem.dynamics.cycle import cycle_history

    lk = four_bar(540, 840, 780, 1020)
    deg = crank_angles(90)
    ref = simulate(lk, samples=90, model=model)
    motion = linkage_state(lk, deg)

    def refuse(*args, **kwargs):
        raise AssertionError("the dynamics solved the linkage itself")

    for module, name in ((cycle, "linkage_state"), (solver, "linkage_state"), (original, "fourbar_angles")):
        monkeypatch.setattr(module, name, refuse)
    h = cycle_history(lk, motion, deg, 1.0, model)
    assert h.meta["model"] == model and h.full_turn and h.meta["mu_deg"] == ref.meta["mu_deg"]
    for j in ref.joints:
        assert np.allclose(h.joints[j].force_N, ref.joints[j].force_N, rtol=1e-12, atol=1e-9)
    assert np.allclose(h.torque_Nm, ref.torque_Nm, rtol=1e-12, atol=1e-9)


def test_the_driver_law_is_geometry_in_the_phase():
    """Constraints know the driver's law in the phase; the speed scales the rates (constant speed)."""
    from rigfem.linkage.constraints import Constraints
    from rigfem.linkage.general import positions, trace

    lk = four_bar(540, 840, 780, 1020)
    theta = np.radians(crank_angles(8))
    value, d1, d2 = Constraints(lk).drive(theta)
    assert np.array_equal(value, theta) and np.all(d1 == 1.0) and np.all(d2 == 0.0)
    tr = trace(lk, crank_angles(8))
    _, qd1, qdd1, _, _ = positions(tr, crank_angles(8), 1.0)
    _, qd3, qdd3, _, _ = positions(tr, crank_angles(8), 3.0)
    assert np.allclose(qd3, 3 * qd1, rtol=1e-12, atol=0) and np.allclose(qdd3, 9 * qdd1, rtol=1e-12, atol=0)


def test_summary_takes_the_peaks_it_is_given():
    """rigfem check refines the peaks once: the summary reuses them."""
    from rigfem.dynamics import peaks, simulate, summary

    h = simulate(four_bar(540, 840, 780, 1020), samples=72)
    pk = peaks(h)

    def refuse(angles):
        raise AssertionError("peaks refined a second time")

    h.evaluator = refuse
    s = summary(h, pk)
    assert s["peaks"] == {k: v for k, v in pk.items() if k != "torque"}
    assert s["torque_Nm"]["peak"] == pk["torque"]["peak"] and "torque" in pk
