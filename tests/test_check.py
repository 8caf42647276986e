"""``rigfem check`` end to end on small parts: report, VTU files, exit codes, refusals."""

import json

import meshio
import numpy as np
import pytest

from rigfem.pipeline import Output, Request, read_report, run_check
from rigfem.cli import main
from rigfem.errors import InputError
from said import one_line

FAST = {"parts": ["plate_A"], "fidelity": "draft", "samples": 72, "frames": 3}


@pytest.fixture(scope="module")
def plate_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("check") / "final-cm"
    return out, run_check(Request("final-cm", FAST), Output(out))


def test_report_and_files(plate_report):
    out, r = plate_report
    assert r == read_report(out)
    assert [(p["name"], p["mode"]) for p in r["parts"]] == [("plate_A", "original"), ("plate_A", "cycle")]
    for p in r["parts"]:
        assert p["verdict"] == "pass" and 0 < p["peak_mpa"] < p["limit_mpa"]
        assert p["solve"]["residual_max"] < 1e-6 and p["solve"]["equilibrium_error"] < 1e-6
    orig, cyc = r["parts"]
    # original mode: the plate carries load factor x the peak pin force at A; cycle mode 1 x the force
    assert orig["peak_mpa"] > cyc["peak_mpa"]
    assert cyc["fatigue"]["safety_factor"] > 1
    assert r["differences"] and r["differences"][0].startswith("plate_A: original")
    for name in ("report.md", "reactions.png", "peak_von_mises.png", "plate_A_original.vtu",
                 "plate_A.png", "plate_A_cycle.pvd", "plate_A_cycle_002.vtu"):
        assert (out / name).is_file(), name
    m = meshio.read(out / "plate_A_original.vtu")
    assert {"displacement", "stress", "von_mises", "safety_factor"} <= set(m.point_data)
    assert np.isclose(m.point_data["von_mises"].max(), orig["peak_mpa"], rtol=1e-6)
    # each case's file is its critical crank angle's field, the cycle case's too
    assert np.isclose(meshio.read(out / "plate_A_cycle.vtu").point_data["von_mises"].max(), cyc["peak_mpa"],
                      rtol=1e-6)
    assert "plate_A_cycle_000.vtu" in (out / "plate_A_cycle.pvd").read_text()
    frame = meshio.read(out / "plate_A_cycle_000.vtu")  # animation frames: corner nodes, linear cells
    assert list(frame.cells_dict) == ["tetra"] and len(frame.points) == orig["mesh"]["nodes"]
    assert np.isfinite(frame.point_data["von_mises"]).all()


def test_existing_folder_is_not_overwritten(plate_report, capsys):
    out, _ = plate_report
    before = (out / "report.json").read_text()
    with pytest.raises(InputError, match="--force"):
        run_check(Request("final-cm", FAST), Output(out))
    assert main(["check", "--out", str(out), "--parts", "plate_A"]) == 2
    assert "already exists; pass --force" in capsys.readouterr().err
    assert (out / "report.json").read_text() == before


def test_failing_part_exits_1(tmp_path, capsys):
    scene = tmp_path / "strict.toml"
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 840.0\nb4 = 780.0\nd = 1020.0\n'
                     '[check]\nlimit_factor = 0.002\n')  # limit 1.5 MPa: the plate must fail
    code = main(["check", str(scene), "--out", str(tmp_path / "o"), "--parts", "plate_A", "--modes",
                 "original", "--fidelity", "draft", "--frames", "0", "--quiet"])
    assert code == 1
    assert "overall: FAIL" in capsys.readouterr().out
    assert json.loads((tmp_path / "o" / "report.json").read_text())["verdict"] == "fail"


def test_toggle_configuration_is_never_given_a_number(tmp_path):
    scene = tmp_path / "toggle.toml"  # d + b2 = 1199 ≈ b3 + b4: μ reaches 175°
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 300.0\nb3 = 600.0\nb4 = 600.0\nd = 899.0\n')
    r = run_check(Request(scene, {"parts": ["plate_A"]}, True), Output(tmp_path / "o"))  # it breaks the crank-turns and hole-grid rules
    assert r["verdict"] == "fail" and r["singular"]
    assert all(p["peak_mpa"] is None and "toggle" in p["notes"][0] for p in r["parts"])
    assert "toggle" in (tmp_path / "o" / "report.md").read_text()


@pytest.mark.parametrize("args, message", [
    (["--parts", "wing"], "[check].parts: 'wing' is not a part of a four-bar"),
    (["--fidelity", "ultra"], "[check].fidelity = 'ultra': Input should be 'draft', 'standard' or 'fine'"),
    (["--size", "-1"], "[check].size_mm = -1.0: Input should be greater than or equal to 0.1"),
    (["--model", "newtonian"], "[check].mass_model = 'newtonian': Input should be"),
    (["no-such-scene"], "neither a file nor a built-in scene"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, args, message):
    assert main(["check", *args, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert message in one_line(err)
    assert not (tmp_path / "o").exists()


def test_imported_csv_reproduces_the_dynamics(tmp_path):
    """A reaction CSV exported by rigfem and imported back gives the same verdict numbers."""
    from rigfem.dynamics import simulate
    from rigfem.io import write_csv
    from stages import job_of

    write_csv(simulate(job_of("final-cm").linkage, samples=360), tmp_path / "ext.csv")
    opts = {"parts": ["plate_A"], "fidelity": "draft", "frames": 0}
    ref = run_check(Request("final-cm", opts), Output(tmp_path / "ref"))
    imp = run_check(Request("final-cm", {**opts, "reactions_csv": str(tmp_path / "ext.csv")}), Output(tmp_path / "imp"))
    assert imp["configuration"]["model"] == "imported from ext.csv"
    for a, b in zip(ref["parts"], imp["parts"]):
        assert b["peak_mpa"] == pytest.approx(a["peak_mpa"], rel=1e-4)
        assert b["crank_deg"] == pytest.approx(a["crank_deg"], abs=0.01)
    with pytest.raises(InputError, match="reactions_csv = 'nope.csv': no such file"):
        run_check(Request("final-cm", {**opts, "reactions_csv": "nope.csv"}), Output(tmp_path / "x"))


def _numbers(entry, prefix=""):
    """The numbers of a verdict entry, flattened (its timings left out)."""
    if isinstance(entry, dict):
        return {k: v for key, val in entry.items() if key not in ("seconds", "ladder")
                for k, v in _numbers(val, f"{prefix}{key}.").items()}
    if isinstance(entry, (list, tuple)):
        return {k: v for i, val in enumerate(entry) for k, v in _numbers(val, f"{prefix}{i}.").items()}
    return {prefix: entry}


def test_a_final_part_holds_only_its_critical_combination():
    """Once a part is final, a check keeps of its solution only what the report still reads (the
    critical row's combination; the animation frames are written as it becomes final), not every
    unit solution; the verdict entries are those of the whole solution."""
    from stages import entries, solved

    job, _, small = solved("final-cm", FAST)
    _, _, every = solved("final-cm", FAST, whole=True)
    for r, ref in zip(small, every):
        shared = [o for o in small if o.solution is r.solution]  # the modes that share supports
        assert r.solution.U.shape[1] == len({tuple(o.coef[o.row]) for o in shared}) < r.solution.cases
        assert r.solution.cases == ref.solution.cases == ref.coef.shape[1]
        dropped = [i for i in range(len(r.case.rows)) if not any((r.coef[i] == o.coef[o.row]).all() for o in shared)]
        assert len(dropped) == len(r.case.rows) - 1 or r.mode == "original"  # a cycle case: all its other angles
        for i in dropped[:1]:
            with pytest.raises(ValueError, match="kept"):
                r.solution.stress(r.coef[i])
        (a,), (b,) = (_numbers(e) for e in entries(job, [r])), (_numbers(e) for e in entries(job, [ref]))
        assert a.keys() == b.keys()
        for k in a:
            assert a[k] == pytest.approx(b[k], rel=1e-10, abs=1e-9) if isinstance(a[k], float) else a[k] == b[k], k
