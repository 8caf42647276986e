"""gmsh's time per meshing step for every ladder level of a check's parts, at gmsh's default 1D
integration precision and at rigfem's (``rigfem.mesh.mesher.LC_INTEGRATION_PRECISION``).

    python benchmarks/bench_mesh.py [--repeats 3] [--scene final-cm] [--fidelity standard]

The meshes are the check's own: every part geometry of the scene, refined at its cases' loaded
holes (``rigfem.fe.partcase.part_geometries`` and ``group_job``, as the check groups them), at every
level of the preset's ladder.  Each setting meshes them all in a fresh process
(``rigfem.mesh.mesher._mesh``, the mesher process's gmsh work: no cache, one thread), the settings
alternating, ``--repeats`` processes each; the steps are timed by the mesher itself (the mesh's
``meta["stages"]``).  Writes results/benchmarks/mesh.json
(``python benchmarks/publish.py`` writes mesh.md).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

from record import write_record

CHILD = """
import json, sys
from rigfem.cache import from_environment
from rigfem.context import Context
from rigfem.fe.partcase import group_job, part_geometries
from rigfem.job import Request, read_job
from rigfem.mesh import mesher
from rigfem.pipeline import load_cases
precision, scene, fidelity = sys.argv[1], sys.argv[2], sys.argv[3]
if precision != "rigfem":
    mesher.LC_INTEGRATION_PRECISION = float(precision)
ctx = Context(from_environment())
job = read_job(Request(scene, {"fidelity": fidelity}), ctx.cache)
_, cases = load_cases(job, ctx)
out = []
for group in part_geometries(cases).values():
    for level, s in job.settings.levels():
        part, ms = group_job(group, s)
        pm = mesher._mesh(part, ms, float("inf"), "bench")
        out.append({"part": f"{part.name} ({group[0][1].name})", "level": level, "tets": len(pm.tets),
                    "min_sicn": pm.quality["min"], "seconds": pm.meta["seconds"], **pm.meta["stages"]})
print(json.dumps(out))
"""

#: gmsh's own default of Mesh.LcIntegrationPrecision
GMSH_DEFAULT = 1e-9
LABELS = {"gmsh": f"gmsh's default precision ({GMSH_DEFAULT:g})", "rigfem": "rigfem's precision"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--scene", default="final-cm")
    ap.add_argument("--fidelity", default="standard", choices=("draft", "standard", "fine"))
    a = ap.parse_args()
    from rigfem.mesh.mesher import LC_INTEGRATION_PRECISION

    arg = {"gmsh": repr(GMSH_DEFAULT), "rigfem": "rigfem"}
    runs: dict[str, list[list[dict]]] = {label: [] for label in LABELS.values()}
    for _ in range(a.repeats):
        for which, label in LABELS.items():
            out = subprocess.run([sys.executable, "-c", CHILD, arg[which], a.scene, a.fidelity],
                                 check=True, capture_output=True, text=True).stdout
            runs[label].append(json.loads(out.strip().splitlines()[-1]))
    # one series per (setting, mesh): the repeats' samples of that mesh
    samples = {f"{label}: {m['part']} {m['level']}": [run[i] for run in rs]
               for label, rs in runs.items() for i, m in enumerate(rs[0])}
    meshes = [f"{m['part']} {m['level']}" for m in runs[LABELS["rigfem"]][0]]

    def med(label: str, mesh: str, key: str) -> float:
        return statistics.median(r[key] for r in samples[f"{label}: {mesh}"])

    old, new = LABELS["gmsh"], LABELS["rigfem"]
    derived = {"seconds, all meshes: gmsh / rigfem": sum(med(old, m, "seconds") for m in meshes)
               / sum(med(new, m, "seconds") for m in meshes),
               "1D seconds, all meshes: gmsh / rigfem": sum(med(old, m, "1D") for m in meshes)
               / sum(med(new, m, "1D") for m in meshes),
               "largest tet count change": max(abs(med(new, m, "tets") / med(old, m, "tets") - 1) for m in meshes)}
    params = {"repeats": a.repeats, "scene": a.scene, "fidelity": a.fidelity, "meshes": meshes,
              "precision": {old: GMSH_DEFAULT, new: LC_INTEGRATION_PRECISION}}
    print(f"wrote {write_record('mesh', samples, derived, params)}")


if __name__ == "__main__":
    main()
