"""Issue 38, degenerate linkages that are valid: change-point four-bars (Grashof's equality: two
lengths sum to the other two) lie flat at crank 0 and/or 180 deg, where both assembly branches
meet.  A rhombus (500 500 500 500) was refused with a message that contradicted itself ("cannot
be assembled at crank 0 deg; it closes for crank angles 0.0 to 359.9 deg") and a kite
(300 700 700 300) was exit 3.  They are computed: the branch chosen by continuity (angles and
rates continuous through the change point), the change point named, the reactions flagged
unbounded there (a toggle), and every refusal's message is true."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rigfem.cli import main
from rigfem.errors import InputError
from rigfem.linkage import fourbar_closes, fourbar_motion, fourbar_turn
from said import one_line

CHANGE_POINT = {"rhombus": (500.0, 500.0, 500.0, 500.0), "kite": (300.0, 700.0, 700.0, 300.0),
                "parallelogram": (300.0, 700.0, 300.0, 700.0), "rig-like": (540.0, 840.0, 780.0, 1080.0),
                "folded at 0": (200.0, 900.0, 500.0, 600.0)}
TURNS = {"rhombus": ([0.0, 180.0], 1), "kite": ([0.0], 2), "parallelogram": ([0.0, 180.0], 1),
         "rig-like": ([180.0], 2), "folded at 0": ([0.0], 2)}


@pytest.mark.parametrize("name", list(CHANGE_POINT))
def test_a_change_point_linkage_moves_smoothly_through_its_change_points(name):
    b2, b3, b4, d = CHANGE_POINT[name]
    deg = np.arange(0.0, 360.0, 0.05)
    m = fourbar_motion(b2, b3, b4, d, deg)
    A, B, O4 = (m.points[p]["position_mm"] for p in ("A", "B", "O4"))
    assert np.allclose(np.linalg.norm(B - A, axis=1), b3, rtol=1e-12)
    assert np.allclose(np.linalg.norm(B - O4, axis=1), b4, rtol=1e-12)
    step = np.radians(0.05) / (2 * np.pi)   # s of a step at 1 Hz
    for link in ("coupler", "rocker"):
        th = np.unwrap(np.radians(m.links[link]["angle_deg"]))
        w, a = m.links[link]["omega_rad_s"], m.links[link]["alpha_rad_s2"]
        assert np.isfinite(w).all() and np.isfinite(a).all()
        # the rate is the angle's derivative, also across each change point (no jump of branch)
        tol = 1e-5 * (np.abs(w).max() + 2 * np.pi)   # of the crank's 2π rad/s
        assert np.allclose(np.diff(th) / step, (w[1:] + w[:-1]) / 2, rtol=0, atol=tol + 1e-3 * np.abs(w).max())
        assert np.abs(np.diff(w)).max() < 0.05 * np.abs(w).max() + tol
    t = fourbar_turn(b2, b3, b4, d)
    assert t["crank_turns_fully"] and (t["change_points_deg"], t["turns_to_repeat"]) == TURNS[name]


@pytest.mark.parametrize("name", ["rhombus", "kite"])
def test_the_rhombus_and_the_kite_are_computed_naming_their_change_points(capsys, name):
    lengths = [f"{x:g}" for x in CHANGE_POINT[name]]
    assert main(["kinematics", "--four-bar", *lengths]) == 0
    out = capsys.readouterr().out
    assert "change points" in out and "0.0000" in out and "Grashof class: change-point" in out
    assert main(["reactions", "--four-bar", *lengths]) == 0   # exit 3 before (the kite)
    out = capsys.readouterr().out
    assert "SINGULAR" in out and "toggle near crank 0.0" in out


def test_the_rhombus_moves_as_a_parallelogram():
    m = fourbar_motion(500, 500, 500, 500, np.arange(0.0, 360.0, 15.0))
    assert np.allclose(np.sin(np.radians(m.links["coupler"]["angle_deg"])), 0.0, atol=1e-12)
    assert np.allclose(m.links["rocker"]["omega_rad_s"], 2 * np.pi, rtol=1e-9)


_RANGE = re.compile(r"(-?[\d.]+) to (-?[\d.]+) deg")


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(lengths=st.lists(st.sampled_from([100.0, 300.0, 500.0, 700.0]) | st.floats(10.0, 1000.0), min_size=4,
                        max_size=4),
       deg=st.sampled_from([0.0, 90.0, 180.0, 270.0]) | st.floats(0.0, 359.9))
@example(lengths=[500.0, 500.0, 500.0, 500.0], deg=0.0)
@example(lengths=[300.0, 700.0, 700.0, 300.0], deg=0.0)
def test_a_four_bar_is_computed_where_it_closes_and_a_refusal_is_true(lengths, deg):
    """Either the motion is there (a closed loop), or the message's crank angle lies outside every
    range it says the loop closes for, and the loop indeed does not close there."""
    b2, b3, b4, d = lengths
    try:
        m = fourbar_motion(b2, b3, b4, d, [deg])
    except InputError as exc:
        at = float(re.search(r"at crank (-?[\d.e+-]+) deg", str(exc)).group(1))
        ranges = [(float(a), float(b)) for a, b in _RANGE.findall(str(exc).split("closes for", 1)[1])]
        assert not any(a - 0.05 <= at <= b + 0.05 for a, b in ranges), str(exc)
        assert not fourbar_closes(b2, b3, b4, d, np.array([at]))[0]
        return
    A, B = m.points["A"]["position_mm"][0], m.points["B"]["position_mm"][0]
    assert np.isclose(np.linalg.norm(B - A), b3, rtol=1e-9) and np.isclose(np.linalg.norm(B - [d, 0]), b4, rtol=1e-9)


def test_a_synthesis_through_a_change_point_is_flagged():
    """A three-position design whose crank passes a change point between the positions reaches them
    only on one of the branches that meet there: a branch defect, not a silent success."""
    from rigfem.linkage import check_three_position, three_position

    trainer = np.array([[0.0, 0.0], [-151.2, -90.0], [-291.28, -40.0]])
    r = three_position(trainer, [-20, -40], [90, 180], [30, 60])
    assert any("change point at 180 deg" in d for d in check_three_position(r)["defects"])


def test_a_refused_change_point_rig_check_names_the_rule(tmp_path, capsys):
    scene = tmp_path / "rhombus.toml"
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 480.0\nb4 = 480.0\nd = 480.0\n')
    assert main(["check", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "breaks the rig rule" in one_line(capsys.readouterr().err)


def test_the_2013_model_sampled_at_a_change_point_reports_a_toggle(capsys):
    """300/600/400/500 mm reaches its change point at 0° (d − b2 = b3 − b4): a sample there made the 2013
    model's 9 × 9 system exactly singular, and `rigfem reactions ... --model original` ended in an internal
    error (LinAlgError); the sample is a toggle, as the law of cosines and the rigid-body model say."""
    from rigfem.dynamics import simulate
    from rigfem.linkage import four_bar

    for model in ("original", "rigid-body"):
        h = simulate(four_bar(300, 600, 400, 500), samples=360, model=model)
        assert any(lo <= 0.0 <= hi or lo <= 360.0 <= hi for lo, hi in h.meta["singular"]), (model, h.meta["singular"])
        assert h.singular_mask[0] and np.all(np.isfinite(h.torque_Nm))
    capsys.readouterr()
    for model in ("original", "rigid-body"):  # the unbounded force there warns nothing either (inf × 0)
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            assert main(["reactions", "--four-bar", "300", "600", "400", "500", "--model", model]) == 0
        out = capsys.readouterr()
        assert "toggle" in out.out and out.err == "", (model, out.err)
