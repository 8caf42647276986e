"""Linkage dynamics benchmark: full-cycle time, sampling vs peak error, rigid-body vs original.

Run:  python benchmarks/bench_dynamics.py [--repeats N]

Writes results/benchmarks/dynamics.json (raw timings; ``python benchmarks/publish.py`` the .md),
results/dynamics/sampling.md (sample count vs peak error) and
results/dynamics/rigid_vs_original.{md,json} (the two mass models on the calibration case).
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import time
from pathlib import Path

from record import summarise, write_record

from rigfem.dynamics import original_program, peaks, simulate, solve
from rigfem.linkage import crank_angles, four_bar
from rigfem.rig import RIG_MASSES

ROOT = Path(__file__).resolve().parents[1]
REF = (540.0, 840.0, 780.0, 1020.0)
ITEMS = ("O2", "A", "B", "O4", "torque")
CAL = {"O2": 641.9099, "A": 578.8140, "B": 379.4016, "O4": 366.4701, "torque": 199.7707}


def _samples(fn, repeats: int) -> list[dict]:
    """Wall and CPU ms of ``repeats`` runs after a warm-up; CPU time is the fairer figure when the
    machine is shared (wall time then includes waiting for a core)."""
    fn()  # warm-up (imports, caches)
    out = []
    for _ in range(repeats):
        c, t = time.process_time(), time.perf_counter()
        fn()
        out.append({"wall_ms": (time.perf_counter() - t) * 1e3, "cpu_ms": (time.process_time() - c) * 1e3})
    return out


def _val(p: dict) -> float:
    return p["force_N"] if "force_N" in p else p["peak"]


def timings(repeats: int) -> dict:
    """Closed form (the default for the rig four-bar) and the general solver side by side."""
    lk = four_bar(*REF)
    out = {}
    for label, fn in (
        ("closed form, 5000 angles (simulate)", lambda: simulate(lk, 5000)),
        ("general solver, 5000 angles", lambda: solve(lk, crank_angles(5000), general=True)),
        ("closed form, 5000 angles + refined peaks", lambda: peaks(simulate(lk, 5000))),
        ("general solver, 5000 angles + refined peaks", lambda: peaks(solve(lk, crank_angles(5000), general=True))),
        ("closed form, 3600 angles (simulate)", lambda: simulate(lk, 3600)),
        ("original (2013) model, 3600 angles", lambda: simulate(lk, 3600, model="original")),
        ("closed form, 360 angles + refined peaks", lambda: peaks(simulate(lk, 360))),
    ):
        out[label] = _samples(fn, repeats)
    return out


def sampling_table() -> list[dict]:
    lk = four_bar(*REF)
    ref = peaks(simulate(lk, 100_000))
    rows = []
    for n in (36, 72, 180, 360, 720, 3600, 20_000):
        h = simulate(lk, n)
        raw, fine = peaks(h, refine=False), peaks(h)
        row = {"samples": n}
        row["raw_rel_err"] = max(abs(_val(raw[k]) / _val(ref[k]) - 1) for k in ITEMS)
        row["refined_rel_err"] = max(abs(_val(fine[k]) / _val(ref[k]) - 1) for k in ITEMS)
        row["refined_angle_err_deg"] = max(abs(fine[k]["crank_deg"] - ref[k]["crank_deg"]) for k in ITEMS)
        row["simulate_peaks_ms"] = statistics.median(r["wall_ms"] for r in _samples(lambda: peaks(simulate(lk, n)), 5))
        rows.append(row)
    return rows


def model_comparison() -> dict:
    lk = four_bar(*REF)
    rb = peaks(simulate(lk, 360))
    og = peaks(simulate(lk, 360, model="original"))
    prog = original_program(*REF)
    comp = {}
    for k in ITEMS:
        comp[k] = {"study_2013": CAL[k], "original_model": _val(og[k]), "rigid_body": _val(rb[k]),
                   "rigid_vs_original_pct": 100 * (_val(rb[k]) / _val(og[k]) - 1),
                   "original_vs_study_rel": prog["torque_Nm" if k == "torque" else k] / CAL[k] - 1,
                   "crank_deg_original": og[k]["crank_deg"], "crank_deg_rigid": rb[k]["crank_deg"]}
    return comp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--no-timing", action="store_true",
                    help="skip the 3600-angle timing table (results/benchmarks/dynamics.md)")
    args = ap.parse_args()
    if not args.no_timing:
        write_timings(args.repeats)
    accuracy_tables()


def write_timings(repeats: int) -> None:
    """results/benchmarks/dynamics.json: wall and CPU times of the cycle solves, raw."""
    samples = timings(repeats)
    samples["benchmark process"] = [{"peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}]
    med = {k: v["wall_ms"]["median"] for k, v in summarise(samples).items() if "wall_ms" in v}
    derived = {"general / closed form, 5000 angles": med["general solver, 5000 angles"]
               / med["closed form, 5000 angles (simulate)"]}
    print(f"wrote {write_record('dynamics', samples, derived, {'repeats': repeats, 'four-bar mm': REF})}")


def accuracy_tables() -> None:
    """results/dynamics/: sampling error table and the rigid-body vs original comparison."""
    rows = sampling_table()
    ddir = ROOT / "results" / "dynamics"
    ddir.mkdir(parents=True, exist_ok=True)
    md = ["# Sample count vs peak error (rig four-bar, rigid-body model)", "",
          "Reference: 100 000 samples with refinement.  Error = worst over the four pin reactions "
          "and the torque.  'raw' is the plain sampled maximum; 'refined' is rigfem's peak "
          "(each sampled maximum refined on the solver itself, vectorised bracket zoom to 1e-7 deg).", "",
          "Time: simulate + refined peaks, wall median of 5 after a warm-up (shared machine).", "",
          "| samples | raw max rel. error | refined max rel. error | refined crank-angle error (deg) "
          "| time ms |",
          "|---:|---:|---:|---:|---:|"]
    md += [f"| {r['samples']} | {r['raw_rel_err']:.2e} | {r['refined_rel_err']:.2e} | "
           f"{r['refined_angle_err_deg']:.2e} | {r['simulate_peaks_ms']:.1f} |" for r in rows]
    (ddir / "sampling.md").write_text("\n".join(md) + "\n")
    (ddir / "sampling.json").write_text(json.dumps(rows, indent=1))
    print("\n".join(md))

    comp = model_comparison()
    md = ["# Rigid-body vs original (2013) mass model, calibration case", "",
          "b2=540 b3=840 b4=780 d=1020 mm, 1 Hz, rig masses.  'original' reproduces the 2013 "
          "program (geometry/RIG.md §3); 'rigid-body' uses uniform rails over their full guide length, "
          "particles at the joints and moments about each body's centre of mass.", "",
          "| peak | 2013 study | original model | rel. to study | rigid-body | rigid vs original |",
          "|---|---:|---:|---:|---:|---:|"]
    for k, v in comp.items():
        unit = "N·m" if k == "torque" else "N"
        md.append(f"| {k} ({unit}) | {v['study_2013']:.4f} | {v['original_model']:.4f} | "
                  f"{v['original_vs_study_rel']:+.1e} | {v['rigid_body']:.4f} | {v['rigid_vs_original_pct']:+.1f} % |")
    cat = RIG_MASSES
    m3 = m4 = cat.study_rail_kg_m * 1.0  # kg: the 1000 mm coupler and rocker rails, 2013 masses
    r4 = cat.rail_kg_m * 1.0  # kg: the same rails with the catalogue's mass
    c4 = 0.5 - cat.rail_behind_mm / 1000  # rocker rail's centre from O4, m
    md += ["", f"Why they differ.  Mass: the rigid-body model uses the catalogue's {cat.rail_kg_m:g} kg/m "
           f"(the meshed rail's profile weighs the same), the 2013 program the study's "
           f"{cat.study_rail_kg_m:g} kg/m; and each rail reaches {cat.rail_behind_mm:g} mm behind its "
           "pivot joint (the pivot coupling's screws sit in its 1st and 3rd holes), where the 2013 "
           "program puts the pivot at the guide's end.  geometry/RIG.md §3 quirks: the 2013 inertias use the "
           "joint distances, not the 1000 mm guides — rocker about O4 "
           f"m4 b4²/3 = {m4 * 0.78**2 / 3:.3f} kg·m² vs the guide's m L4²/12 + m c² = "
           f"{r4 / 12 + r4 * c4**2:.3f} kg·m² (c = {c4 * 1000:g} mm), coupler "
           f"m3 b3²/12 = {m3 * 0.84**2 / 12:.3f} vs m L3²/12 = {r4 / 12:.3f} kg·m² (about different points, "
           "too: the guide's centre is not the combined centre of mass); each guide mass "
           "gets the acceleration of the combined centre of mass instead of its own; "
           "bar 3's moment arms are taken about L3/2.  The rigid-body model is the consistent one "
           "(every body checked against Newton–Euler in tests/test_linkage.py); its peaks differ by "
           f"{min(v['rigid_vs_original_pct'] for v in comp.values()):+.1f} to "
           f"{max(v['rigid_vs_original_pct'] for v in comp.values()):+.1f} % here."]
    (ddir / "rigid_vs_original.md").write_text("\n".join(md) + "\n")
    (ddir / "rigid_vs_original.json").write_text(json.dumps(comp, indent=1))
    print("\n".join(md))


if __name__ == "__main__":
    main()
