"""Cycle mode against CalculiX doing the same work: same mesh, same crank angles, same outputs.

A check's cycle mode gets the stress at every crank angle of a part from one factorisation
and a few dozen unit-load solutions, superposed.  CalculiX has no such shortcut: each crank
angle is a load step, assembled, factorised and solved.  This benchmark takes the crank rail
of the reference scene (cycle mode, ``--fidelity``) with the turn sampled at N crank angles
(the dynamics sampled at N angles), meshes it once, then times rigfem's part solve (assembly,
factorisation, unit solves, stresses, superposition over the N angles, peak per angle) and
ccx on the identical model with the same N angles as N *STEPs (von Mises peak per angle).
Nothing is extrapolated: both codes compute every angle; the peaks are compared angle by angle.

    python benchmarks/bench_cycle_calculix.py [--fidelity draft] [--angles 12] [--repeats 3]

Writes results/benchmarks/cycle_vs_calculix.json (``python benchmarks/publish.py`` the .md).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tempfile
import time
from pathlib import Path

from record import summarise, write_record


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fidelity", default="draft")
    ap.add_argument("--angles", type=int, nargs="+", default=[12], help="crank angles per turn (N steps in ccx)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--part", default="crank_rail")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench-cycle-cache-") as cache:
        os.environ["RIGFEM_CACHE"] = cache  # no cached solutions; removed afterwards
        return _run(a)


def _run(a: argparse.Namespace) -> int:
    """Both codes on the same mesh and angles; the record."""
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    from rigfem.cache import from_environment
    from rigfem.context import Context
    from rigfem.fe import Plan, mesh_case, solve_cases, supports_of
    from rigfem.io import export_model, run_ccx
    from rigfem.job import Request, read_job
    from rigfem.pipeline import load_cases
    from rigfem.tensors import von_mises

    ctx = Context(from_environment())
    solving = Context(ctx.cache.without("solutions", "sweeps"))  # meshes cached, every solve and sweep done
    samples: dict[str, list] = {}
    params = {"part": a.part, "fidelity": a.fidelity, "angles": a.angles, "repeats": a.repeats, "threads": 1}
    for n in a.angles:
        job = read_job(Request("final-cm", {"fidelity": a.fidelity, "parts": [a.part], "modes": ["cycle"]}), ctx.cache)
        # N angles straight from the dynamics (a scene's [check].samples starts at 36: N ccx steps must run here)
        job = dataclasses.replace(job, dynamics=dataclasses.replace(job.dynamics, samples=n))
        _, cases = load_cases(job, ctx)
        mesh_case(cases[0][1], job.settings, ctx.cache)  # the same mesh for both codes
        rig = samples.setdefault(f"rigfem, {n} angles", [])
        for _ in range(a.repeats):
            t0 = time.perf_counter()
            res = solve_cases(cases, job.settings, Plan(frames=None), solving)[0]
            rig.append({"wall_s": time.perf_counter() - t0})
        sol, model = res.solution, res.solution.model
        rows = len(res.case.rows)
        params[f"{n} angles"] = {"dof": int(model.mesh.ndof), "rows": rows, "unit_loads": int(sol.U.shape[1])}
        ccx = samples.setdefault(f"ccx, {n} angles", [])
        with tempfile.TemporaryDirectory(prefix="bench-cycle-") as tmp:
            deck = export_model(model, supports_of(res.case), sol.F @ res.coef.T, Path(tmp) / f"cycle{n}.inp",
                                heading=f"{a.part} cycle, {rows} crank angles")
            for _ in range(a.repeats):
                out = run_ccx(deck, threads=1)
                k = len(model.mesh.nodes)
                diff = max(abs(von_mises(out.stress[j, :k]).max() / res.vm_rows[j] - 1) for j in range(rows))
                ccx.append({"wall_s": out.wall_time, "max_peak_rel_diff": float(diff)})
        print(f"{n} angles: rigfem {rig[-1]['wall_s']:.1f} s, ccx {ccx[-1]['wall_s']:.1f} s", flush=True)
    s = summarise(samples)
    derived = {f"rigfem / ccx, {n} angles": s[f"rigfem, {n} angles"]["wall_s"]["median"]
               / s[f"ccx, {n} angles"]["wall_s"]["median"] for n in a.angles}
    print(f"wrote {write_record('cycle_vs_calculix', samples, derived, params)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
