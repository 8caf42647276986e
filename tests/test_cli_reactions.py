"""`rigfem reactions`: default reference run, JSON/CSV/plot outputs, every bad-input case."""

import json

import pytest

from rigfem.cli import main
from rigfem.io import read_csv
from said import said

CAL = {"O2": 641.9099, "A": 578.8140, "B": 379.4016, "O4": 366.4701}


def _run(capsys, *argv):
    rc = main(["reactions", *argv])
    out, err = capsys.readouterr()
    return rc, out, err


def test_default_is_the_reference_configuration_table(capsys):
    """No configuration: the same reference scene as ``rigfem check`` (final-cm)."""
    rc, out, err = _run(capsys)
    assert rc == 0 and said(err) == []
    assert "b2=480" in out and "d=1020" in out and "rigid-body" in out
    for j in ("O2", "A", "B", "O4"):
        assert f"\n{j} " in out
    assert "peak driver torque" in out
    assert _run(capsys, "final-cm")[1] == out


def test_json_original_model_reproduces_calibration(capsys):
    rc, out, _ = _run(capsys, "--four-bar", "540", "840", "780", "1020", "--model", "original", "--json")
    assert rc == 0
    res = json.loads(out)
    assert {"rules", "transmission_angle_deg", "peaks", "torque_Nm", "singular"} <= set(res)
    for j, v in CAL.items():
        assert res["peaks"][j]["force_N"] == pytest.approx(v, rel=1e-4)
        assert set(res["peaks"][j]) >= {"force_N", "crank_deg", "fx_N", "fy_N"}
    assert res["torque_Nm"]["peak"] == pytest.approx(199.7707, rel=1e-4)
    assert res["transmission_angle_deg"]["min"] == pytest.approx(34.2160, rel=1e-4)
    assert res["singular"] is None
    assert all(set(r) >= {"name", "value", "limit", "ok"} for r in res["rules"])


def test_slider_crank_scene_csv_and_plot(capsys, tmp_path):
    csv_path, png = tmp_path / "h.csv", tmp_path / "h.png"
    rc, out, _ = _run(capsys, "--slider-crank", "300", "900", "--offset", "60", "--samples", "90",
                      "--csv", str(csv_path), "--plot", str(png), "--speed-hz", "2")
    assert rc == 0 and "slide" in out
    h = read_csv(csv_path)
    assert h.crank_deg.size == 90 and set(h.joints) == {"O2", "A", "B", "slide"}
    assert png.stat().st_size > 1000
    rc, out, _ = _run(capsys, "mech5-compressor", "--json")
    assert rc == 0 and json.loads(out)["linkage"] == "slider-crank"


def test_singular_configuration_is_never_a_plain_number(capsys):
    rc, out, _ = _run(capsys, "--four-bar", "540", "840", "780", "1080", "--json")
    res = json.loads(out)
    assert rc == 0 and res["singular"]
    assert all(p["force_N"] is None for p in res["peaks"].values())
    rc, out, _ = _run(capsys, "--four-bar", "540", "840", "780", "1080")
    assert "SINGULAR" in out and "WARNING: toggle" in out
    assert "e+" not in out


@pytest.mark.parametrize("argv,needle", [
    (["--four-bar", "0", "840", "780", "1020"], "B2"),
    (["--four-bar", "540", "-840", "780", "1020"], "B3"),
    (["--four-bar", "540", "840", "abc", "1020"], "B4 must be a number"),
    (["--slider-crank", "300", "x"], "B3 must be a number"),
    (["--model", "quantum"], "--model"),
    (["--four-bar", "540", "840", "780", "1200"], "cannot be assembled for crank angles 133.6-226.4 deg"),
    (["--slider-crank", "500", "300"], "cannot be assembled for crank angles"),
    (["--four-bar", "0.54", "0.84", "0.78", "1.02"], "looks like metres"),
    (["--slider-crank", "0.3", "0.9"], "looks like metres"),
    (["--samples", "2"], "--samples"),
    (["--speed-hz", "-1"], "--speed-hz"),
    (["--slider-crank", "300", "900", "--model", "original"], "only for the four-bar"),
    (["no-such-scene"], "neither a file nor a built-in scene"),
])
def test_bad_input_one_line_exit_2(capsys, argv, needle):
    rc, out, err = _run(capsys, *argv)
    assert rc == 2 and out == ""
    assert len(said(err)) == 1 and needle in err


def test_bad_scene_file(capsys, tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('[linkage]\ntype = "four-bar"\nb2 = 540\nb3 = 840\nb4 = 780\nd = "wide"\n[check]\nx = 1\n')
    rc, _, err = _run(capsys, str(p))
    assert rc == 2 and "[linkage].d = 'wide': Input should be a valid number" in err
    p.write_text('[linkage]\ntype = "four-bar"\nb2 = 540\nb3 = 840\nb4 = 780\nd = 1020\n[check]\nx = 1\n')
    rc, _, err = _run(capsys, str(p))  # the whole file is checked: unknown keys anywhere are refused
    assert rc == 2 and "[check].x: unknown key 'x'" in err
    p.write_text('[linkage]\ntype = "four-bar"\nb2 = 540\nb3 = 840\nb4 = 780\nd = 1020\n')
    rc, out, _ = _run(capsys, str(p))
    assert rc == 0 and "b2=540" in out
