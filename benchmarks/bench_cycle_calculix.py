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
import os
import shutil
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
    from rigfem.check import load_check_scene
    from rigfem.dynamics import peaks, simulate
    from rigfem.fe import mesh_case, solve_cases, supports_of
from rigfem.tensors import von_mises
    from rigfem.io import export_model, run_ccx
    from rigfem.loads import part_cases

    samples: dict[str, list] = {}
    params = {"part": a.part, "fidelity": a.fidelity, "angles": a.angles, "repeats": a.repeats, "threads": 1}
    for n in a.angles:
        cs = load_check_scene("final-cm", {"fidelity": a.fidelity, "parts": [a.part], "modes": ["cycle"]})
        # N angles straight from the dynamics (a scene's [check].samples starts at 36: N ccx steps must run here)
        h = simulate(cs.linkage, samples=n, speed_hz=cs.scene.speed_hz, model=cs.mass_model)
        cases = part_cases(h, peaks(h), cs.settings)
        mesh_case(cases[0][1], cs.settings)  # the same mesh for both codes
        rig = samples.setdefault(f"rigfem, {n} angles", [])
        for _ in range(a.repeats):
            shutil.rmtree(Path(os.environ["RIGFEM_CACHE"]) / "solutions", ignore_errors=True)  # solve every time
            t0 = time.perf_counter()
            res = solve_cases(cases, cs.settings)[0]
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
