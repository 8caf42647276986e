"""MKL PARDISO's default settings, rigfem's, and rigfem's without the variable blocks, on a rig part.

    python benchmarks/bench_pardiso.py [--repeats 3] [--level draft] [--rhs 60]

Builds the supported stiffness of the 1000 mm rail of ``final-cm`` (the coupler/rocker rail, the
original mode's bolted supports) at the ladder ``--level``, then, in fresh processes alternating the
settings, times PARDISO's analysis (phase 11), numeric factorisation (22) and one solve of
``--rhs`` right-hand sides (33: a cycle-mode part has about that many unit loads), with the worst
relative residual of the solves and the growth of the process's peak resident memory over the
three phases (Linux: its high-water mark, reset after the matrix is built, read before the
residual is checked; nothing is factorised before), for three settings: MKL's defaults
(``iparm[0] = 0``), which include 2 steps of iterative refinement in every solve;
``rigfem.fe.solver.PARDISO_IPARM``, which turns them off, since rigfem checks every solve's
backward error itself and refines only where needed, and stores the matrix in variable-size
blocks (iparm 37); and rigfem's without the blocks.
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
import scipy.sparse as sp
from rigfem.cache import from_environment
from rigfem.context import Context
from rigfem.fe.model import build_model, free_block, supported_stiffness
from rigfem.fe.partcase import mesh_case, supports_of
from rigfem.job import Request, read_job
from rigfem.pipeline import load_cases
iparm, level, nrhs = json.loads(sys.argv[1]), sys.argv[2], int(sys.argv[3])
ctx = Context(from_environment())
job = read_job(Request("final-cm", {"parts": ["coupler_rail"], "modes": ["original"]}), ctx.cache)
_, ((_, case),) = load_cases(job, ctx)
s = dict(job.settings.levels())[level]
model = build_model(mesh_case(case, s, ctx.cache), s.material, s.order, ctx.cache)
# the supported stiffness rigfem.fe.model.StaticProblem gives a direct solver, and its upper triangle
K, fixed, _ = supported_stiffness(model, supports_of(case))
A = free_block(K, fixed)
U = sp.triu(A, format="csr")
U.sort_indices()
B = np.asfortranarray(np.random.default_rng(0).standard_normal((A.shape[0], nrhs)))
ps = pypardiso.PyPardisoSolver(mtype=2)
for i, v in iparm.items():
    ps.set_iparm(int(i), v)
out = {"dofs": int(A.shape[0]), "nnz_upper": int(U.nnz)}


def kib(field):
    return next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith(field + ":"))


open("/proc/self/clear_refs", "w").write("5")  # the high-water mark starts again from here
before = kib("VmRSS")
for phase, name, b in ((11, "analysis_s", np.zeros((A.shape[0], 1))), (22, "factorise_s", np.zeros((A.shape[0], 1))),
                       (33, "solve_s", B)):
    ps.set_phase(phase)
    t0 = time.perf_counter()
    x = ps._call_pardiso(U, b)
    out[name] = time.perf_counter() - t0
out["peak_rss_growth_kib"] = kib("VmHWM") - before
out["residual_max"] = float((np.linalg.norm(A @ x - B, axis=0) / np.linalg.norm(B, axis=0)).max())
out["refinement_steps"] = int(ps.iparm[6])
print(json.dumps(out))
"""

LABELS = {"mkl": "MKL's defaults (iparm[0] = 0)",
          "rigfem": "rigfem's: PARDISO_IPARM (no refinement inside, variable blocks)",
          "csr": "rigfem's without the variable blocks (iparm 37 = 0)"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--level", default="draft", choices=("coarse", "draft", "standard"))
    ap.add_argument("--rhs", type=int, default=60)
    a = ap.parse_args()
    from rigfem.fe.solver import PARDISO_IPARM

    # pypardiso's 1-based iparm numbers and values of each setting
    settings = {"mkl": {}, "rigfem": PARDISO_IPARM, "csr": {**PARDISO_IPARM, 37: 0}}
    runs: dict[str, list[dict]] = {label: [] for label in LABELS.values()}
    for _ in range(a.repeats):
        for which, label in LABELS.items():
            out = subprocess.run([sys.executable, "-c", CHILD, json.dumps(settings[which]), a.level, str(a.rhs)],
                                 check=True, capture_output=True, text=True).stdout
            runs[label].append(json.loads(out.strip().splitlines()[-1]))

    def med(label: str, key: str) -> float:
        return statistics.median(r[key] for r in runs[label])

    mkl, mine, csr = LABELS["mkl"], LABELS["rigfem"], LABELS["csr"]
    keys = ("analysis_s", "factorise_s", "solve_s", "peak_rss_growth_kib")
    derived = {f"{k} MKL / rigfem": med(mkl, k) / med(mine, k) for k in keys}
    derived |= {f"{k} without blocks / rigfem": med(csr, k) / med(mine, k) for k in keys}
    derived["residual_max"] = max(r["residual_max"] for v in runs.values() for r in v)
    params = {"repeats": a.repeats, "level": a.level, "rhs": a.rhs, "part": "coupler_rail (1000 mm rail)",
              "mode": "original (bolted)"}
    print(f"wrote {write_record('pardiso', runs, derived, params)}")


if __name__ == "__main__":
    main()
