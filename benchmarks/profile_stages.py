"""Where the time goes: a check (cold and warm cache) and a sweep chunk, per stage.

Run: ``python benchmarks/profile_stages.py [--fidelity standard] [--chunk 64]``
-> results/benchmarks/stages.md.  Each stage is the cumulative time (cProfile, one process
per measurement) of the functions that do it; stages can nest in the profile but are listed
so they do not overlap.  Profiling adds some overhead; the totals are the profiled wall times.
"""

from __future__ import annotations

import argparse
import os
import pstats
import subprocess
import sys
import tempfile
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"

#: stage -> (module file suffix, function name) whose cumulative time it is
STAGES = {
    "dynamics (reactions over the turn)": [("dynamics/cycle.py", "simulate"), ("dynamics/history.py", "peaks")],
    "geometry (OpenCASCADE)": [("mesh/geometry.py", "build")],
    "meshing (gmsh, linear; the rest of mesh_part)": [("mesh/mesher.py", "mesh_part")],
    "second-order nodes (gmsh)": [("mesh/mesher.py", "second_order")],
    "P2 mesh, curved elements": [("fe/assembly.py", "fe_mesh")],
    "stiffness assembly": [("fe/assembly.py", "stiffness")],
    "factorisation": [("fe/solver.py", "__init__")],
    "solves": [("fe/solver.py", "solve")],
    "load vectors": [("fe/model.py", "load_matrix")],
    "stress recovery": [("fe/stress.py", "nodal_stress")],
    "cache I/O (meshes, unit solutions)": [("mesh/partmesh.py", "load_npz"), ("mesh/partmesh.py", "save_npz"),
                                          ("fe/cache.py", "load_solution"), ("fe/cache.py", "save_solution")],
    "superposition, peaks, error estimate": [("fe/solution.py", "peak_sweep"), ("fe/solution.py", "peak")],
    "pictures": [("report/pictures.py", "field_picture"), ("report/pictures.py", "reactions_plot"),
                 ("report/pictures.py", "_plot_peaks")],
    "VTU/PVD writing": [("report/vtu.py", "write_vtu")],
    "sweep: unit-field peaks": [("studies/sweep_bases.py", "case_peak")],
    "sweep: load cases": [("loads/cases.py", "part_cases")],
}


def _stages(prof: str) -> tuple[float, dict[str, float]]:
    st = pstats.Stats(prof).stats
    total = max(v[3] for v in st.values())
    out = {}
    for stage, funcs in STAGES.items():
        t = sum(v[3] for (f, _, name), v in st.items() if any(f.endswith(s) and name == n for s, n in funcs))
        if t > 0:
            out[stage] = t
    meshing = "meshing (gmsh, linear; the rest of mesh_part)"
    if meshing in out:  # mesh_part contains the geometry and the second-order step: listed apart
        out[meshing] -= out.get("geometry (OpenCASCADE)", 0.0) + out.get("second-order nodes (gmsh)", 0.0)
    return total, out


def _profile(argv: list[str], cache: str, prof: str) -> None:
    env = {**os.environ, "RIGFEM_CACHE": cache}
    subprocess.run([sys.executable, "-m", "cProfile", "-o", prof, *argv], env=env, check=True,
                   capture_output=True)


SWEEP_CHUNK = """
import sys
from rigfem.studies import SweepParams, build_bases, enumerate_configs, run_chunk
p = SweepParams(fidelity=sys.argv[1])
bases = build_bases(p)
import cProfile
turning = [c for c in enumerate_configs(p) if c["b2"] + c["d"] < c["b3"] + c["b4"] - 1e-6]  # the FE-checked kind
cProfile.run("run_chunk(turning[::7][:int(sys.argv[2])], p, bases)", sys.argv[3])
"""


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fidelity", default="standard")
    ap.add_argument("--chunk", type=int, default=64, help="configurations in the profiled sweep chunk")
    a = ap.parse_args(argv)
    cols = {}
    with tempfile.TemporaryDirectory() as tmp:
        check = ["-m", "rigfem", "check", "final-cm", "--fidelity", a.fidelity]
        for name in ("cold", "warm"):
            prof = f"{tmp}/{name}.prof"
            _profile([*check, "--out", f"{tmp}/out-{name}"], tmp + "/cache", prof)
            cols[f"check {name}"] = _stages(prof)
        prof = f"{tmp}/sweep.prof"
        script = Path(tmp) / "chunk.py"
        script.write_text(SWEEP_CHUNK)
        subprocess.run([sys.executable, str(script), "draft", str(a.chunk), prof],  # the user's (warm) cache
                       env=os.environ, check=True, capture_output=True)
        cols[f"sweep chunk ({a.chunk} configurations whose crank turns, draft, unit solutions built)"] = _stages(prof)
    names = list(cols)
    lines = [f"# Where the time goes (`python benchmarks/profile_stages.py --fidelity {a.fidelity} --chunk {a.chunk}`)",
             "", f"`rigfem check final-cm --fidelity {a.fidelity}`: cold = empty cache, warm = meshes and unit "
             "solutions cached; cumulative seconds per stage under cProfile (one process each, "
             f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end).", "",
             "| stage | " + " | ".join(names) + " |", "|---|" + "---:|" * len(names)]
    for stage in STAGES:
        vals = [cols[n][1].get(stage) for n in names]
        if any(vals):
            lines.append(f"| {stage} | " + " | ".join(f"{v:.2f}" if v else "–" for v in vals) + " |")
    lines.append("| **total (profiled)** | " + " | ".join(f"**{cols[n][0]:.1f}**" for n in names) + " |")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "stages.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
