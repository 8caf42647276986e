"""MKL PARDISO's default settings on a rig part against rigfem's (no refinement inside PARDISO).

    python benchmarks/bench_pardiso.py [--repeats 3] [--level draft] [--rhs 60]

Builds the supported stiffness of the 1000 mm rail of ``final-cm`` (the coupler/rocker rail, the
original mode's bolted supports) at the ladder ``--level``, then, in fresh processes alternating the
two settings, times PARDISO's analysis (phase 11), numeric factorisation (22) and one solve of
``--rhs`` right-hand sides (33: a cycle-mode part has about that many unit loads), with the worst
relative residual of the solves.  MKL's defaults (``iparm[0] = 0``) include 2 steps of iterative
refinement in every solve; ``rigfem.fe.solver.PARDISO_IPARM`` turns them off, since rigfem checks
every solve's backward error itself and refines only where needed.
Writes results/benchmarks/pardiso.json (``python benchmarks/publish.py`` writes the .md).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

from record import write_record

CHILD = """
import json, sys, time
import numpy as np
import pypardiso
from rigfem.check import load_check_scene
from rigfem.dynamics.cycle import cycle_history
from rigfem.dynamics.history import peaks
from rigfem.fe.model import StaticProblem, build_model
from rigfem.fe.partcase import mesh_case, supports_of
from rigfem.fe.solver import PARDISO_IPARM
from rigfem.loads.cases import part_cases
mine, level, nrhs = sys.argv[1] == "rigfem", sys.argv[2], int(sys.argv[3])
cs = load_check_scene("final-cm", {"parts": ["coupler_rail"], "modes": ["original"]})
h = cycle_history(cs.linkage, cs.motion, cs.crank_deg, cs.scene.speed_hz, cs.mass_model)
(_, case), = part_cases(h, peaks(h), cs.settings)
s = dict(cs.settings.levels())[level]
ls = StaticProblem(build_model(mesh_case(case, s), s.material, s.order), supports_of(case), "pardiso").linear_solver
A, U = ls.A, ls._upper  # the supported stiffness and the upper triangle PARDISO is given
B = np.asfortranarray(np.random.default_rng(0).standard_normal((A.shape[0], nrhs)))
ps = pypardiso.PyPardisoSolver(mtype=2)
for i, v in (PARDISO_IPARM.items() if mine else ()):
    ps.set_iparm(i, v)
out = {"dofs": int(A.shape[0]), "nnz_upper": int(U.nnz)}
for phase, name, b in ((11, "analysis_s", np.zeros((A.shape[0], 1))), (22, "factorise_s", np.zeros((A.shape[0], 1))),
                       (33, "solve_s", B)):
    ps.set_phase(phase)
    t0 = time.perf_counter()
    x = ps._call_pardiso(U, b)
    out[name] = time.perf_counter() - t0
out["residual_max"] = float((np.linalg.norm(A @ x - B, axis=0) / np.linalg.norm(B, axis=0)).max())
out["peak_numeric_kb"] = int(ps.iparm[16])
out["refinement_steps"] = int(ps.iparm[6])
print(json.dumps(out))
"""

LABELS = {"mkl": "MKL's defaults (iparm[0] = 0)", "rigfem": "rigfem's: PARDISO_IPARM (no refinement inside)"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--level", default="draft", choices=("coarse", "draft", "standard"))
    ap.add_argument("--rhs", type=int, default=60)
    a = ap.parse_args()
    runs: dict[str, list[dict]] = {label: [] for label in LABELS.values()}
    for _ in range(a.repeats):
        for which, label in LABELS.items():
            out = subprocess.run([sys.executable, "-c", CHILD, which, a.level, str(a.rhs)], check=True,
                                 capture_output=True, text=True).stdout
            runs[label].append(json.loads(out.strip().splitlines()[-1]))

    def med(label: str, key: str) -> float:
        return statistics.median(r[key] for r in runs[label])

    mkl, mine = LABELS["mkl"], LABELS["rigfem"]
    derived = {f"{k} MKL / rigfem": med(mkl, k) / med(mine, k) for k in ("analysis_s", "factorise_s", "solve_s")}
    derived["residual_max"] = max(r["residual_max"] for v in runs.values() for r in v)
    params = {"repeats": a.repeats, "level": a.level, "rhs": a.rhs, "part": "coupler_rail (1000 mm rail)",
              "mode": "original (bolted)"}
    print(f"wrote {write_record('pardiso', runs, derived, params)}")


if __name__ == "__main__":
    main()
