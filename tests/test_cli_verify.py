"""``rigfem verify --against calculix``: same model in CalculiX, compared case by case."""

import pytest

from rigfem.cli import main


@pytest.mark.tool("ccx")
def test_verify_plate_against_calculix(tmp_path, capsys):
    scene = tmp_path / "plate.toml"
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 840.0\nb4 = 780.0\nd = 1020.0\n'
                     '[check]\nparts = ["plate_A"]\nmodes = ["original"]\nsamples = 72\n')
    assert main(["verify", "--against", "calculix", str(scene), "--out", str(tmp_path / "v")]) == 0
    out = capsys.readouterr().out
    assert "| plate_A | original |" in out
    assert (tmp_path / "v" / "calculix_verify_plate.md").read_text() == out


BAD = [(["--against", "abaqus"], "only other solver is 'calculix'"),
       (["--threads", "0"], "--threads = '0' is outside"),
       (["--peak-tol", "x"], "--peak-tol"),
       (["--fidelity", "ultra"], "fidelity"),
       (["no-such-scene"], "no-such-scene"),
       (["--out", "/proc/sys/v"], "is under /proc, a system folder")]  # before any computation


@pytest.mark.parametrize("ccx", ["on PATH", "missing"])
@pytest.mark.parametrize("args, message", BAD)
def test_verify_bad_input(args, message, ccx, capsys, tmp_path, monkeypatch):
    """Every option and the scene are checked before ccx is looked for: the same one-line
    error whether ccx is installed or not, and nothing written."""
    if ccx == "missing":
        monkeypatch.setenv("PATH", str(tmp_path))  # an empty folder: no ccx
    assert main(["verify", "--out", str(tmp_path / "v"), *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "ccx" not in err.replace("--against calculix", "")
    assert not (tmp_path / "v").exists()


def test_verify_without_ccx_names_the_package(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    assert main(["verify", "final-cm", "--out", str(tmp_path / "v")]) == 2
    assert "apt-get install calculix-ccx" in capsys.readouterr().err
    assert not (tmp_path / "v").exists()


@pytest.mark.tool("ccx")
@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_export_inp_is_the_same_model(tmp_path):
    """The deck written by ``rigfem check --export-inp`` reproduces rigfem's peak in ccx."""
    from rigfem.pipeline import read_report
    from rigfem.tensors import von_mises
    from rigfem.io import run_ccx

    out = tmp_path / "o"
    assert main(["check", "final-cm", "--out", str(out), "--parts", "plate_A", "--modes", "original",
                 "--fidelity", "draft", "--frames", "0", "--export-inp", "--quiet"]) == 0
    part = read_report(out)["parts"][0]
    res = run_ccx(out / "plate_A_original.inp", workdir=tmp_path / "ccx")
    nodes = part["mesh"]["dofs"] // 3  # the auxiliary nodes of the shaft-in-hole springs come after
    assert von_mises(res.stress[0][:nodes]).max() == pytest.approx(part["peak_mpa"], rel=1e-3)
