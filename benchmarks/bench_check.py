"""Wall time and peak memory of ``rigfem check`` on the reference scene: cold and warm cache.

Run: ``python benchmarks/bench_check.py [--repeats 3] [--fidelity standard draft]``
-> results/benchmarks/check.{md,json}.  Each run is a separate ``rigfem check`` process, so
its wall time includes start-up and its peak RSS is its own.  *Cold*: an empty cache
(``RIGFEM_CACHE`` a new folder): meshing, assembly, factorisation and solves.  *Warm*: the
meshes and unit solutions come from the cache a first run filled (what a user sees from the
second check of a scene on).  Outputs (VTU, PVD frames, pictures) are written as the
README's main command writes them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def _run(scene: str, fidelity: str, cache: str) -> dict:
    """One ``rigfem check`` process: wall s, its peak RSS (MiB), load average at start, exit code."""
    with tempfile.TemporaryDirectory() as tmp:
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "rigfem", "check", scene, "--fidelity", fidelity,
                            "--out", str(Path(tmp) / "o")], env={**os.environ, "RIGFEM_CACHE": cache},
                           capture_output=True, text=True)
        wall = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise SystemExit(f"rigfem check failed ({p.returncode}): {p.stderr.strip()[-500:]}")
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024  # largest child so far
    return {"wall_s": wall, "peak_rss_mib": rss, "load_avg": load, "exit": p.returncode}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--fidelity", nargs="+", default=["standard", "draft"])
    ap.add_argument("--scene", default="final-cm")
    args = ap.parse_args(argv)
    rows = []
    for fid in args.fidelity:
        cold, warm = [], []
        for _ in range(args.repeats):
            with tempfile.TemporaryDirectory() as cache:
                cold.append(_run(args.scene, fid, cache))
        with tempfile.TemporaryDirectory() as cache:
            _run(args.scene, fid, cache)  # fills the cache
            warm = [_run(args.scene, fid, cache) for _ in range(args.repeats)]
        row = {"fidelity": fid, "cold": cold, "warm": warm}
        for name, runs in (("cold", cold), ("warm", warm)):
            row[f"{name}_median_wall_s"] = statistics.median(r["wall_s"] for r in runs)
            row[f"{name}_min_wall_s"] = min(r["wall_s"] for r in runs)
            row[f"{name}_max_wall_s"] = max(r["wall_s"] for r in runs)
        rows.append(row)
        print(f"{fid}: cold median {row['cold_median_wall_s']:.1f} s, warm median {row['warm_median_wall_s']:.1f} s")
    cmd = "python benchmarks/bench_check.py " + " ".join(argv if argv is not None else sys.argv[1:])
    lines = [f"# `rigfem check {args.scene}`: wall time, cold and warm cache", "",
             f"Command: `{cmd.strip()}`; {os.cpu_count()} cores; each run a separate process; median "
             f"(min–max) of {args.repeats} runs.  Cold: empty cache (mesh, assemble, factorise, solve). "
             f"Warm: meshes and unit solutions from the cache.  Peak RSS: the largest process so far "
             f"(getrusage of the children).", "",
             "| fidelity | cold wall s | warm wall s | warm / cold | peak RSS MiB | load average at starts |",
             "|---|---|---|---:|---:|---|"]
    for r in rows:
        loads = ", ".join(f"{x['load_avg']:.1f}" for x in r["cold"] + r["warm"])
        rss = max(x["peak_rss_mib"] for x in r["cold"] + r["warm"])
        lines.append(f"| {r['fidelity']} | {r['cold_median_wall_s']:.1f} ({r['cold_min_wall_s']:.1f}–"
                     f"{r['cold_max_wall_s']:.1f}) | {r['warm_median_wall_s']:.1f} ({r['warm_min_wall_s']:.1f}–"
                     f"{r['warm_max_wall_s']:.1f}) | {r['warm_median_wall_s'] / r['cold_median_wall_s']:.2f} | "
                     f"{rss:.0f} | {loads} |")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "check.md").write_text("\n".join(lines) + "\n")
    (OUT / "check.json").write_text(json.dumps({"command": cmd.strip(), "rows": rows}, indent=1) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
