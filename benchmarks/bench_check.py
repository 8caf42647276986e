"""Wall and CPU time of ``rigfem check`` on the reference scene, per fidelity preset.

Run: ``python benchmarks/bench_check.py [--repeats 3] [--fidelity standard draft]``
-> results/benchmarks/check.{md,json}.  Meshes come from the cache after the first run of a
preset (a repeated check does not remesh), so the first run is reported apart from the
median of the others.  Outputs (VTU, PVD frames, pictures) are written as the README's main
command writes them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

from rigfem.check import REFERENCE_SCENE, run_check

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--fidelity", nargs="+", default=["standard", "draft"])
    ap.add_argument("--scene", default=REFERENCE_SCENE)
    args = ap.parse_args(argv)
    rows = []
    for fid in args.fidelity:
        runs = []
        for _ in range(args.repeats + 1):
            with tempfile.TemporaryDirectory() as tmp:
                load = os.getloadavg()[0]
                t0, c0 = time.perf_counter(), _cpu()
                r = run_check(args.scene, out=Path(tmp) / "o", overrides={"fidelity": fid}, quiet=True)
                runs.append({"wall_s": time.perf_counter() - t0, "cpu_s": _cpu() - c0, "load_avg": load,
                             "verdict": r["verdict"]})
        rest = runs[1:]
        rows.append({"fidelity": fid, "first": runs[0],
                     "median_wall_s": statistics.median(x["wall_s"] for x in rest),
                     "median_cpu_s": statistics.median(x["cpu_s"] for x in rest),
                     "load_avg": [round(x["load_avg"], 2) for x in runs], "runs": runs})
        print(f"{fid}: median wall {rows[-1]['median_wall_s']:.1f} s, CPU {rows[-1]['median_cpu_s']:.1f} s "
              f"(first run {runs[0]['wall_s']:.1f} s)")
    cmd = "python benchmarks/bench_check.py " + " ".join(argv if argv is not None else sys.argv[1:])
    lines = [f"# `rigfem check {args.scene}`: wall and CPU time per fidelity", "",
             f"Command: `{cmd.strip()}`; {os.cpu_count()} cores; median of {args.repeats} runs after a "
             f"first run (the first may mesh; later runs take meshes from the cache).  CPU = user + system "
             f"of the process (pardiso uses both cores, so CPU can exceed wall).", "",
             "| fidelity | median wall s | median CPU s | first run wall s | load average at each start |",
             "|---|---:|---:|---:|---|"]
    lines += [f"| {r['fidelity']} | {r['median_wall_s']:.1f} | {r['median_cpu_s']:.1f} | "
              f"{r['first']['wall_s']:.1f} | {', '.join(map(str, r['load_avg']))} |" for r in rows]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "check.md").write_text("\n".join(lines) + "\n")
    (OUT / "check.json").write_text(json.dumps({"command": cmd.strip(), "rows": rows}, indent=2) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
