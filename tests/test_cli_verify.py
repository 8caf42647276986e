"""``rigfem verify --against calculix``: same model in CalculiX, compared case by case."""

import shutil

import pytest

from rigfem.cli import main

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="ccx (calculix-ccx) not installed")


@needs_ccx
def test_verify_plate_against_calculix(tmp_path, capsys):
    scene = tmp_path / "plate.toml"
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 840.0\nb4 = 780.0\nd = 1020.0\n'
                     '[check]\nparts = ["plate_A"]\nmodes = ["original"]\nsamples = 72\n')
    assert main(["verify", "--against", "calculix", str(scene), "--out", str(tmp_path / "v")]) == 0
    out = capsys.readouterr().out
    assert "| plate_A | original |" in out
    assert (tmp_path / "v" / "calculix_verify_plate.md").read_text() == out


@pytest.mark.parametrize("args, message", [(["--against", "abaqus"], "only other solver is 'calculix'"),
                                           (["--threads", "0"], "--threads = '0' is outside")])
def test_verify_bad_input(args, message, capsys):
    if shutil.which("ccx") is None and "--threads" in args:
        pytest.skip("ccx missing: the ccx check comes first")
    assert main(["verify", *args]) == 2
    assert message in capsys.readouterr().err


@needs_ccx
def test_export_inp_is_the_same_model(tmp_path):
    """The deck written by ``rigfem check --export-inp`` reproduces rigfem's peak in ccx."""
    from rigfem.check import read_report
    from rigfem.fe import von_mises
    from rigfem.io import run_ccx

    out = tmp_path / "o"
    assert main(["check", "final-cm", "--out", str(out), "--parts", "plate_A", "--modes", "original",
                 "--fidelity", "draft", "--frames", "0", "--export-inp", "--quiet"]) == 0
    part = read_report(out)["parts"][0]
    res = run_ccx(out / "plate_A_original.inp", workdir=tmp_path / "ccx")
    nodes = part["mesh"]["dofs"] // 3  # the auxiliary nodes of the shaft-in-hole springs come after
    assert von_mises(res.stress[0][:nodes]).max() == pytest.approx(part["peak_mpa"], rel=1e-3)
