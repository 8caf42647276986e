"""Sweep timing: unit solutions once, then configurations on a local Dask cluster of 1 and 2 workers.

    python benchmarks/bench_sweep.py [--every 40] [--repeats 1] [--full-seconds S]

Times a fixed, evenly spread subset of the four-bar configurations that assemble (every
``--every``-th, so short and long linkages are both in it) with 1 and 2 worker processes
(median of ``--repeats``, fresh work folder each time, scatter of the unit solutions included),
reports the scaling efficiency and the projected full-sweep time; ``--full-seconds`` records a
measured full sweep (e.g. the wall time printed in results/sweep/worst_four-bar.md).
Writes results/benchmarks/sweep.md and sweep.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from rigfem.linkage import fourbar_closes
from rigfem.studies import SweepParams, build_bases, enumerate_configs, run_sweep

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=40)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--full-seconds", type=float, default=None)
    a = ap.parse_args()
    p = SweepParams()
    grid = np.linspace(0.0, 360.0, 3601)
    allc = enumerate_configs(p)
    t0 = time.perf_counter()
    closes = [c for c in allc if fourbar_closes(c["b2"], c["b3"], c["b4"], c["d"], grid).all()]
    t_enum = time.perf_counter() - t0
    subset = closes[::a.every]
    t0 = time.perf_counter()
    bases = build_bases(p)
    t_bases = time.perf_counter() - t0
    load = os.getloadavg()[0]
    runs: dict[int, list[float]] = {1: [], 2: []}
    fixed: dict[int, list[float]] = {1: [], 2: []}  # cluster start, mapped unit fields, one chunk
    for _ in range(a.repeats):
        for w in (1, 2):
            for configs, out in ((subset, runs), (subset[:8], fixed)):
                with tempfile.TemporaryDirectory() as tmp:
                    t0 = time.perf_counter()
                    run_sweep(p, tmp, configs=configs, chunk_size=8, workers=w, distributed=True, bases=bases,
                              progress=False)
                    out[w].append(time.perf_counter() - t0)
    med = {w: statistics.median(v) for w, v in runs.items()}
    med_fixed = {w: statistics.median(v) for w, v in fixed.items()}
    eff = med[1] / (2 * med[2])
    # the steady state: per-configuration throughput once the cluster runs (fixed cost subtracted)
    eff_steady = (med[1] - med_fixed[1]) / (2 * (med[2] - med_fixed[2]))
    per_cfg = {w: med[w] / len(subset) for w in med}
    projected = {w: t_bases + per_cfg[w] * len(closes) + t_enum for w in med}
    res = {"subset_configurations": len(subset), "assembling_configurations": len(closes),
           "mountable_configurations": len(allc), "unit_solutions_s": t_bases, "enumeration_s": t_enum,
           "wall_s": runs, "median_s": med, "per_configuration_s": per_cfg, "scaling_efficiency_2": eff_steady,
           "scaling_efficiency_2_with_startup": eff, "fixed_cost_s": med_fixed,
           "projected_full_sweep_s": projected, "measured_full_sweep_s": a.full_seconds,
           "fidelity": p.fidelity, "samples": p.samples, "load_average_at_start": load,
           "cpus": os.cpu_count(), "python": platform.python_version(),
           "peak_rss_mb_main": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "sweep.json").write_text(json.dumps(res, indent=1))
    cmd = f"python benchmarks/bench_sweep.py --every {a.every} --repeats {a.repeats}"
    cmd += f" --full-seconds {a.full_seconds:.0f}" if a.full_seconds else ""
    md = [f"# Sweep timing (four-bar, {p.fidelity} fidelity, {p.samples} crank angles, rigid-body, 1 Hz)", "",
          f"Command: `{cmd}` (OMP/OpenBLAS threads = 1).", "",
          f"- mountable four-bar configurations: {len(allc)}; assembling over a full turn: {len(closes)} "
          f"(enumeration + assembly test {t_enum:.1f} s)",
          f"- unit solutions (6 part geometry/support sets, one factorisation each, or read from the "
          f"disk cache when it holds them): {t_bases:.0f} s",
          f"- timed subset: every {a.every}th assembling configuration = {len(subset)} configurations, "
          f"chunks of 8, LocalCluster processes, unit fields memory-mapped by the workers", "",
          "| workers | wall median (s) | per configuration (s) | projected full sweep (min) |",
          "|---:|---:|---:|---:|"]
    md += [f"| {w} | {med[w]:.1f} | {per_cfg[w]:.3f} | {projected[w] / 60:.1f} |" for w in (1, 2)]
    md += ["", f"Scaling efficiency with 2 workers, steady state: {100 * eff_steady:.0f} % "
           f"((t1 − f1) / (2 (t2 − f2)), f = the same run on one chunk of 8 configurations: cluster start, "
           f"unit fields mapped, one chunk: f1 = {med_fixed[1]:.1f} s, f2 = {med_fixed[2]:.1f} s); "
           f"with the start-up included: {100 * eff:.0f} % (t1 / (2 t2)).",
           f"Peak RSS of the main process (it holds the unit fields): {res['peak_rss_mb_main']:.0f} MB; the workers "
           f"map the same fields from one file, shared in the page cache (getrusage cannot tell a worker's own "
           f"peak: its fork counts the parent's pages).",
           f"Measured full four-bar sweep: {a.full_seconds / 60:.1f} min." if a.full_seconds else "",
           "", f"Environment: Python {platform.python_version()}, {os.cpu_count()} CPUs shared with other "
           f"jobs, load average {load:.1f} at start: wall times include waiting for a core."]
    (OUT / "sweep.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
