"""One vocabulary for a part, built-in or custom: the preset is the mesher's settings type, and
``rigfem mesh`` says where it refined and lists only the exit codes it can return."""

import dataclasses
import pathlib

import pytest

from rigfem.cli import build_parser, main
from rigfem.mesh import mesh_part
from rigfem.rig import load_part
from rigfem.settings import FIDELITY, MeshSettings, check_settings, preset

GEO = str(pathlib.Path(__file__).resolve().parents[1] / "examples" / "plate_with_hole.geo")


@pytest.fixture(autouse=True)
def cache_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))


def test_a_preset_is_the_mesh_settings_of_a_check():
    """The presets, a scene's [check] settings and the mesher share one type and its field names."""
    for name, p in FIDELITY.items():
        assert isinstance(p, MeshSettings) and preset(name) is p
        s = check_settings({"fidelity": name}, "four-bar")
        assert isinstance(s, MeshSettings) and s.key() == p.key()
        assert (s.order, s.bearing_directions) == (p.order, p.bearing_directions)
    over = check_settings({"fidelity": "draft", "size_mm": 7.0}, "four-bar")
    assert (over.size_mm, over.local_size_mm) == (7.0, FIDELITY["draft"].local_size_mm)
    assert {f.name for f in dataclasses.fields(MeshSettings)} >= {"size_mm", "local_size_mm"}


def test_a_preset_meshes_a_custom_part():
    pm = mesh_part(load_part(GEO), preset("draft").refined(("hole",)))
    assert pm.meta["settings"]["size_mm"] == 8.0 and pm.meta["settings"]["local_size_mm"] == 1.7
    assert pm.meta["settings"]["refine"] == ["hole"]


def test_mesh_says_which_surfaces_it_refined(tmp_path, capsys):
    out = str(tmp_path / "m.vtu")
    assert main(["mesh", GEO, "--fidelity", "standard", "--refine", "hole", "--out", out]) == 0
    said = capsys.readouterr().out
    assert "global size 6 mm (standard preset)" in said and "refined on hole to 1.2 mm" in said
    assert main(["mesh", GEO, "--out", out, "--force"]) == 0   # replaces the file rigfem wrote
    said = capsys.readouterr().out
    assert "no surface refined" in said and "nowhere" not in said


def test_mesh_names_the_curved_surfaces_meshed_finer(tmp_path, capsys):
    """Curvature sizing refines the plate's small screw holes even when --refine is not given."""
    assert main(["mesh", "PF_4b_006", "--out", str(tmp_path / "p.vtu")]) == 0
    said = capsys.readouterr().out
    assert "finer by curvature on screw_1" in said and "screw_2" in said and "nowhere" not in said


def _epilog(command: str) -> str:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return sub.choices[command].epilog


def test_mesh_help_lists_only_its_exit_codes():
    mesh, check = _epilog("mesh"), _epilog("check")
    assert "0 mesh written" in mesh and "2 bad input" in mesh and "3 could not compute" in mesh
    assert "1 a part fails" not in mesh and "passes" not in mesh
    assert "0 every part passes, 1 a part fails" in check


def test_mesh_local_size_above_size_is_bad_input(tmp_path, capsys):
    rc = main(["mesh", GEO, "--size", "4", "--local-size", "5", "--out", str(tmp_path / "m.vtu")])
    assert rc == 2 and "--local-size" in capsys.readouterr().err
