"""Issue 26's exact speed-ups keep the results: basis body loads, one residual product per solve,
meshes prefetched in mesher processes, smoothing by part kind, a check without pictures."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from rigfem.cache import from_environment
from rigfem.pipeline import Output, Request, run_check
from rigfem.cli import main
from rigfem.fe import BearingLoad, Gravity, Inertia, build_model, load_matrix, load_vector
from rigfem.fe.solver import LinearSolver
from rigfem.material import get_material
from rigfem.mesh import mesher
from rigfem.mesh import pool
from rigfem.mesh.mesher import MeshSettings, mesh_inputs, mesh_part
from rigfem.rig.parts import load_part
from rigfem.settings import PLATE, RAIL


@pytest.fixture(scope="module")
def plate_model():
    pm = mesh_part(load_part(PLATE), MeshSettings(12.0))
    return build_model(pm, get_material("rig_steel"), 2)


def test_basis_body_loads_equal_the_per_load_assembly(plate_model):
    m = plate_model
    c = m.mesh.nodes.mean(0)
    loads = [Inertia(a0=(1.0, 0, 0), origin=(3.0, -40.0, 7.0)), Inertia(alpha=(0, 0, 1.0), origin=(-60.0, 0, 0)),
             Inertia(omega=(0, 0, 1.0), origin=tuple(c)), Gravity((0, 0, -9810.0)),
             Inertia(a0=(2.0, -1.0, 0.5), alpha=(0.3, -0.2, 1.1), omega=(0.4, 0.1, -2.0), origin=(100.0, 20.0, -5.0)),
             [Inertia(alpha=(0, 0, 3.0)), BearingLoad("bore", (100.0, 0, 0))]]
    F = load_matrix(m, loads)
    for k, case in enumerate(loads):
        ref = sum(load_vector(m.mesh, m.part.holes, m.material.density, ld)
                  for ld in (case if isinstance(case, list) else [case]))
        assert np.abs(F[:, k] - ref).max() <= 1e-12 * np.abs(ref).max(), k


class _Counting(sp.csr_matrix):
    products = 0

    def __matmul__(self, other):
        type(self).products += 1
        return super().__matmul__(other)


@pytest.mark.parametrize("method", ["pardiso", "superlu"])
def test_a_solve_forms_its_residual_once(method):
    n = 200
    A = sp.diags([-1.0, 2.05, -1.0], [-1, 0, 1], shape=(n, n), format="csr")
    s = LinearSolver(A, method)
    s.A = _Counting(s.A)
    _Counting.products = 0
    F = np.random.default_rng(1).normal(size=(n, 3))
    X = s.solve(F)
    assert _Counting.products == 1  # the residual that decides refinement is the one reported and checked
    assert s.backward_errors.max() < 1e-14 and np.allclose(A @ X, F)


def test_smoothing_follows_the_part_kind():
    s = MeshSettings(12.0)
    assert mesh_inputs(load_part(RAIL, {"length": 300}), s)[1]["smooth"] is True
    assert mesh_inputs(load_part(PLATE), s)[1]["smooth"] is False
    assert mesh_inputs(load_part("PF_4b_003_v2"), s)[1]["smooth"] is False
    pm = mesh_part(load_part(PLATE), s)
    assert pm.meta["smoothed"] is False


def test_prefetched_mesh_is_made_once_and_taken(tmp_path, monkeypatch):
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    made = []
    real = mesher.make_mesh

    def counting(part, settings, *a, **k):
        made.append(part.name)
        return real(part, settings, *a, **k)

    monkeypatch.setattr(mesher, "make_mesh", counting)
    jobs = [(load_part(PLATE), MeshSettings(14.0)), (load_part(RAIL, {"length": 200}), MeshSettings(14.0))]
    assert mesher.prefetch(jobs, from_environment()) == 2
    pms = [mesh_part(p, s) for p, s in jobs]
    assert sorted(made) == sorted([PLATE, RAIL]) and [pm.name for pm in pms] == [PLATE, RAIL]
    assert mesher.prefetch(jobs, from_environment()) == 0  # both now in the cache
    again = mesh_part(*jobs[0])
    assert again.meta["cache"] == "hit" and np.array_equal(again.points, pms[0].points)


def test_cancelled_prefetch_ends_its_mesher(tmp_path, monkeypatch):
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    job = (load_part(RAIL, {"length": 200}), MeshSettings(9.0))
    assert mesher.prefetch([job], from_environment()) == 1
    key = mesh_inputs(*job)[0]
    fut = pool._jobs[key][0]
    pool.cancel()
    with pytest.raises(BaseException):
        fut.result(timeout=30)
    assert not list((tmp_path / "cache").glob("rigfem-entries/meshes/*"))


FAST = ["--parts", "plate_A", "--fidelity", "draft", "--samples", "72", "--frames", "0", "--quiet"]


def test_no_pictures_and_verdict_printed_first(tmp_path, capsys, monkeypatch):
    import rigfem.report.check as report

    seen = []
    real = report.reactions_plot
    monkeypatch.setattr(report, "reactions_plot", lambda *a: (seen.append(capsys.readouterr().out), real(*a)))
    assert main(["check", "--out", str(tmp_path / "pics"), *FAST]) == 0
    assert "overall: PASS" in seen[0]  # the verdict was printed before the first picture
    assert main(["check", "--out", str(tmp_path / "none"), "--no-pictures", *FAST]) == 0
    d = tmp_path / "none"
    assert not list(d.glob("*.png")) and list((tmp_path / "pics").glob("*.png"))
    r = json.loads((d / "report.json").read_text())
    assert "not made" in r["pictures"] and not any(f.endswith(".png") for f in r["files"])
    assert "not made" in (d / "report.html").read_text() and "not made" in (d / "report.md").read_text()
    ref = json.loads((tmp_path / "pics" / "report.json").read_text())
    assert [p["peak_mpa"] for p in r["parts"]] == [p["peak_mpa"] for p in ref["parts"]]


def test_run_check_without_pictures(tmp_path):
    r = run_check(Request("final-cm", {"parts": ["plate_A"], "fidelity": "draft",
                                                             "samples": 36, "frames": 0, "modes": ["original"]}), Output(tmp_path / "o", pictures=False))
    assert r["verdict"] == "pass" and not list((tmp_path / "o").glob("*.png"))


def test_pypardiso_is_told_where_mkl_is():
    """pypardiso, imported without PYPARDISO_MKL_RT, searches the whole environment for MKL's
    library (a tenth of a second of every solving process); rigfem names the mkl wheel's file."""
    code = ("import glob, os\n"
            "def searched(*a, **k):\n    raise AssertionError('pypardiso searched for MKL')\n"
            "glob.glob = searched\n"
            "import rigfem.fe.solver as s\np = s.pardiso()\n"
            "print(p.ps.libmkl._name == os.environ['PYPARDISO_MKL_RT'] == s._mkl_rt())")
    env = {k: v for k, v in os.environ.items() if k != "PYPARDISO_MKL_RT"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"
