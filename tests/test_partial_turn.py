"""Issue 24 §5: kinematics of a linkage whose crank does not make a whole turn works where it
assembles and names its range of motion elsewhere — for every linkage type: the four-bar, the
slider-crank (long crank, offset) and the general solver's inverted slider-crank."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigfem.cli import main
from rigfem.linkage import slider_crank_motion
from said import one_line


def _json(capsys, argv):
    assert main(["kinematics", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("argv,at", [(["--slider-crank", "300", "200"], 170.0),        # crank longer than rod
                                     (["--slider-crank", "300", "200"], 10.0),         # the other arc
                                     (["--slider-crank", "200", "300", "--offset", "150"], 0.0)])
def test_slider_crank_at_an_angle_where_it_assembles(capsys, argv, at):
    r = _json(capsys, [*argv, "--at", str(at)])
    b2, b3 = float(argv[1]), float(argv[2])
    off = float(argv[4]) if "--offset" in argv else 0.0
    ref = slider_crank_motion(b2, b3, off, np.array([at]))
    assert not r["turn"]["crank_turns_fully"]
    assert r["angles"][0]["slider"]["position_mm"] == pytest.approx(ref.slider["position_mm"][0], abs=1e-6)


def test_slider_crank_elsewhere_names_every_arc(capsys):
    assert main(["kinematics", "--slider-crank", "300", "200", "--at", "90"]) == 2
    err = capsys.readouterr().err
    assert "--at = 90 deg" in one_line(err)
    assert "between 138.1897 and 221.8103 deg or between 318.1897 and 401.8103 deg" in err


def test_slider_crank_whole_range_of_motion(capsys):
    r = _json(capsys, ["--slider-crank", "200", "300", "--offset", "150", "--samples", "16"])
    a, b = r["turn"]["crank_range_deg"]
    deg = [x["crank_deg"] for x in r["angles"]]
    assert len(deg) == 16 and a < min(deg) and max(deg) < b


@pytest.fixture
def partial_isc(tmp_path):
    from rigfem.scene import builtin_scenes

    text = builtin_scenes()["mech3-inverted-slider-crank"].read_text()
    path = tmp_path / "isc.toml"
    path.write_text(text.replace("arm = 200.0", "arm = 400.0"))   # |O4A| goes down to 300 mm < arm
    return str(path)


def test_general_solver_scene_at_an_angle_where_it_assembles(capsys, partial_isc):
    r = _json(capsys, [partial_isc, "--at", "180"])
    dead = np.degrees(np.arccos((200**2 + 500**2 - 400**2) / (2 * 200 * 500)))
    assert r["method"] == "general solver" and r["turn"]["crank_range_deg"] == pytest.approx([dead, 360 - dead])
    # at 180 deg A - O4 = (-700, 0) and A lies on the slide line: (A - O4)·(cos φ4, sin φ4) = arm
    assert r["angles"][0]["crank_deg"] == 180.0
    assert r["angles"][0]["links"]["rocker"]["angle_deg"] == pytest.approx(np.degrees(np.arccos(-400 / 700)))


def test_general_solver_scene_elsewhere_names_its_range(capsys, partial_isc):
    assert main(["kinematics", partial_isc, "--at", "0"]) == 2
    assert "its crank moves only between 49.4584 and 310.5416 deg" in capsys.readouterr().err
    r = _json(capsys, [partial_isc, "--samples", "12"])
    assert all(49.4 < x["crank_deg"] < 310.6 for x in r["angles"]) and len(r["angles"]) == 12
