"""Cycle mode against CalculiX running the same crank angles as load steps.

A check's cycle mode gets the stress at every crank angle of a part from one factorisation
and a few dozen unit-load solutions, superposed.  CalculiX has no such shortcut: the same
crank angles are load steps, each assembled, factorised and solved.  This benchmark takes
the crank rail of the reference scene (cycle mode, ``--fidelity``), times rigfem's whole
part solve (P2 mesh given: assembly, factorisation, unit solves, stresses, superposition over
every crank angle, peak), then ccx on the identical model with ``m`` of those angles as
*STEPs for two values of ``m``; ccx's time is linear in the steps (T = a + b·m, fitted to the
two runs) and is extrapolated to every angle of the turn.  The peaks of the common angles
are compared.

    python benchmarks/bench_cycle_calculix.py [--fidelity draft] [--steps 4 12] [--repeats 3]

Writes results/benchmarks/cycle_vs_calculix.{md,json}.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fidelity", default="draft")
    ap.add_argument("--steps", type=int, nargs=2, default=[4, 12], help="two ccx step counts to fit")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--part", default="crank_rail")
    a = ap.parse_args(argv)
    os.environ["RIGFEM_CACHE"] = tempfile.mkdtemp(prefix="bench-cycle-cache-")  # no cached solutions
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    from rigfem.check import load_check_scene
    from rigfem.dynamics import peaks, simulate
    from rigfem.fe import mesh_case, solve_cases, supports_of, von_mises
    from rigfem.io import export_model, run_ccx
    from rigfem.loads import part_cases

    cs = load_check_scene("final-cm", {"fidelity": a.fidelity, "parts": [a.part], "modes": ["cycle"]})
    h = simulate(cs.linkage, samples=cs.samples, speed_hz=cs.scene.speed_hz, model=cs.mass_model)
    cases = part_cases(h, peaks(h), cs.settings)
    s = cs.settings
    mesh_case(cases[0][1], s)  # meshed once, outside the timing (same mesh for both)
    rig = []
    for _ in range(a.repeats):
        shutil.rmtree(Path(os.environ["RIGFEM_CACHE"]) / "solutions", ignore_errors=True)  # solve every time
        t0 = time.perf_counter()
        res = solve_cases(cases, s)[0]
        rig.append(time.perf_counter() - t0)
    rows = len(res.case.rows)
    sol, model = res.solution, res.solution.model
    ccx_runs = {}
    with tempfile.TemporaryDirectory(prefix="bench-cycle-") as tmp:
        for m in a.steps:
            pick = np.linspace(0, rows, m, endpoint=False).astype(int)
            F = sol.F @ res.coef[pick].T
            deck = export_model(model, supports_of(res.case), F, Path(tmp) / f"cycle{m}.inp",
                                heading=f"{a.part} cycle, {m} crank angles")
            walls, out = [], None
            for _ in range(a.repeats):
                out = run_ccx(deck, threads=1)
                walls.append(out.wall_time)
            n = len(model.mesh.nodes)
            diff = max(abs(von_mises(out.stress[j, :n]).max() / res.vm_rows[r] - 1) for j, r in enumerate(pick))
            ccx_runs[m] = {"median_s": statistics.median(walls), "runs": walls, "max_peak_rel_diff": float(diff)}
    (m1, m2) = a.steps
    b = (ccx_runs[m2]["median_s"] - ccx_runs[m1]["median_s"]) / (m2 - m1)
    a0 = ccx_runs[m1]["median_s"] - b * m1
    ccx_all = a0 + b * rows
    t_rig = statistics.median(rig)
    info = {"command": "python benchmarks/bench_cycle_calculix.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "part": a.part, "fidelity": a.fidelity, "dof": int(model.mesh.ndof), "crank_angles": rows,
            "unit_loads": int(sol.U.shape[1]), "rigfem_runs_s": rig, "rigfem_median_s": t_rig,
            "ccx": {str(k): v for k, v in ccx_runs.items()}, "ccx_per_step_s": b, "ccx_fixed_s": a0,
            "ccx_all_angles_s": ccx_all, "ratio": t_rig / ccx_all, "load_avg_end": os.getloadavg()[0]}
    md = [f"# Cycle mode vs CalculiX load steps: {a.part} of final-cm, {a.fidelity}", "",
          f"Command: `{info['command'].strip()}`; one thread each; median of {a.repeats} runs.", "",
          f"Model: {info['dof']} DOF (P2, C3D10), {rows} crank angles, {info['unit_loads']} unit loads.", "",
          "| | wall s |", "|---|---:|",
          f"| rigfem: assembly, one factorisation, {info['unit_loads']} unit solves, stresses, "
          f"superposition over {rows} angles | {t_rig:.1f} |"]
    md += [f"| CalculiX: {m} angles as *STEPs (measured) | {v['median_s']:.1f} |" for m, v in ccx_runs.items()]
    md += [f"| CalculiX: all {rows} angles (T = {a0:.1f} s + {b:.2f} s/step, extrapolated) | {ccx_all:.0f} |", "",
           f"Ratio rigfem / CalculiX over the turn: **{info['ratio']:.4f}**.  Peak von Mises at the common "
           f"angles agrees to {max(v['max_peak_rel_diff'] for v in ccx_runs.values()):.1e} (relative).  "
           f"Load average at the end {info['load_avg_end']:.1f}."]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "cycle_vs_calculix.json").write_text(json.dumps(info, indent=1) + "\n")
    (OUT / "cycle_vs_calculix.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
