"""What Dask's MALLOC_TRIM_THRESHOLD_ costs the sweep's superposition.

    python benchmarks/bench_malloc_trim.py [--repeats 3] [--every 20]

Dask's nannies start their workers with ``MALLOC_TRIM_THRESHOLD_=65536``; setting it turns off
glibc's adaptive mmap threshold, so every large temporary is mapped and unmapped afresh.  This
times one sweep chunk (every ``--every``-th configuration whose crank turns, draft, unit
solutions from the disk cache) in fresh single-threaded processes with and without the
variable: wall, user and system time and minor page faults of the chunk alone (median of
``--repeats`` processes each).  ``rigfem.studies.sweep`` starts its local workers without it.
Writes results/benchmarks/malloc_trim.{md,json}.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"

CHILD = """
import json, resource, sys, time
import numpy as np
from rigfem.linkage import fourbar_closes
from rigfem.studies import SweepParams, build_bases, enumerate_configs, run_chunk
p = SweepParams()
grid = np.linspace(0.0, 360.0, 3601)
cfgs = [c for c in enumerate_configs(p) if fourbar_closes(c["b2"], c["b3"], c["b4"], c["d"], grid).all()]
cfgs = cfgs[::int(sys.argv[1])]
bases = build_bases(p)
r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
run_chunk(cfgs, p, bases)
r1, t1 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
print(json.dumps({"configurations": len(cfgs), "wall_s": t1 - t0, "user_s": r1.ru_utime - r0.ru_utime,
                  "sys_s": r1.ru_stime - r0.ru_stime, "minor_faults": r1.ru_minflt - r0.ru_minflt}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--every", type=int, default=20)
    a = ap.parse_args()
    base = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
    base.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    runs: dict[str, list[dict]] = {"without": [], "MALLOC_TRIM_THRESHOLD_=65536": []}
    for _ in range(a.repeats):
        for label in runs:
            env = dict(base, **({"MALLOC_TRIM_THRESHOLD_": "65536"} if label != "without" else {}))
            out = subprocess.run([sys.executable, "-c", CHILD, str(a.every)], env=env, check=True,
                                 capture_output=True, text=True).stdout
            runs[label].append(json.loads(out.strip().splitlines()[-1]))
    med = {label: {k: statistics.median(r[k] for r in rs) for k in rs[0]} for label, rs in runs.items()}
    (off, on) = med.values()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "malloc_trim.json").write_text(json.dumps({"runs": runs, "median": med, "load_avg": os.getloadavg()[0]},
                                                     indent=1))
    md = ["# Dask's MALLOC_TRIM_THRESHOLD_ and the sweep's superposition", "",
          f"Command: `python benchmarks/bench_malloc_trim.py --repeats {a.repeats} --every {a.every}`; one sweep "
          f"chunk of {int(off['configurations'])} configurations, draft, single-threaded fresh processes, "
          f"median of {a.repeats} each.", "",
          "| environment | wall s | user s | system s | minor page faults |", "|---|---:|---:|---:|---:|"]
    md += [f"| {label} | {m['wall_s']:.1f} | {m['user_s']:.1f} | {m['sys_s']:.1f} | {m['minor_faults']:,.0f} |"
           for label, m in med.items()]
    md += ["", f"With the variable the chunk takes {100 * (on['wall_s'] / off['wall_s'] - 1):+.0f} % wall time; "
           "local sweep workers are started without it (`rigfem.studies.sweep._run_dask`).",
           f"Load average {os.getloadavg()[0]:.1f} at the end (shared 2-core machine)."]
    (OUT / "malloc_trim.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
