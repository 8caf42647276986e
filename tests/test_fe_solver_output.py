"""Solver methods agree, shaft-in-hole support, export data, VTU output, materials."""

import platform

import meshio
import numpy as np
import pytest
import scipy.sparse as sp
from fe_shapes import bar_with_holes, box

from rigfem.errors import InputError
from rigfem.fe import (
    BearingLoad,
    Fixed,
    ShaftInHole,
    StaticProblem,
    SurfaceForce,
    build_model,
    export_data,
    solve,
)
from rigfem.material import get_material, material_from_dict
from rigfem.report import write_vtu


@pytest.fixture(scope="module")
def cantilever():
    return build_model(box(100, 10, 10, 20, 2, 2), get_material("rig_steel"), 2)


def test_pardiso_superlu_amg_agree(cantilever):
    cases = [SurfaceForce("xmax", (0, 0, -100)), SurfaceForce("xmax", (50, 20, 0))]
    sols = {m: solve(cantilever, [Fixed("xmin")], cases, solver=m) for m in ("pardiso", "superlu", "amg")}
    ref = sols["superlu"].U
    for m, s in sols.items():
        assert s.method == m and s.residuals.max() < 1e-8 and s.backward_errors.max() < 1e-10
        assert np.abs(s.U - ref).max() < 1e-6 * np.abs(ref).max()
    with pytest.raises(InputError, match="solver"):
        solve(cantilever, [Fixed("xmin")], cases, solver="cholesky")


def test_export_data_reproduces_solution(cantilever):
    cases = [SurfaceForce("xmax", (0, 0, -100))]
    sol = solve(cantilever, [Fixed("xmin")], cases)
    ex = export_data(cantilever, [Fixed("xmin")], cases)
    assert ex.element_type == "C3D10" and ex.elements.shape[1] == 10
    # corner nodes positively oriented, mid-edge nodes at edge midpoints in C3D10 order
    x = ex.nodes[ex.elements]
    assert (np.linalg.det(x[:, 1:4] - x[:, :1]) > 0).all()
    assert np.allclose(x[:, 4], (x[:, 0] + x[:, 1]) / 2) and np.allclose(x[:, 6], (x[:, 2] + x[:, 0]) / 2)
    free = np.setdiff1d(np.arange(3 * len(ex.nodes)), ex.fixed_dofs)
    assert np.allclose(cantilever.K[free][:, free] @ sol.U[free, 0], ex.loads[free, 0], atol=1e-8 * 100)


def test_shaft_in_hole_reactions_and_bearing_half():
    part = bar_with_holes(100, 25, 10, 5, [20, 80], size=6, h_hole=2.0)
    model = build_model(part, get_material("rig_steel"), 2)
    F = 1000.0
    sol = solve(model, [ShaftInHole("h0", direction=(-1, 0, 0))], [BearingLoad("h1", (F, 0, 0))])
    r = sol.support_reactions["ShaftInHole(h0)"][0]
    assert np.allclose(r[:3], [-F, 0, 0], atol=1e-9 * F)
    # the shaft bears on the -x half of the hole; the +x half carries only the weak tangential/axial springs
    x = model.mesh.nodes - part.holes["h0"].center
    rn = sol.reactions[:, 0].reshape(-1, 3)
    on = np.isin(np.arange(len(x)), np.unique(model.mesh.surfaces["h0"]))
    front, back = on & (x[:, 0] < -1.0), on & (x[:, 0] > 1.0)
    assert np.abs(rn[back]).sum() < 0.01 * np.abs(rn[front]).sum()
    p = sol.peak()
    assert np.isfinite(p.value) and p.error_pct >= 0
    with pytest.raises(InputError, match="hole 'h7'"):
        solve(model, [ShaftInHole("h7")], [BearingLoad("h1", (F, 0, 0))])


@pytest.mark.heavy
def test_shaft_support_peak_converges_fixed_hole_does_not():
    """Peak von Mises at the support hole under refinement: bounded for ShaftInHole, growing for Fixed."""
    peaks = {"shaft": [], "fixed": []}
    for size, h in ((6.0, 2.0), (4.0, 1.0), (3.0, 0.5)):
        part = bar_with_holes(100, 25, 10, 5, [20, 80], size=size, h_hole=h)
        model = build_model(part, get_material("rig_steel"), 2)
        near = np.linalg.norm(model.mesh.nodes[:, :2] - [20, 0], axis=1) < 10
        for k, sup in (("shaft", ShaftInHole("h0", direction=(-1, 0, 0))), ("fixed", Fixed("h0"))):
            sol = solve(model, [sup], [BearingLoad("h1", (1000.0, 0, 0))])
            peaks[k].append(sol.von_mises()[near].max())
    assert abs(peaks["shaft"][-1] / peaks["shaft"][-2] - 1) < 0.05
    assert peaks["fixed"][-1] / peaks["fixed"][-2] > peaks["shaft"][-1] / peaks["shaft"][-2]


def test_vtu_roundtrip(cantilever, tmp_path):
    sol = solve(cantilever, [Fixed("xmin")], [SurfaceForce("xmax", (0, 0, -100))])
    m = meshio.read(write_vtu(tmp_path / "c.vtu", sol, None, 375.0))
    assert m.cells[0].type == "tetra10" and len(m.points) == len(cantilever.mesh.nodes)
    assert m.point_data["stress"].shape == (len(m.points), 6)
    for k in ("displacement", "stress", "von_mises", "safety_factor"):
        assert np.isfinite(m.point_data[k]).all()
    vm = m.point_data["von_mises"]
    i = int(np.argmax(vm))
    assert m.point_data["safety_factor"][i] == pytest.approx(375.0 / vm[i])


def test_materials():
    assert get_material("abs").E == 2200.0 and get_material("al_6082_t6").sigma_u == 310.0
    with pytest.raises(InputError, match="unknown"):
        get_material("unobtainium")
    with pytest.raises(InputError, match="nu"):
        material_from_dict({"name": "x", "E": 1e5, "nu": 0.5, "sigma_u": 100, "density": 1e-9})
    with pytest.raises(InputError, match="missing"):
        material_from_dict({"name": "x", "E": 1e5})
    assert sp.issparse(build_model(box(1, 1, 1, 1, 1, 1), get_material("abs"), 1).K)


def test_factorise_once_and_superposition(cantilever):
    problem = StaticProblem(cantilever, [Fixed("xmin")])
    a = problem.solve([SurfaceForce("xmax", (0, 0, -100)), SurfaceForce("xmax", (0, 40, 0))])
    b = problem.solve([[SurfaceForce("xmax", (0, 0, -50)), SurfaceForce("xmax", (0, 60, 0))]])
    c = np.array([0.5, 1.5])
    assert np.allclose(a.U @ c, b.U[:, 0], rtol=1e-9, atol=1e-12)
    assert np.allclose(a.stress(c), b.stress(), atol=1e-9 * b.peak().value)
    assert a.peak(c).value == pytest.approx(b.peak().value, rel=1e-9)
    vals, nodes = a.peak_sweep(np.array([c, [1.0, 0.0], [0.0, 1.0]]))
    assert vals[0] == pytest.approx(b.peak().value, rel=1e-9) and nodes[0] == b.peak().node
    assert vals[1] == pytest.approx(a.peak(np.array([1.0, 0.0])).value, rel=1e-12)


_RELEASE_PROBE = """
import gc
import numpy as np, scipy.sparse as sp
from rigfem.fe import LinearSolver
n = 40  # 3-D Laplacian, 64 000 unknowns: a factor of about 150 MB
d = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], (n, n))
eye = sp.identity(n)
A = (sp.kron(sp.kron(d, eye), eye) + sp.kron(sp.kron(eye, d), eye) + sp.kron(sp.kron(eye, eye), d)).tocsr()
def peak():  # VmHWM: peak RSS of this process image (ru_maxrss would carry the parent's over exec)
    with open("/proc/self/status") as f:
        return next(int(l.split()[1]) for l in f if l.startswith("VmHWM")) / 1024
def round_trip():
    s = LinearSolver(A, "pardiso")
    s.solve(np.ones(A.shape[0]))
    del s
    gc.collect()
r0 = peak(); round_trip(); r1 = peak()
for _ in range(6):
    round_trip()
print(r1 - r0, peak() - r1)
"""


@pytest.mark.skipif(platform.machine() != "x86_64", reason="pypardiso (MKL) is a dependency on x86_64 only")
def test_pardiso_factors_are_released_with_their_solver():
    """MKL holds PARDISO's factors outside Python: a solver must release them when it is
    dropped, or every factorisation of a long run (sweep, convergence, test suite) stays in
    memory.  In a fresh process (its own peak RSS), six more factorise/solve/drop rounds raise
    the peak by far less than the first one (by six times it before the release was added)."""
    import subprocess
    import sys

    from rigfem.fe.solver import pardiso

    assert pardiso() is not None, "pypardiso (a declared dependency on x86_64) is not installed"
    out = subprocess.run([sys.executable, "-c", _RELEASE_PROBE], capture_output=True, text=True, check=True)
    first, more = map(float, out.stdout.split())
    assert first > 50.0  # the probe's factor is big enough to be seen
    assert more < 0.5 * first


def test_solution_cache_reproduces_the_solve_exactly(tmp_path, monkeypatch):
    """A part model solved once is loaded from the disk cache the second time, bit for bit."""
    from fe_shapes import plate_with_hole

    from rigfem.fe import Pressure, Symmetry, build_model, cached_solve
    from rigfem.material import get_material

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    pm = plate_with_hole(60.0, 40.0, 2.0, 5.0, size=8.0, h_hole=3.0)
    pm.meta["hash"] = "test-mesh"
    sup = [Symmetry("xsym"), Symmetry("ysym"), Symmetry("zsym")]
    first = cached_solve(build_model(pm, get_material("rig_steel"), 2), sup, [Pressure("xmax", -10.0)])
    second = cached_solve(build_model(pm, get_material("rig_steel"), 2), sup, [Pressure("xmax", -10.0)])
    assert "cache" not in first.times and second.times["cache"] == 1.0
    for name in ("U", "F", "reactions", "nodal_stress"):
        assert np.array_equal(getattr(first, name), getattr(second, name))
    assert second.peak().value == first.peak().value
    # another load, material or mesh is another entry
    other = cached_solve(build_model(pm, get_material("abs"), 2), sup, [Pressure("xmax", -10.0)])
    assert "cache" not in other.times
    assert len(list((tmp_path / "rigfem-entries" / "solutions").iterdir())) == 2


def test_peak_von_mises_is_exact():
    """The bounded search returns the brute-force maximum and its node, whatever the chunking:
    a field with one sharp peak, rows that cancel it, rows of zeros."""
    from rigfem.tensors import peak_von_mises, von_mises

    rng = np.random.default_rng(1)
    S = rng.normal(size=(5, 3000, 6))
    S[0, 17] *= 40.0  # one field with a sharp peak, others diffuse
    C = rng.normal(size=(40, 5))
    C[3] = 0.0
    C[4] = [0.0, 1.0, -1.0, 0.5, 0.0]
    brute = von_mises(np.einsum("rk,knc->rnc", C, S))
    for chunk in (1, 7, 64):
        vals, nodes = peak_von_mises(C, S, chunk=chunk)
        assert np.allclose(vals, brute.max(1), rtol=1e-13, atol=0)
        ok = vals > 0
        assert np.array_equal(nodes[ok], brute.argmax(1)[ok])


def test_pardiso_runs_with_rigfems_settings_and_no_inner_refinement(cantilever):
    """PARDISO gets rigfem's iparm (not MKL's defaults, which refine every solve twice): it reports
    no refinement step of its own, and rigfem's check of every solve still holds."""
    from rigfem.fe.solver import PARDISO_IPARM

    ls = StaticProblem(cantilever, [Fixed("xmin")], "pardiso").linear_solver
    F = np.random.default_rng(1).standard_normal((ls.A.shape[0], 8))
    X = ls.solve(F)
    assert all(ls._ps.iparm[i - 1] == v for i, v in PARDISO_IPARM.items())
    assert ls._ps.iparm[6] == 0  # iterative refinement steps PARDISO performed
    assert ls.backward_errors.max() < 1e-13 and np.abs(ls.A @ X - F).max() < 1e-8 * np.abs(F).max()


def test_kept_combinations_answer_as_before_and_refuse_the_rest(cantilever):
    """Solution.kept holds only some combinations of the unit cases (what a check keeps of a part
    once it is final): a kept combination gives the same fields, peak, loads and reactions as the
    full solution; a combination it dropped raises instead of answering with wrong numbers."""
    cases = [SurfaceForce("xmax", (0, 0, -100)), SurfaceForce("xmax", (50, 20, 0)), SurfaceForce("xmax", (0, 30, 0))]
    full = solve(cantilever, [Fixed("xmin")], cases)
    C = np.array([[1.0, -0.5, 2.0], [0.0, 1.0, 0.0], [1.0, -0.5, 2.0]])  # a repeated row is kept once
    kept = full.kept(C)
    assert kept.U.shape[1] == 2 and kept.nodal_stress.shape[0] == 2 and kept.cases == 3
    for c in C:
        assert np.allclose(kept.displacement(c), full.displacement(c), rtol=1e-12, atol=0)
        assert np.allclose(kept.stress(c), full.stress(c), rtol=1e-12, atol=1e-12)
        assert np.allclose(kept.loads(c), full.loads(c)) and np.allclose(kept.reaction(c), full.reaction(c))
        assert kept.peak(c) == full.peak(c)
    assert np.allclose(kept.peak_sweep(C)[0], full.peak_sweep(C)[0], rtol=1e-12)
    assert np.array_equal(kept.equilibrium_error, full.equilibrium_error)  # the 3 solves' own check
    again = kept.kept(C[1:2])  # a kept solution kept again copies its cases: the same bytes
    assert again.U.shape[1] == 1 and np.array_equal(again.stress(C[1]), kept.stress(C[1]))
    with pytest.raises(ValueError, match="kept 2 combinations of its 3 load cases"):
        kept.stress([1.0, 0.0, 0.0])
    with pytest.raises(InputError, match="3 finite numbers"):
        kept.stress([1.0, 0.0])


def test_a_last_solve_frees_the_factors_before_the_stresses(cantilever):
    """``solve`` (one batch of cases) frees the factorisation before recovering the stresses, so
    the two largest arrays of a part are never held together; the problem then solves no more."""
    from rigfem.fe import StaticProblem

    problem = StaticProblem(cantilever, [Fixed("xmin")])
    sol = problem.solve([SurfaceForce("xmax", (0, 0, -100))], last=True)
    assert sol.backward_errors.max() < 1e-10 and problem.linear_solver.A is None
    with pytest.raises(RuntimeError, match="released"):
        problem.solve([SurfaceForce("xmax", (0, 0, -100))])


@pytest.mark.skipif(platform.system() != "Linux", reason="malloc_trim is glibc's")
def test_the_heap_is_trimmed_on_linux():
    """rigfem gives freed heap back after each part (rigfem.memory.trim_heap): on Linux (glibc)
    the call must reach malloc_trim, not silently do nothing."""
    from rigfem.memory import _libc, trim_heap

    assert _libc() is not None
    trim_heap()


