"""rigfem vs CalculiX 2.20 on the 700 mm crank rail (P2, about 100 000 DOF), side by side.

The 2013 study's rail case: the rail held by the two screws of its pivot coupling
(ShaftInHole on hole_00 and hole_01), the far-joint load split over the last two holes
(BearingLoad on hole_10 and hole_11).  Each repeat times rigfem (mesh, assembly, solve,
stress) and then ccx on the deck rigfem exports for the same model; medians are written to
results/benchmarks/calculix_vs_rigfem.{json,md}.

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

import json
import platform
import resource
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from rigfem.fe import BearingLoad, ShaftInHole, build_model, solve, von_mises
from rigfem.io import export_model, run_ccx
from rigfem.material import get_material
from rigfem.mesh import MeshSettings, mesh_part
from rigfem.rig import load_part

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"
HOLES = ("hole_00", "hole_01", "hole_10", "hole_11")
SUPPORTS = [ShaftInHole("hole_00"), ShaftInHole("hole_01")]
CASES = [[BearingLoad("hole_10", (300.0, 200.0, 0.0)), BearingLoad("hole_11", (300.0, 200.0, 0.0))]]


def unit_cases(k: int) -> list:
    """k unit bearing loads (1 N) on the far holes, directions spread over the rail plane."""
    ang = 2 * np.pi * np.arange(k) / k
    return [BearingLoad(HOLES[2 + i % 2], (float(np.cos(a)), float(np.sin(a)), 0.0)) for i, a in enumerate(ang)]


def rigfem_once(settings: MeshSettings):
    """One full rigfem run; returns (model, solution, timings in s)."""
    part = load_part("rail_size25", {"length": 700})
    t0, c0 = time.perf_counter(), time.process_time()
    pm = mesh_part(part, settings, use_cache=False)
    t1, c1 = time.perf_counter(), time.process_time()
    model = build_model(pm, get_material("rig_steel"), order=2)
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
    args = ap.parse_args(argv)
    settings = MeshSettings(size_mm=args.size, refine=HOLES, local_size_mm=args.refine_size)
    load0 = os.getloadavg()
    rig, ccx, agree, multi = [], [], [], []
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
            t0 = time.perf_counter()
            solk = solve(model, SUPPORTS, cases)
            t_rig = time.perf_counter() - t0 + times["assembly"]
            resk = run_ccx(export_model(model, SUPPORTS, cases, Path(tmp) / "unit.inp"), threads=args.threads)
            cmp_k = max(abs(von_mises(resk.stress[j, :n]).max() / solk.von_mises(np.eye(len(cases))[j]).max() - 1)
                        for j in range(len(cases)))
            multi.append({"rigfem_fe": t_rig, "ccx": resk.wall_time, "max_peak_rel_diff": float(cmp_k)})
            print(f"repeat {r + 1}: rigfem {times['total']:.2f} s (FE {times['fe_total']:.2f} s), "
                  f"ccx {res.wall_time:.2f} s; {args.cases} cases: rigfem FE {t_rig:.2f} s, ccx {resk.wall_time:.2f} s",
                  file=sys.stderr)
    med = {k: float(np.median([t[k] for t in rig])) for k in rig[0]}
    cmed = {k: float(np.median([t[k] for t in ccx])) for k in ccx[0]}
    mmed = {k: float(np.median([t[k] for t in multi])) for k in multi[0]}
    a = agree[-1]
    info = {
        "case": "rail_size25, length 700 mm, P2 (C3D10); ShaftInHole hole_00+hole_01; "
                "BearingLoad (300, 200, 0) N on hole_10 and hole_11",
        "mesh": {"size_mm": args.size, "refine_size_mm": args.refine_size, "refine": list(HOLES),
                 "nodes": int(len(model.mesh.nodes)), "tets": int(len(model.mesh.elements)),
                 "dof": int(model.mesh.ndof)},
        "threads": args.threads, "repeats": args.repeats,
        "rigfem_solver": sol.method, "rigfem_backward_error": float(sol.backward_errors.max()),
        "ccx": "CalculiX 2.20 (" + (shutil.which("ccx") or "?") + "), SPOOLES direct solver, "
               f"OMP_NUM_THREADS=CCX_NPROC_*={args.threads}",
        "machine": {"cpu": _cpu(), "cores": os.cpu_count(), "python": platform.python_version(),
                    "loadavg_start": load0, "loadavg_end": os.getloadavg()},
        "median_s": {"rigfem": med, "ccx": cmed},
        "runs": {"rigfem": rig, "ccx": ccx},
        "unit_cases": {"cases": args.cases, "median_s": mmed, "runs": multi,
                       "load": "1 N bearing loads on hole_10/hole_11, directions 360°/k apart"},
        "agreement": {**a, "peak_von_mises_rel_diff": a["peak_von_mises_ccx"] / a["peak_von_mises_rigfem"] - 1,
                      "tip_disp_rel_diff": a["tip_disp_ccx"] / a["tip_disp_rigfem"] - 1},
        "command": "python benchmarks/bench_calculix.py " + " ".join(argv if argv is not None else sys.argv[1:]),
    }
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "calculix_vs_rigfem.json").write_text(json.dumps(info, indent=2) + "\n")
    (OUT / "calculix_vs_rigfem.md").write_text(_markdown(info))
    print(_markdown(info))
    return 0


def _child_cpu() -> float:
    """CPU seconds (user + system) of finished child processes (ccx)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _cpu() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        return next(line.split(":", 1)[1].strip() for line in out.splitlines() if line.startswith("Model name"))
    except (OSError, StopIteration):
        return platform.processor()


def _markdown(info: dict) -> str:
    m, r, c = info["mesh"], info["median_s"]["rigfem"], info["median_s"]["ccx"]
    u, um = info["unit_cases"], info["unit_cases"]["median_s"]
    a = info["agreement"]
    rows = [("mesh (gmsh)", r["mesh"], None), ("assembly (P2 mesh + stiffness)", r["assembly"], None),
            ("supports + loads", r["supports_loads"], None), ("factorise", r["factorise"], None),
            ("solve", r["solve"], None), ("stress recovery", r["stress"], None),
            ("**FE total** (same mesh given)", r["fe_total"], c["wall"]),
            ("total incl. meshing", r["total"], None),
            ("CPU time, FE total (user + system)", r["cpu_fe_total"], c["cpu"])]
    lines = [
        "# rigfem vs CalculiX 2.20: 700 mm crank rail, P2", "",
        f"Command: `{info['command']}`  ",
        f"Case: {info['case']}  ",
        f"Mesh: {m['nodes']} nodes, {m['tets']} C3D10, **{m['dof']} DOF** (size {m['size_mm']} mm, "
        f"{m['refine_size_mm']} mm on {', '.join(m['refine'])})  ",
        f"Threads: {info['threads']} for both (rigfem solver: {info['rigfem_solver']}, backward error "
        f"{info['rigfem_backward_error']:.2g}; ccx: {info['ccx']})  ",
        f"Machine: {info['machine']['cpu']}, {info['machine']['cores']} cores shared with other jobs, load average "
        f"{info['machine']['loadavg_start'][0]:.2f} at start, {info['machine']['loadavg_end'][0]:.2f} at end  ",
        f"Median of {info['repeats']} repeats, each repeat runs rigfem then ccx on the same exported deck.", "",
        "| step | rigfem [s] | CalculiX [s] |", "|---|---:|---:|",
    ]
    lines += [f"| {name} | {v:.2f} | {'' if w is None else f'{w:.2f}'} |" for name, v, w in rows]
    lines += [
        "", f"CalculiX wall time is the whole ccx process (read deck, assemble, SPOOLES factorise/solve, stresses, "
            f"write .frd); ccx's own \"Total CalculiX Time\": {c['ccx_reported']:.2f} s. Deck export: "
            f"{c['export']:.2f} s (not counted).", "",
        f"Agreement: peak von Mises {a['peak_von_mises_rigfem']:.4g} MPa (rigfem) vs {a['peak_von_mises_ccx']:.4g} MPa "
        f"(ccx), {100 * a['peak_von_mises_rel_diff']:+.4f} %; tip displacement {a['tip_disp_rigfem']:.5g} mm vs "
        f"{a['tip_disp_ccx']:.5g} mm, {100 * a['tip_disp_rel_diff']:+.4f} %.", "",
        f"FE wall time ratio rigfem / CalculiX: **{r['fe_total'] / c['wall']:.2f}**; including meshing "
        f"{r['total'] / c['wall']:.2f}; CPU time ratio {r['cpu_fe_total'] / c['cpu']:.2f} (less sensitive to the "
        f"other jobs on the machine).", "",
        f"**{u['cases']} unit load cases** on the same mesh ({u['load']}): rigfem (assembly + one factorisation, "
        f"{u['cases']} solves, stresses) {um['rigfem_fe']:.2f} s, CalculiX ({u['cases']} *STEPs, one factorisation "
        f"each) {um['ccx']:.2f} s, ratio **{um['rigfem_fe'] / um['ccx']:.2f}**; largest peak von Mises difference "
        f"over the cases {100 * um['max_peak_rel_diff']:.4f} %.", "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
