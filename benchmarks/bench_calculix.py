"""rigfem vs CalculiX 2.20 on the 700 mm crank rail (P2, about 100 000 DOF), side by side.

The 2013 study's rail case: the rail held by the two screws of its pivot coupling
(ShaftInHole on hole_00 and hole_01), the far-joint load split over the last two holes
(BearingLoad on hole_10 and hole_11).  Each repeat times rigfem (mesh, assembly, solve,
stress) and then ccx on the deck rigfem exports for the same model; medians are written to
results/benchmarks/calculix_vs_rigfem.json (``python benchmarks/publish.py`` writes the .md).

    python benchmarks/bench_calculix.py --repeats 3 --threads 1
"""

from __future__ import annotations

import argparse
import os
import sys

if __name__ == "__main__":  # thread counts must be set before numpy/MKL load
    _pre = argparse.ArgumentParser(add_help=False)
    _pre.add_argument("--threads", type=int, default=1)
    _t = str(_pre.parse_known_args()[0].threads)
    os.environ.update(OMP_NUM_THREADS=_t, MKL_NUM_THREADS=_t, OPENBLAS_NUM_THREADS=_t, NUMBA_NUM_THREADS=_t)

import resource
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from record import OUT, summarise, write_record

from rigfem.cache import NO_CACHE
from rigfem.fe import BearingLoad, ShaftInHole, build_model, solve
from rigfem.tensors import von_mises
from rigfem.io import export_model, run_ccx
from rigfem.material import get_material
from rigfem.mesh import MeshSettings, mesh_part
from rigfem.rig import load_part

HOLES = ("hole_00", "hole_01", "hole_10", "hole_11")
SUPPORTS = [ShaftInHole("hole_00"), ShaftInHole("hole_01")]
CASES = [[BearingLoad("hole_10", (300.0, 200.0, 0.0)), BearingLoad("hole_11", (300.0, 200.0, 0.0))]]


def unit_cases(k: int) -> list:
    """k unit bearing loads (1 N) on the far holes, directions spread over the rail plane."""
    ang = 2 * np.pi * np.arange(k) / k
    return [BearingLoad(HOLES[2 + i % 2], (float(np.cos(a)), float(np.sin(a)), 0.0)) for i, a in enumerate(ang)]


def warm_up() -> float:
    """Solve the rail once on a coarse mesh, untimed in the comparison: the process's first solve
    imports the sparse solvers and loads (or, on an empty numba cache, compiles) the FE kernels,
    a one-time cost of a process that ccx, a compiled program, does not pay.  Returns its seconds."""
    t0 = time.perf_counter()
    pm = mesh_part(load_part("rail_size25", {"length": 700}), MeshSettings(size_mm=12.0, local_size_mm=2.4))
    solve(build_model(pm, get_material("rig_steel"), order=2), SUPPORTS, CASES)
    return time.perf_counter() - t0


def rigfem_once(settings: MeshSettings):
    """One full rigfem run; returns (model, solution, timings in s)."""
    part = load_part("rail_size25", {"length": 700})
    t0, c0 = time.perf_counter(), time.process_time()
    pm = mesh_part(part, settings, cache=NO_CACHE)
    t1, c1 = time.perf_counter(), time.process_time()
    model = build_model(pm, get_material("rig_steel"), order=2)
    model.K  # noqa: B018 - the stiffness is assembled on first use: time it here, with the P2 mesh
    t2 = time.perf_counter()
    sol = solve(model, SUPPORTS, CASES)
    t3, c3 = time.perf_counter(), time.process_time()
    st = sol.times
    times = {"mesh": t1 - t0, "assembly": t2 - t1, "factorise": st["factorise"], "solve": st["solve"],
             "stress": st["stress"], "supports_loads": (t3 - t2) - st["factorise"] - st["solve"] - st["stress"],
             "fe_total": t3 - t1, "total": t3 - t0, "cpu_mesh": c1 - c0, "cpu_fe_total": c3 - c1}
    return model, sol, times


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1, help="threads for both codes (MKL/OpenMP, ccx)")
    ap.add_argument("--size", type=float, default=6.0, help="global element size, mm")
    ap.add_argument("--refine-size", type=float, default=1.25, help="element size on the loaded holes, mm")
    ap.add_argument("--cases", type=int, default=4, help="unit load cases of the multi-case comparison")
    ap.add_argument("--out", type=Path, default=OUT, help="record folder (benchmarks/bench_perf.py: a scratch one)")
    args = ap.parse_args(argv)
    settings = MeshSettings(size_mm=args.size, refine=HOLES, local_size_mm=args.refine_size)
    rig, ccx, agree, multi = [], [], [], []
    first = warm_up()
    with tempfile.TemporaryDirectory(prefix="bench-ccx-") as tmp:
        for r in range(args.repeats):
            model, sol, times = rigfem_once(settings)
            rig.append(times)
            t0 = time.perf_counter()
            deck = export_model(model, SUPPORTS, CASES, Path(tmp) / "rail.inp", heading="700 mm crank rail")
            t_export = time.perf_counter() - t0
            c0 = _child_cpu()
            res = run_ccx(deck, threads=args.threads)
            ccx.append({"wall": res.wall_time, "ccx_reported": res.ccx_time, "export": t_export,
                        "cpu": _child_cpu() - c0})
            n = len(model.mesh.nodes)
            tip = int(np.argmax(model.mesh.nodes[:, 0]))
            u_fe, u_cx = sol.displacement(), res.displacement[0, :n]
            vm_fe, vm_cx = sol.von_mises(), von_mises(res.stress[0, :n])
            agree.append({"peak_von_mises_rigfem": float(vm_fe.max()), "peak_von_mises_ccx": float(vm_cx.max()),
                          "tip_disp_rigfem": float(np.linalg.norm(u_fe[tip])),
                          "tip_disp_ccx": float(np.linalg.norm(u_cx[tip]))})
            # k unit cases: rigfem factorises once, ccx factorises once per *STEP
            cases = unit_cases(args.cases)
            t0 = time.perf_counter()   # a fresh model: stiffness assembled again, as ccx does
            solk = solve(build_model(model.part, get_material("rig_steel"), order=2), SUPPORTS, cases)
            t_rig = time.perf_counter() - t0
            resk = run_ccx(export_model(model, SUPPORTS, cases, Path(tmp) / "unit.inp"), threads=args.threads)
            cmp_k = max(abs(von_mises(resk.stress[j, :n]).max() / solk.von_mises(np.eye(len(cases))[j]).max() - 1)
                        for j in range(len(cases)))
            multi.append({"rigfem_fe": t_rig, "ccx": resk.wall_time, "max_peak_rel_diff": float(cmp_k)})
            print(f"repeat {r + 1}: rigfem {times['total']:.2f} s (FE {times['fe_total']:.2f} s), "
                  f"ccx {res.wall_time:.2f} s; {args.cases} cases: rigfem FE {t_rig:.2f} s, ccx {resk.wall_time:.2f} s",
                  file=sys.stderr)
    s = summarise({"rigfem": rig, "ccx": ccx, "unit cases": multi})
    r, c, m = ({k: v["median"] for k, v in s[x].items()} for x in ("rigfem", "ccx", "unit cases"))
    params = {
        "case": "rail_size25, length 700 mm, P2 (C3D10); ShaftInHole hole_00+hole_01; "
                "BearingLoad (300, 200, 0) N on hole_10 and hole_11",
        "mesh": {"size_mm": args.size, "refine_size_mm": args.refine_size, "refine": list(HOLES),
                 "nodes": int(len(model.mesh.nodes)), "tets": int(len(model.mesh.elements)),
                 "dof": int(model.mesh.ndof)},
        "threads": args.threads, "repeats": args.repeats, "unit cases": args.cases,
        "rigfem warm-up s": first,
        "rigfem warm-up": "one untimed coarse solve first (imports, FE kernels loaded or compiled): a one-time "
                          "cost per process; every rigfem figure is of the part's own model, stiffness assembly included",
        "unit load": "1 N bearing loads on hole_10/hole_11, directions 360°/k apart",
        "rigfem_solver": sol.method, "rigfem_backward_error": float(sol.backward_errors.max()),
        "ccx": "CalculiX 2.20 (" + (shutil.which("ccx") or "?") + "), SPOOLES direct solver, "
               f"OMP_NUM_THREADS=CCX_NPROC_*={args.threads}"}
    derived = {"FE wall ratio rigfem / ccx": r["fe_total"] / c["wall"],
               "wall ratio incl. meshing": r["total"] / c["wall"], "CPU ratio": r["cpu_fe_total"] / c["cpu"],
               "unit cases wall ratio rigfem / ccx": m["rigfem_fe"] / m["ccx"],
               "peak von Mises rel diff": max(abs(x["peak_von_mises_ccx"] / x["peak_von_mises_rigfem"] - 1)
                                              for x in agree),
               "tip displacement rel diff": max(abs(x["tip_disp_ccx"] / x["tip_disp_rigfem"] - 1) for x in agree)}
    samples = {"rigfem": rig, "ccx": ccx, "agreement": agree, "unit cases": multi}
    print(f"wrote {write_record('calculix_vs_rigfem', samples, derived, params, out=args.out)}")
    return 0


def _child_cpu() -> float:
    """CPU seconds (user + system) of finished child processes (ccx)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


if __name__ == "__main__":
    sys.exit(main())
