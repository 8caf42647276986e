"""``rigfem kinematics`` and ``rigfem reactions`` on textbook (massless) scenes, through the CLI."""

import json

import numpy as np
import pytest

from rigfem.cli import main


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_scene_instant_is_the_default_and_matches_mechanisms_6(capsys):
    res = _json(capsys, ["kinematics", "mech6-slider-crank-instant", "--json"])
    assert res["textbook"] and res["omega_rad_s"] == pytest.approx(-3.12) and len(res["angles"]) == 1
    a = res["angles"][0]
    assert a["crank_deg"] == 60.0
    assert a["links"]["rod"]["omega_rad_s"] == pytest.approx(0.7200, rel=1e-4)
    assert a["slider"]["velocity_mm_s"] / 25.4 == pytest.approx(9.9766, rel=1e-4)
    assert res["turn"]["stroke_mm"] == pytest.approx(2 * 76.2)


def test_four_bar_turn_and_csv(capsys, tmp_path):
    out = tmp_path / "k.csv"
    res = _json(capsys, ["kinematics", "--four-bar", "540", "840", "780", "1020", "--samples", "36", "--json",
                         "--csv", str(out)])
    assert res["turn"]["grashof"] == "crank-rocker" and len(res["angles"]) == 36
    assert res["transmission_angle_deg"]["min"] == pytest.approx(34.2160, abs=1e-4)   # geometry/RIG.md §3
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert rows.size == 36 and np.allclose(rows["crank_deg"], np.arange(36) * 10.0)


def test_general_solver_scene_and_at(capsys):
    res = _json(capsys, ["kinematics", "mech4-quick-return", "--at", "0", "--json"])
    assert res["method"] == "general solver" and res["turn"] is None
    assert res["angles"][0]["slider"]["position_mm"] == pytest.approx(800 * 150 / 350)


def test_never_overwrites(tmp_path, capsys):
    f = tmp_path / "m.gif"
    f.write_bytes(b"keep")
    assert main(["kinematics", "mech2-fourbar-coupler-point", "--animate", str(f)]) == 2
    assert "already exists" in capsys.readouterr().err and f.read_bytes() == b"keep"


def test_plot(tmp_path, capsys):
    f = tmp_path / "m.png"
    assert main(["kinematics", "mech1-slider-crank", "--samples", "72", "--plot", str(f)]) == 0
    assert f.stat().st_size > 10_000


def test_bad_input_exit_2(capsys):
    # the crank cannot turn fully: valid input, computed over its range of motion (issue 24 §5)
    assert main(["kinematics", "--four-bar", "100", "70", "75", "80", "--samples", "8"]) == 0
    assert "crank range" in capsys.readouterr().out
    assert main(["kinematics", "--slider-crank", "100", "300", "--at", "x"]) == 2


@pytest.mark.parametrize("scene", ["mech2-fourbar-coupler-point", "mech6-slider-crank-instant",
                                   "mech7-elliptical-trainer"])
def test_reactions_on_massless_scene_points_to_kinematics(scene, capsys):
    assert main(["reactions", scene]) == 0
    out = capsys.readouterr().out
    assert "no masses" in out and f"rigfem kinematics {scene}" in out and "0.0000" not in out


def test_textbook_scene_gets_no_rig_rules(capsys):
    res = _json(capsys, ["reactions", "mech5-compressor", "--samples", "36", "--json"])
    assert res["textbook"] and res["rules"] == []
    res = _json(capsys, ["reactions", "rig-fourbar-reference", "--samples", "36", "--json"])
    assert not res["textbook"] and res["rules"]
