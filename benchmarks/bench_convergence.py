"""Speed/accuracy of the sampling (issue 6, "the same for the dynamics"), final-cm scene.

1. Dynamics: crank-angle samples vs wall time (median of 5, ``time.perf_counter``) of
   ``simulate`` + ``peaks`` and the worst relative error of the peak pin reactions and torque
   against 100 000 refined samples (raw sampled maximum and rigfem's refined peak).
   results/dynamics/sampling.md has the error table; this adds the time.
2. Cycle-mode stress peak vs samples: the FE check takes the peak over the *sampled* crank angles (no
   refinement), so its sampling error is measured too: plate_A and crank_rail on the draft
   mesh, peak von Mises vs samples against 3600 samples (same mesh and unit loads).

3. Cycle-mode stress peak vs the number of bearing directions (mesh fixed): separates the
   direction error of a preset from its mesh error.
4. On request (``candidates``): candidate preset values run on every studied part, error vs the
   reference peak of its convergence study.

Writes results/convergence/sampling.md and .json.  The mesh studies are
``rigfem convergence PART`` (see results/convergence/summary.md).

    python benchmarks/bench_convergence.py [dynamics] [cycle_stress] [directions] [candidates]
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from rigfem.check import load_check_scene
from rigfem.loadcases import part_cases
from rigfem.mechanisms import simulate
from rigfem.partcheck import solve_cases
from rigfem.reactions import peaks

ROOT = Path(__file__).resolve().parents[1]
SCENE = "final-cm"
ITEMS = ("O2", "A", "B", "O4", "torque")
SAMPLES = (36, 72, 180, 360, 720, 3600)


def _val(p: dict) -> float:
    return p["force_N"] if "force_N" in p else p["peak"]


def _median(fn, repeats: int = 5) -> float:
    fn()
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def dynamics() -> list[dict]:
    cs = load_check_scene(SCENE)
    lk, hz = cs.scene.linkage, cs.scene.speed_hz
    ref = peaks(simulate(lk, samples=100_000, speed_hz=hz))
    rows = []
    for n in SAMPLES:
        h = simulate(lk, samples=n, speed_hz=hz)
        raw, fine = peaks(h, refine=False), peaks(h)
        rows.append({"samples": n,
                     "simulate_ms": 1e3 * _median(lambda: simulate(lk, samples=n, speed_hz=hz)),
                     "simulate_peaks_ms": 1e3 * _median(lambda: peaks(simulate(lk, samples=n, speed_hz=hz))),
                     "raw_rel_err": max(abs(_val(raw[k]) / _val(ref[k]) - 1) for k in ITEMS),
                     "refined_rel_err": max(abs(_val(fine[k]) / _val(ref[k]) - 1) for k in ITEMS)})
    return rows


def cycle_stress(part: str) -> list[dict]:
    """Cycle-mode peak von Mises vs samples on the draft mesh (reference: 3600 samples)."""
    out = {}
    for n in SAMPLES:
        cs = load_check_scene(SCENE, {"parts": [part], "modes": ["cycle"], "fidelity": "draft",
                                      "samples": n})
        h = simulate(cs.scene.linkage, samples=n, speed_hz=cs.scene.speed_hz)
        t = time.perf_counter()
        r = solve_cases(part_cases(h, peaks(h), cs.settings), cs.settings)[0]
        out[n] = (float(r.vm_rows.max()), time.perf_counter() - t, r.seconds.get("superpose", 0.0))
    ref = out[3600][0]
    return [{"part": part, "samples": n, "peak_mpa": v, "rel_err": v / ref - 1, "fe_seconds": s,
             "superpose_seconds": sp} for n, (v, s, sp) in out.items() if n != 3600]


def directions(part: str) -> list[dict]:
    """Cycle-mode peak vs bearing directions on the draft mesh (mesh held fixed)."""
    from rigfem.convergence import StepSpec, run_step, scene_cases
    from rigfem.settings import FIDELITY

    settings, by = scene_cases(SCENE, [part], {"modes": ["cycle"]})
    rows = []
    for preset in ("draft",):
        f = FIDELITY[preset]
        for n in (8, 12, 24, 48):
            spec = StepSpec(f"{preset}/{n}", "d", 2, f["size_mm"], f["local_size_mm"], n)
            r = run_step(by[part](n), settings, spec, isolate=False)
            rows.append({"part": part, "mesh": preset, "directions": n,
                         "peak_mpa": r["modes"]["cycle"]["peak_mpa"], "seconds": r["seconds"],
                         "cpu_seconds": r["cpu_seconds"]})
    for r in rows:
        ref = next(x["peak_mpa"] for x in rows if x["mesh"] == r["mesh"] and x["directions"] == 48)
        r["rel_to_48"] = r["peak_mpa"] / ref - 1
    return rows


#: candidate preset values checked against the studies' references (results/convergence/<part>.json)
CANDIDATES = {"draft (8/1.7)": (8.0, 1.7, 8)}
CANDIDATE_PARTS = ("plate_A", "post_B", "crank_rail", "coupler_rail", "rocker_rail")


def candidates(d: Path) -> list[dict]:
    """Run each candidate setting on every studied part; error vs the study's reference peak."""
    from rigfem.convergence import StepSpec, run_step, scene_cases

    rows = []
    for part in CANDIDATE_PARTS:
        path = d / f"{part}.json"
        if not path.is_file():
            continue
        res = json.loads(path.read_text())
        settings, by = scene_cases(SCENE, [part])
        for label, (size, local, n_dir) in CANDIDATES.items():
            r = run_step(by[part](n_dir), settings, StepSpec(label, "preset", 2, size, local, n_dir))
            for mode, qs in res["modes"].items():
                for qty, a in qs.items():
                    ex = a.get("extrapolation") or {}
                    ref = ex.get("limit") if ex.get("converging") else None
                    q = r["modes"][mode][qty]
                    rows.append({"part": part, "mode": mode, "quantity": qty, "candidate": label,
                                 "peak_mpa": q, "reference_mpa": ref, "uncertainty": ex.get("gci"),
                                 "error": None if ref is None else q / ref - 1, "dofs": r["dofs"],
                                 "seconds": r["seconds"], "cpu_seconds": r["cpu_seconds"],
                                 "peak_rss_mib": r["peak_rss_mib"]})
    return rows


def main(sections: list[str]) -> None:
    """Recompute the named sections (all by default), keep the others from sampling.json."""
    d = ROOT / "results" / "convergence"
    d.mkdir(parents=True, exist_ok=True)
    path = d / "sampling.json"
    data = json.loads(path.read_text()) if path.is_file() else {}
    todo = sections or ["dynamics", "cycle_stress", "directions"]
    if "dynamics" in todo:
        data["dynamics"] = dynamics()
    if "cycle_stress" in todo:
        data["cycle_stress"] = cycle_stress("plate_A") + cycle_stress("crank_rail")
    if "directions" in todo:
        data["directions"] = directions("plate_A") + directions("crank_rail")
    if "candidates" in sections:  # only on request: it needs the convergence studies first
        data["candidates"] = candidates(d)
    path.write_text(json.dumps(data, indent=1))
    dyn, cyc, dirs = (data.get(k, []) for k in ("dynamics", "cycle_stress", "directions"))
    md = ["# Sampling: crank-angle samples vs time and peak error (final-cm)", "",
          "Command: `python benchmarks/bench_convergence.py`; dynamics wall time median of 5 "
          "(perf_counter), 2 shared cores.", "",
          "## Dynamics (rigid-body): peak pin reactions and torque", "",
          "Reference: 100 000 samples, refined.  Error = worst over O2, A, B, O4 and the torque.", "",
          "| samples | simulate ms | simulate + refined peaks ms | raw max rel. error "
          "| refined max rel. error |",
          "|---:|---:|---:|---:|---:|"]
    md += [f"| {r['samples']} | {r['simulate_ms']:.1f} | {r['simulate_peaks_ms']:.1f} | "
           f"{r['raw_rel_err']:.2e} | {r['refined_rel_err']:.2e} |" for r in dyn]
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
    cand = data.get("candidates", [])
    if cand:
        md += ["", "## Candidate preset values vs the convergence studies' reference peaks", "",
               "`python benchmarks/bench_convergence.py candidates`; reference and its uncertainty from "
               "results/convergence/<part>.json (none where the peak does not converge).", "",
               "| part | mode | quantity | candidate | peak MPa | reference MPa | error | DOFs | time s | CPU s "
               "| peak RSS MiB |", "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
        for r in cand:
            ref = "singular | - |" if r["error"] is None else \
                f"{r['reference_mpa']:.2f} ± {100 * (r['uncertainty'] or 0):.2f} % | {100 * r['error']:+.2f} % |"
            md.append(f"| {r['part']} | {r['mode']} | {r['quantity']} | {r['candidate']} | {r['peak_mpa']:.2f} | "
                      f"{ref} {r['dofs']} | {r['seconds']:.1f} | {r['cpu_seconds']:.1f} | "
                      f"{r['peak_rss_mib']:.0f} |")
    (d / "sampling.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
