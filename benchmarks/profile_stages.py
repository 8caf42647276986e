"""Where the time goes: a check (cold and warm cache) and a sweep chunk, per stage.

Run: ``python benchmarks/profile_stages.py [--fidelity standard] [--chunk 64]``
-> results/benchmarks/stages.json (``python benchmarks/publish.py`` writes stages.md).  The cold
check starts with empty rigfem and numba caches.  Each stage is the cumulative time (cProfile, one process
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

from record import cold_env, write_record

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
    # the picture functions rigfem.check calls (field_picture runs inside render_field's fallback only)
    "pictures": [("report/pictures.py", "render_field"), ("report/pictures.py", "utilisation_plot"),
                 ("report/pictures.py", "reactions_plot"), ("report/pictures.py", "_plot_peaks")],
    "HTML report": [("report/html.py", "write_html")],
    "VTU/PVD writing": [("report/vtu.py", "write_unstructured")],
    "sweep: unit-field peaks": [("sweep/bases.py", "case_peak")],
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


def _profile(argv: list[str], env: dict, prof: str) -> None:
    subprocess.run([sys.executable, "-m", "cProfile", "-o", prof, *argv], env=env, check=True, capture_output=True)


SWEEP_CHUNK = """
import sys
from rigfem.sweep import SweepParams, build_bases, enumerate_configs, run_chunk
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
    samples = {}
    with tempfile.TemporaryDirectory() as tmp:
        check = ["-m", "rigfem", "check", "final-cm", "--fidelity", a.fidelity]
        env = cold_env(tmp)
        for name in ("cold", "warm"):
            prof = f"{tmp}/{name}.prof"
            _profile([*check, "--out", f"{tmp}/out-{name}"], env, prof)
            samples[f"check {name}"] = [_sample(prof)]
        prof = f"{tmp}/sweep.prof"
        script = Path(tmp) / "chunk.py"
        script.write_text(SWEEP_CHUNK)
        subprocess.run([sys.executable, str(script), "draft", str(a.chunk), prof],  # the user's (warm) cache
                       env=os.environ, check=True, capture_output=True)
        samples[f"sweep chunk ({a.chunk} configurations whose crank turns, draft, unit solutions built)"] = \
            [_sample(prof)]
    print(f"wrote {write_record('stages', samples, {}, {'fidelity': a.fidelity, 'chunk': a.chunk})}")


def _sample(prof: str) -> dict:
    total, stages = _stages(prof)
    return {"total (profiled)": total, **stages}


if __name__ == "__main__":
    main()
