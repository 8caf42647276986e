"""Loads that lost information never end in PASS; cached data is verified, never trusted blindly.

Each class of the issue: a reaction CSV without its torque column, a free body out of moment
balance, a scene nothing loads, an unloaded part, and corrupted, truncated or zeroed cache entries.
"""

import csv
import json
import logging
import shutil

import numpy as np
import pytest

from rigfem.pipeline import Output, Request, run_check
from rigfem.cli import main
from rigfem.errors import InputError
from said import one_line

QUICK = {"fidelity": "draft", "frames": 0}


# ----------------------------------------------------------------------------- reactions CSV
@pytest.fixture(scope="module")
def no_torque(tmp_path_factory):
    """final-cm's own reaction history as CSV, without its torque column; and a scene that states it."""
    from rigfem.dynamics import simulate
    from rigfem.io import write_csv
    from stages import job_of

    d = tmp_path_factory.mktemp("csv")
    write_csv(simulate(job_of("final-cm").linkage, samples=360), d / "full.csv")
    rows = []
    for line in (d / "full.csv").read_text().splitlines():
        if line.startswith("#"):
            rows.append(line)
            continue
        cells = next(csv.reader([line]))
        assert cells[0] != "crank_deg" or cells[-2] == "torque_Nm"
        rows.append(",".join(cells[:-2] + cells[-1:]))
    (d / "notorque.csv").write_text("\n".join(rows) + "\n")
    linkage = '[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 840.0\nb4 = 780.0\nd = 1020.0\n'
    (d / "stated.toml").write_text(linkage + '[check]\nreactions_csv = "notorque.csv"\n'
                                   'reactions_csv_missing = { torque_Nm = 0 }\n')
    (d / "silent.toml").write_text(linkage + '[check]\nreactions_csv = "notorque.csv"\n')
    return d


def test_csv_without_torque_is_refused_naming_the_column(no_torque, capsys):
    with pytest.raises(InputError, match="no driver-torque column .*torque_Nm.*reactions_csv_missing"):
        run_check(Request(no_torque / "silent.toml", QUICK), Output(no_torque / "x"))
    assert main(["check", "final-cm", "--reactions-csv", str(no_torque / "notorque.csv"),
                 "--out", str(no_torque / "y"), "--parts", "plate_A", "--fidelity", "draft"]) == 2
    err = capsys.readouterr().err
    assert "torque_Nm" in one_line(err)
    assert not (no_torque / "x").exists() and not (no_torque / "y").exists()


@pytest.mark.parametrize("table, field", [
    ('reactions_csv_missing = { torque_Nm = 0 }', "reactions_csv_missing is given without reactions_csv"),
    ('reactions_csv = "notorque.csv"\nreactions_csv_missing = { torque = 0 }', "reactions_csv_missing.torque_Nm is missing"),
    ('reactions_csv = "notorque.csv"\nreactions_csv_missing = { torque_Nm = "zero" }', "torque_Nm"),
])
def test_stated_column_is_validated(no_torque, capsys, table, field):
    scene = no_torque / "bad.toml"
    scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 840.0\nb4 = 780.0\nd = 1020.0\n'
                     f'[check]\n{table}\n')
    assert main(["check", str(scene), "--out", str(no_torque / "z")]) == 2
    err = capsys.readouterr().err
    assert field in one_line(err)


@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
def test_lost_torque_leaves_the_crank_undecided_not_passed(no_torque, capsys):
    """The stated zero torque is read, said at the top of the report, and the crank's free body
    is out of moment balance: undecided (exit 1), with the imbalance in the message and report.
    The same history with its torque balances within the tolerance and passes."""
    from rigfem.verdict import IMBALANCE_TOL

    out = no_torque / "stated"
    code = main(["check", str(no_torque / "stated.toml"), "--out", str(out), "--parts", "crank_rail",
                 "--modes", "cycle", "--fidelity", "draft", "--frames", "0", "--quiet"])
    assert code == 1
    text = capsys.readouterr().out
    assert "overall: UNDECIDED" in text and "ASSUMED: the reaction CSV" in text
    assert "free body out of balance: force" in text and "moment" in text
    r = json.loads((out / "report.json").read_text())
    (part,) = r["parts"]
    imb = part["solve"]["imbalance"]
    assert part["verdict"] == "undecided" and imb["moment_pct"] > 4 * 100 * IMBALANCE_TOL
    assert part["notes"][0].startswith("free body out of balance") and "moment" in part["notes"][0]
    assert "torque" in r["assumed"][0]
    md = (out / "report.md").read_text()
    assert md.index("ASSUMED") < md.index("Overall verdict") and "free-body imbalance" in md
    assert "ASSUMED" in (out / "report.html").read_text()
    ref = run_check(Request("final-cm", {**QUICK, "parts": ["crank_rail"], "modes": ["cycle"],
                               "reactions_csv": str(no_torque / "full.csv")}), Output(no_torque / "ref"))
    (p,) = ref["parts"]
    assert p["verdict"] == "pass" and ref["assumed"] == []
    assert max(p["solve"]["imbalance"]["force_pct"], p["solve"]["imbalance"]["moment_pct"]) < 1.0
    assert p["peak_mpa"] > 5 * part["peak_mpa"]  # what the lost torque hid


# ----------------------------------------------------------------------------- nothing loads the parts
def test_scene_nothing_loads_is_refused(tmp_path, capsys):
    assert main(["check", "mech2-fourbar-coupler-point", "--out", str(tmp_path / "o"), "--parts", "plate_A",
                 "--fidelity", "draft", "--frames", "0", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "nothing loads its parts" in one_line(err) and "rigfem kinematics" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_unloaded_part_among_loaded_ones_is_not_a_pass(tmp_path, monkeypatch, capsys):
    """A part whose every load is zero is reported "not loaded"; the overall verdict is not PASS."""
    import rigfem.pipeline

    real = rigfem.pipeline.part_cases

    def one_unloaded(h, pk, settings):
        cases = real(h, pk, settings)
        for _, case in cases:
            if case.name == "plate_B":
                case.coef[:] = 0.0
        return cases
    monkeypatch.setattr(rigfem.pipeline, "part_cases", one_unloaded)
    code = main(["check", "final-cm", "--out", str(tmp_path / "o"), "--parts", "plate_A,plate_B",
                 "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"])
    assert code == 1
    r = json.loads((tmp_path / "o" / "report.json").read_text())
    verdicts = {p["name"]: p["verdict"] for p in r["parts"]}
    assert verdicts == {"plate_A": "pass", "plate_B": "not loaded"} and r["verdict"] == "undecided"
    assert "NOT LOADED" in capsys.readouterr().out
    assert 'class="badge not-loaded"' in (tmp_path / "o" / "report.html").read_text()
    assert "**NOT LOADED**" in (tmp_path / "o" / "report.md").read_text()


def test_criterion_never_passes_unloaded_or_unbalanced():
    from rigfem.verdict import IMBALANCE_TOL, overall
    from rigfem.verdict.criterion import half_ultimate

    assert half_ultimate(0.0, 750.0, loaded=False).verdict == "not loaded"
    assert half_ultimate(30.0, 750.0, imbalance=(0.0, 2 * IMBALANCE_TOL)).verdict == "undecided"
    assert half_ultimate(30.0, 750.0, imbalance=(2 * IMBALANCE_TOL, 0.0)).verdict == "undecided"
    assert half_ultimate(500.0, 750.0, imbalance=(0.0, 2 * IMBALANCE_TOL)).verdict == "fail"
    assert overall([{"verdict": "pass"}, {"verdict": "not loaded"}]) == "undecided"


# ----------------------------------------------------------------------------- verified cache entries
@pytest.fixture
def small(tmp_path, monkeypatch):
    """A small plate-with-hole model, its loads and supports, with the cache in tmp_path."""
    from fe_shapes import plate_with_hole

    from rigfem.fe import Pressure, Symmetry, build_model
    from rigfem.material import get_material

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    pm = plate_with_hole(60.0, 40.0, 2.0, 5.0, size=8.0, h_hole=3.0)
    pm.meta["hash"] = "test-mesh"
    return (lambda: build_model(pm, get_material("rig_steel"), 2),
            [Symmetry("xsym"), Symmetry("ysym"), Symmetry("zsym")], [Pressure("xmax", -10.0)], tmp_path)


def _zeroed(f):
    a = np.load(f)
    np.save(f, np.zeros_like(a))  # a valid array file whose numbers are gone


DAMAGE = {"corrupted": lambda f: f.write_bytes(f.read_bytes()[:-8] + b"\x7f" * 8),
          "truncated": lambda f: f.write_bytes(f.read_bytes()[: len(f.read_bytes()) // 2]),
          "zeroed": _zeroed}


@pytest.mark.parametrize("damage", list(DAMAGE))
@pytest.mark.parametrize("array", ["U", "nodal_stress"])
def test_bad_solution_entry_is_recomputed_and_logged_once(small, caplog, damage, array):
    from rigfem.fe import cached_solve

    model, sup, loads, root = small
    first = cached_solve(model(), sup, loads)
    (f,) = (root / "rigfem-entries" / "solutions").rglob(f"{array}.npy")
    DAMAGE[damage](f)
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        again = cached_solve(model(), sup, loads)
        healed = cached_solve(model(), sup, loads)
    assert len([r for r in caplog.records if "discarded" in r.getMessage()]) == 1
    assert "cache" not in again.times and healed.times["cache"] == 1.0  # recomputed, then a verified hit
    for name in ("U", "nodal_stress"):
        assert np.array_equal(getattr(again, name), getattr(first, name))
        assert np.array_equal(getattr(healed, name), getattr(first, name))


def test_bad_mesh_entry_is_recomputed_and_logged_once(tmp_path, monkeypatch, caplog):
    from rigfem.mesh import MeshSettings, mesh_part
    from rigfem.rig.parts import load_part

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    part = load_part("PF_4b_003_v2")
    a = mesh_part(part, MeshSettings(8.0))
    (f,) = (tmp_path / "rigfem-entries" / "meshes").rglob("*.npz")
    f.write_bytes(f.read_bytes()[: len(f.read_bytes()) // 2])
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        b = mesh_part(part, MeshSettings(8.0))
        c = mesh_part(part, MeshSettings(8.0))
    assert len([r for r in caplog.records if "discarded" in r.getMessage()]) == 1
    assert (b.meta["cache"], c.meta["cache"]) == ("miss", "hit")
    assert np.array_equal(a.points, c.points) and np.array_equal(a.tets, c.tets)


def test_entry_of_other_inputs_is_not_read(tmp_path, caplog):
    """An entry whose manifest names other inputs (a hash collision, or a hand-made folder) is not
    read: discarded, logged, computed again."""
    import json

    from rigfem.cache import Cache

    cache = Cache(tmp_path, 10**9)
    assert cache.put("t", {"a": 1}, lambda t: (t / "x.txt").write_text("1"))
    assert cache.get("t", {"a": 1}, lambda e: e.text("x.txt")) == "1"
    d = cache.entry_folder("t", {"a": 1})
    man = json.loads((d / "manifest.json").read_text())
    (d / "manifest.json").write_text(json.dumps({**man, "inputs": {"a": 2}}))
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        assert cache.get("t", {"a": 1}, lambda e: e.text("x.txt")) is None
    assert not d.exists() and "other inputs" in caplog.text


# ----------------------------------------------------------------------------- invariants
def test_zero_energy_solution_is_never_served(small, caplog):
    """An entry that is self-consistent (checksums match) but holds no strain energy for a
    non-zero load is discarded and recomputed: the invariant cannot be cached away."""
    import dataclasses

    from rigfem.cache import from_environment
    from rigfem.fe import cached_solve, check_energy, solution_inputs
    from rigfem.fe.cache import _save_solution

    model, sup, loads, root = small
    first = cached_solve(model(), sup, loads)
    assert check_energy(first) == ""
    inputs = solution_inputs(first.model, sup, loads, "auto", 1e-10)
    cache = from_environment()
    shutil.rmtree(cache.entry_folder("solutions", inputs))
    cache.put("solutions", inputs, lambda t: _save_solution(dataclasses.replace(first, U=np.zeros_like(first.U)), t))
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        again = cached_solve(model(), sup, loads)
    assert "no strain energy" in caplog.text
    assert np.array_equal(again.U, first.U)


def test_loaded_part_with_zero_peak_cannot_be_computed(tmp_path, monkeypatch, capsys):
    """A loaded part whose stress field is exactly zero is an error (exit 3), never a 0 % pass."""
    import dataclasses

    import rigfem.fe.partcase

    real = rigfem.fe.partcase.cached_solve

    def no_stress(*a, **k):
        sol = real(*a, **k)
        return dataclasses.replace(sol, nodal_stress=np.zeros_like(sol.nodal_stress))
    monkeypatch.setattr(rigfem.fe.partcase, "cached_solve", no_stress)  # the solver's answer, where the part solve asks
    code = main(["check", "final-cm", "--out", str(tmp_path / "o"), "--parts", "plate_A", "--modes", "original",
                 "--fidelity", "draft", "--frames", "0", "--quiet"])
    assert code == 3
    assert "loaded, but its peak von Mises is 0.0 MPa" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
