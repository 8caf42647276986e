"""Unit-load decomposition used for superposition over the crank cycle."""

import numpy as np
import pytest

from rigfem.errors import InputError
from rigfem.loads import (
    direction_weights,
    directions,
    rotate_into,
    screw_forces,
)
from rigfem.rig import RailLayout


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


def test_rail_layout_couplings():
    holes = 20.0 + 60.0 * np.arange(12)  # 700 mm rail
    two_pitch = RailLayout(holes, 60.0, 120.0)  # plate screws two pitches apart
    assert two_pitch.pivot_x == 80.0
    assert two_pitch.coupling(540.0, "crank") == (9, 11)
    with pytest.raises(InputError, match="crank: a joint 600 mm from the pivot does not fit on a 700 mm rail; allowed 0..540 mm"):
        two_pitch.coupling(600.0, "crank")
    one_pitch = RailLayout(holes, 60.0, 60.0)
    assert one_pitch.pivot_x == 50.0 and one_pitch.coupling(540.0, "crank") == (9, 10)


def _rig_bars():
    from rigfem.loads import Bar

    def layout(length):
        return RailLayout(20.0 + 60.0 * np.arange(int((length - 40) // 60) + 1), 60.0, 120.0)

    return [Bar("crank_rail", "O2", "A", "rail_size25", 700.0, layout(700.0), 480.0, driven=True),
            Bar("coupler_rail", "A", "B", "rail_size25", 1000.0, layout(1000.0), 840.0),
            Bar("rocker_rail", "O4", "B", "rail_size25", 1000.0, layout(1000.0), 780.0)]


@pytest.mark.parametrize("speed_hz", [1.0, 3.0])
def test_cycle_rail_loads_balance_the_rigid_body_dynamics(speed_hz):
    """Every free rail's loads (couplings, driver couple, own inertia) are in equilibrium.

    Independent truth: Newton–Euler of the rail alone, a uniform bar over the meshed rail
    (0..L, pivot joint at ``layout.pivot_x``) with the catalogue's linear mass.
    """
    from rigfem.dynamics import simulate
    from rigfem.linkage import four_bar
    from rigfem.loads import bar_body, cycle_rail
    from rigfem.rig import RIG_MASSES

    h = simulate(four_bar(480, 840, 780, 1020), samples=72, speed_hz=speed_hz)
    for bar in _rig_bars():
        case = cycle_rail(h, bar, n_dir=12)
        body = h.bodies[bar_body(h, bar)]
        hole_x = {f"hole_{i:02d}": x for i, x in enumerate(bar.layout.hole_x)}
        force = np.zeros((len(case.rows), 2))
        moment = np.zeros(len(case.rows))  # about the pivot joint, N·mm
        for k, load in enumerate(case.loads):
            c = case.coef[:, k]
            if load.kind == "bearing":
                f = c[:, None] * np.array(load.direction[:2])
                force += f
                moment += (hole_x[load.group] - bar.layout.pivot_x) * f[:, 1]
        a0 = case.coef[:, [case.loads.index(l) for l in case.loads if l.component in ("a0x", "a0y")]]
        alpha = case.coef[:, [l.component for l in case.loads].index("alpha")]
        w2 = case.coef[:, [l.component for l in case.loads].index("omega2")]
        m, rc = case.mass_kg, np.array([bar.length_mm / 2 - bar.layout.pivot_x, 0.0])
        i_pivot = m * bar.length_mm ** 2 / 12 + m * rc @ rc
        acc_c = a0 + alpha[:, None] * np.array([-rc[1], rc[0]]) - w2[:, None] * rc
        force -= m * acc_c / 1000.0
        moment -= (m * (rc[0] * a0[:, 1] - rc[1] * a0[:, 0]) + i_pivot * alpha) / 1000.0
        scale = np.abs(case.coef[:, :-4]).sum(axis=1).max()
        assert np.abs(force).max() < 1e-9 * scale, bar.name
        assert np.abs(moment).max() < 1e-9 * scale * bar.length_mm, bar.name
        assert body.mass_kg == pytest.approx(RIG_MASSES.rail_kg_m * bar.length_mm / 1000)


def test_dynamics_rail_matches_the_meshed_rail():
    """The dynamics' rail (mass, reach behind the pivot) is the meshed rail: catalogue kg/m
    equals the part file's, and ``rail_behind_mm`` equals the mesh layout's pivot position."""
    from rigfem.dynamics import simulate
    from rigfem.linkage import four_bar
    from rigfem.rig import RIG_MASSES, load_part, rail_layout
    from rigfem.settings import PLATE, RAIL

    h = simulate(four_bar(540, 840, 780, 1020), samples=8)
    layout = rail_layout(RAIL, 700.0, PLATE)
    assert layout.pivot_x == RIG_MASSES.rail_behind_mm
    cat = load_part("rail_size25").reference["linear_mass_catalogue"].value
    assert RIG_MASSES.rail_kg_m == cat
    crank = h.bodies["crank"]  # the rail's own mass and centre (point masses apart)
    assert crank.com_local_mm[0] == pytest.approx(350.0 - layout.pivot_x)
    assert crank.mass_kg == pytest.approx(0.7 * cat)


def test_load_cases_use_the_parts_resolved_once(monkeypatch):
    """The check's parts are resolved against geometry/ once (``check_settings``); the load cases
    take them from the settings and look up no part definition or rail layout of their own."""
    import rigfem.loads.cases
    import rigfem.rig.layout
    import rigfem.rig.parts
    from rigfem.dynamics import peaks, simulate
    from rigfem.linkage import four_bar
    from rigfem.loads import part_cases
    from rigfem.settings import check_settings

    h = simulate(four_bar(540, 840, 780, 1020), samples=8)
    s = check_settings({"modes": ["original"]}, "four-bar", [700.0, 1000.0, 1000.0])
    expected = {c.name: c.supports for _, c in part_cases(h, peaks(h), s)}

    def looked_up(*a, **k):
        raise AssertionError("a load case looked a part up again")

    for mod in (rigfem.rig.parts, rigfem.rig.layout, rigfem.loads.cases):
        monkeypatch.setattr(mod, "load_part", looked_up, raising=False)
        monkeypatch.setattr(mod, "rail_layout", looked_up, raising=False)
    cases = part_cases(h, peaks(h), s)
    assert {c.name: c.supports for _, c in cases} == expected
    assert set(expected) == {"crank_rail", "coupler_rail", "rocker_rail", "plate_A", "plate_B", "post_B"}


def test_the_material_is_resolved_after_the_parts():
    """part_settings checks the parts and mesh of a [check] table; its material is resolved
    apart (rigfem.material.table_material), after the rig rules in rigfem check; check_settings
    does both."""
    from rigfem.material import table_material
    from rigfem.settings import check_settings, part_settings

    own = {"name": "s355", "E": 210e3, "nu": 0.3, "sigma_u": 470, "density": 7.85e-9}
    rails = [700.0, 1000.0, 1000.0]
    assert check_settings({"material": own}, "four-bar", rails).material == table_material(own)
    assert part_settings({"material": own}, "four-bar", rails).material.name == "rig_steel"
    assert table_material("rig_steel").name == "rig_steel"
    with pytest.raises(InputError, match="material E"):
        table_material(dict(own, E=210e9))
