"""FE core benchmark: stiffness assembly (rigfem kernel vs scikit-fem generic) and
solvers (pypardiso vs SuperLU vs CG+AMG) on a ~100k-DOF P2 rail-like bar.

    python benchmarks/bench_fe.py [--reps 3] [--nx 140]
    python benchmarks/bench_fe.py --rss-nx 1378   # one bar of about 1M DOF: assemble, factorise, solve

``--rss-nx`` builds, factorises and solves one bar and prints ``{"dof", "factorise_s", "solve_s"}``:
benchmarks/bench_perf.py runs it in a process per mesh to publish peak RSS against DOF.

Writes results/benchmarks/fe_assembly.json (raw runs, medians over ``--reps``; ``python benchmarks/publish.py``
writes the .md).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
from record import write_record
from skfem import Basis, ElementTetP2, ElementVector, MeshTet, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

from rigfem.fe import (
    Fixed,
    Gravity,
    SolverError,
    StaticProblem,
    SurfaceForce,
    build_model,
    fe_mesh,
    load_matrix,
    nodal_stress,
    stiffness,
)
from rigfem.material import get_material
from rigfem.mesh import PartMesh


def rail_bar(nx: int) -> PartMesh:
    """700 × 23 × 24 mm bar (the crank rail's envelope), structured tets, faces root/tip named."""
    m = MeshTet.init_tensor(np.linspace(0, 700, nx + 1), np.linspace(-11.5, 11.5, 6), np.linspace(0, 24, 6))
    f = m.boundary_facets()
    xc = m.p[0, m.facets[:, f]].mean(0)
    return PartMesh("rail_bar", m.p.T, m.t.T, {"root": m.facets[:, f[xc < 1e-9]].T,
                                               "tip": m.facets[:, f[xc > 700 - 1e-9]].T})


def cube(n: int) -> PartMesh:
    """100 mm cube, n³ × 6 structured tets, faces root (x = 0) and tip (x = 100)."""
    m = MeshTet.init_tensor(*(np.linspace(0, 100, n + 1),) * 3)
    f = m.boundary_facets()
    xc = m.p[0, m.facets[:, f]].mean(0)
    return PartMesh("cube", m.p.T, m.t.T, {"root": m.facets[:, f[xc < 1e-9]].T, "tip": m.facets[:, f[xc > 100 - 1e-9]].T})


def timed(fn, reps: int):
    out, ts = None, []
    for _ in range(reps):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return out, statistics.median(ts), ts


def rss_run(nx: int) -> dict:
    """The check's FE path on one bar (P2, clamped root, a tip force): what its peak memory is made of."""
    model = build_model(rail_bar(nx), get_material("rig_steel"), 2)
    t0 = time.perf_counter()
    problem = StaticProblem(model, [Fixed("root")], "pardiso")
    t1 = time.perf_counter()
    F = load_matrix(model, [[SurfaceForce("tip", (0.0, 100.0, 0.0))]])
    problem.linear_solver.solve(F[problem.free, 0])
    return {"dof": int(model.mesh.ndof), "factorise_s": t1 - t0, "solve_s": time.perf_counter() - t1}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rss-nx", type=int, metavar="NX", help="only: solve one bar of NX divisions, print its DOF")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--nx", type=int, default=140)
    ap.add_argument("--ncube", type=int, default=13)
    ap.add_argument("--amg-maxiter", type=int, default=400)
    a = ap.parse_args()
    if a.rss_nx:
        print(json.dumps(rss_run(a.rss_nx)))
        return
    part = rail_bar(a.nx)
    mat = get_material("rig_steel")
    fm = fe_mesh(part, 2)
    res = {"case": f"P2 box 700x23x24 mm, {len(fm.elements)} tets, {fm.ndof} DOF", "reps": a.reps}
    samples: dict[str, list] = {}
    print(res["case"])

    t0 = time.perf_counter()
    stiffness(fe_mesh(rail_bar(4), 2), mat.E, mat.nu)  # numba compile / cache load
    res["numba_first_call_s"] = time.perf_counter() - t0
    K, t_k, samples["assembly rigfem"] = timed(lambda: stiffness(fm, mat.E, mat.nu), a.reps)
    res["assembly_rigfem_s"] = t_k
    print(f"assembly rigfem kernel     {t_k:8.3f} s (median of {a.reps}); numba first call "
          f"{res['numba_first_call_s']:.2f} s")
    mesh = MeshTet(fm.nodes[:fm.n_vertices].T, fm.elements[:, :4].T)
    basis, t_b, samples["assembly skfem Basis"] = timed(lambda: Basis(mesh, ElementVector(ElementTetP2())), a.reps)
    form = linear_elasticity(*lame_parameters(mat.E, mat.nu))
    Ks, t_s, samples["assembly skfem asm"] = timed(lambda: asm(form, basis), a.reps)
    res.update(assembly_skfem_basis_s=t_b, assembly_skfem_asm_s=t_s)
    res["assembly_speedup"] = (t_b + t_s) / t_k
    assert abs(Ks).sum() == abs(K).sum() or abs(abs(Ks).sum() / abs(K).sum() - 1) < 1e-12
    print(f"assembly skfem generic     {t_s:8.3f} s (+ Basis {t_b:.3f} s)  -> rigfem {res['assembly_speedup']:.1f}x")

    res["solvers"] = {}
    for label, bench_part in (("rail", part), ("cube", cube(a.ncube))):
        model = build_model(bench_part, mat, 2)
        # seven unit load cases: tip forces x, y, z, body accelerations x, y, z, and one combined
        cases = [SurfaceForce("tip", tuple(v)) for v in np.eye(3)] + [Gravity(tuple(9810 * v)) for v in np.eye(3)]
        F = load_matrix(model, [cases] + cases)
        print(f"{label}: {model.mesh.ndof} DOF")
        for method in ("pardiso", "superlu", "amg"):
            reps = 1 if method != "pardiso" else a.reps
            problem, t_f, samples[f"{label}/{method} factorise"] = timed(
                lambda: StaticProblem(model, [Fixed("root")], method), reps)
            ls_ = problem.linear_solver
            Fs = F[problem.free] if method != "amg" else np.where(np.isin(np.arange(len(F)), problem.fixed)[:, None],
                                                                   0.0, F)
            ls_.maxiter = a.amg_maxiter
            try:
                _, t_1, samples[f"{label}/{method} first solve"] = timed(lambda: ls_.solve(Fs[:, 0]), reps)
                _, t_n, samples[f"{label}/{method} 6 cases"] = timed(lambda: ls_.solve(Fs[:, 1:7]), reps)
            except SolverError as e:
                res["solvers"][f"{label}/{method}"] = dict(factorise_s=t_f, failed=str(e), dof=model.mesh.ndof)
                print(f"{label:4s} {method:8s} setup {t_f:7.2f} s  FAILED: {e}")
                continue
            r = dict(dof=model.mesh.ndof, factorise_s=t_f, first_solve_s=t_1, block6_solve_s=t_n,
                     block6_over_first=t_n / (t_f + t_1), residual=float(ls_.residuals.max()),
                     backward_error=float(ls_.backward_errors.max()),
                     cg_iterations_6=ls_.iterations if method == "amg" else None)
            res["solvers"][f"{label}/{method}"] = r
            print(f"{label:4s} {method:8s} factorise/setup {t_f:7.2f} s  first solve {t_1:6.3f} s  6 more cases "
                  f"{t_n:6.3f} s ({100 * r['block6_over_first']:.0f} % of the first)  residual {r['residual']:.1e}")
        if label == "rail":
            p = StaticProblem(model, [Fixed("root")], "pardiso")
            U = np.zeros((model.mesh.ndof, 6))
            U[p.free] = p.linear_solver.solve(F[p.free, 1:7])
            _, t_sr, samples["stress recovery, 6 cases"] = timed(
                lambda: nodal_stress(model.mesh, mat.E, mat.nu, U), a.reps)
            res["stress_recovery_6_cases_s"] = t_sr
            print(f"nodal stress recovery, 6 cases {t_sr:.3f} s")

    samples["numba first call"] = [res["numba_first_call_s"]]
    params = {"reps": a.reps, "nx": a.nx, "ncube": a.ncube, "amg_maxiter": a.amg_maxiter}
    print(f"wrote {write_record('fe_assembly', samples, res, params)}")


if __name__ == "__main__":
    main()
