"""Speed/accuracy of the crank-angle sampling and bearing directions of the FE check (issue 6), final-cm.

1. Cycle-mode stress peak vs samples: the FE check takes the peak over the *sampled* crank angles (no
   refinement), so its sampling error is measured too: plate_A and crank_rail on the draft
   mesh, peak von Mises vs samples against 3600 samples (same mesh and unit loads).

2. Cycle-mode stress peak vs the number of bearing directions (mesh fixed): separates the
   direction error of a preset from its mesh error.

Writes results/convergence/sampling.md and .json.  The dynamics' samples vs peak error and
time are ``python benchmarks/bench_dynamics.py`` (results/dynamics/sampling.md).  The mesh studies are
``rigfem convergence PART`` (see results/convergence/summary.md).

    python benchmarks/bench_convergence.py [cycle_stress] [directions]
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from rigfem.cache import from_environment
from rigfem.context import Context
from rigfem.fe import Plan, solve_cases
from rigfem.job import Request, read_job
from rigfem.pipeline import load_cases

ROOT = Path(__file__).resolve().parents[1]
SCENE = "final-cm"
SAMPLES = (36, 72, 180, 360, 720, 3600)


def cycle_stress(part: str) -> list[dict]:
    """Cycle-mode peak von Mises vs samples on the draft mesh (reference: 3600 samples)."""
    ctx, out = Context(from_environment()), {}
    for n in SAMPLES:
        job = read_job(Request(SCENE, {"parts": [part], "modes": ["cycle"], "fidelity": "draft",
                                       "samples": n}), ctx.cache)
        _, cases = load_cases(job, ctx)
        t = time.perf_counter()
        r = solve_cases(cases, job.settings, Plan(frames=None), ctx)[0]
        out[n] = (float(r.vm_rows.max()), time.perf_counter() - t, r.seconds.get("superpose", 0.0))
    ref = out[3600][0]
    return [{"part": part, "samples": n, "peak_mpa": v, "rel_err": v / ref - 1, "fe_seconds": s,
             "superpose_seconds": sp} for n, (v, s, sp) in out.items() if n != 3600]


def directions(part: str) -> list[dict]:
    """Cycle-mode peak vs bearing directions on the draft mesh (mesh held fixed)."""
    from rigfem.settings import FIDELITY
    from rigfem.verification import StepSpec, run_step, scene_cases

    job, by = scene_cases(Request(SCENE, {"parts": [part], "modes": ["cycle"]}), from_environment())
    rows = []
    for preset in ("draft",):
        f = FIDELITY[preset]
        for n in (8, 12, 24, 48):
            spec = StepSpec(f"{preset}/{n}", "d", 2, f.size_mm, f.local_size_mm, n)
            r = run_step(by[part](n), job.settings, spec, isolate=False)
            rows.append({"part": part, "mesh": preset, "directions": n,
                         "peak_mpa": r["modes"]["cycle"]["peak_mpa"], "seconds": r["seconds"],
                         "cpu_seconds": r["cpu_seconds"]})
    for r in rows:
        ref = next(x["peak_mpa"] for x in rows if x["mesh"] == r["mesh"] and x["directions"] == 48)
        r["rel_to_48"] = r["peak_mpa"] / ref - 1
    return rows


def main(sections: list[str]) -> None:
    """Recompute the named sections (all by default), keep the others from sampling.json."""
    d = ROOT / "results" / "convergence"
    d.mkdir(parents=True, exist_ok=True)
    path = d / "sampling.json"
    data = json.loads(path.read_text()) if path.is_file() else {}
    todo = sections or ["cycle_stress", "directions"]
    if "cycle_stress" in todo:
        data["cycle_stress"] = cycle_stress("plate_A") + cycle_stress("crank_rail")
    if "directions" in todo:
        data["directions"] = directions("plate_A") + directions("crank_rail")
    for gone in ("dynamics", "candidates"):  # now in bench_dynamics.py and rigfem convergence
        data.pop(gone, None)
    path.write_text(json.dumps(data, indent=1))
    cyc, dirs = (data.get(k, []) for k in ("cycle_stress", "directions"))
    md = ["# Sampling: crank-angle samples and bearing directions vs peak error (final-cm)", "",
          "Command: `python benchmarks/bench_convergence.py`; 2 shared cores.  The dynamics' samples vs "
          "peak error and time: results/dynamics/sampling.md (`python benchmarks/bench_dynamics.py`)."]
    md += ["", "## Cycle-mode stress peak (FE, draft mesh): max over the sampled crank angles", "",
           "Reference: 3600 samples on the same mesh.  The stress peak is not refined between samples, "
           "so its error is the raw sampling error of the superposed cycle.", "",
           "| part | samples | peak MPa | rel. error | FE s (mesh+solve+sweep) | sweep s |",
           "|---|---:|---:|---:|---:|---:|"]
    md += [f"| {r['part']} | {r['samples']} | {r['peak_mpa']:.3f} | {r['rel_err']:+.2e} | "
           f"{r['fe_seconds']:.1f} | {r['superpose_seconds']:.2f} |" for r in cyc]
    md += ["", "## Bearing directions (cycle mode): peak vs the number of unit load directions", "",
           "A turning pin force is a non-negative combination of the two neighbouring unit bearing loads; "
           "the mesh is held fixed (preset sizes), reference: 48 directions on the same mesh.", "",
           "| part | mesh | directions | peak MPa | vs 48 dirs | time s | CPU s |",
           "|---|---|---:|---:|---:|---:|---:|"]
    md += [f"| {r['part']} | {r['mesh']} | {r['directions']} | {r['peak_mpa']:.3f} | "
           f"{100 * r['rel_to_48']:+.2f} % | {r['seconds']:.1f} | {r['cpu_seconds']:.1f} |" for r in dirs]
    (d / "sampling.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
