"""What Dask's MALLOC_TRIM_THRESHOLD_ costs the sweep's superposition.

    python benchmarks/bench_malloc_trim.py [--repeats 3] [--every 20]

Dask's nannies start their workers with ``MALLOC_TRIM_THRESHOLD_=65536``; setting it turns off
glibc's adaptive mmap threshold, so every large temporary is mapped and unmapped afresh.  This
times one sweep chunk (every ``--every``-th configuration whose crank turns, draft, unit
solutions from the disk cache) in fresh single-threaded processes with and without the
variable: wall, user and system time and minor page faults of the chunk alone (median of
``--repeats`` processes each).  ``rigfem.sweep.run`` starts its local workers without it.
Writes results/benchmarks/malloc_trim.json (``python benchmarks/publish.py`` writes the .md).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

from record import summarise, write_record

CHILD = """
import json, resource, sys, time
import numpy as np
from rigfem.linkage import fourbar_closes
from rigfem.sweep import SweepParams, build_bases, enumerate_configs, run_chunk
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
    med = {label: v["wall_s"]["median"] for label, v in summarise(runs).items()}
    derived = {"wall with / without - 1": med["MALLOC_TRIM_THRESHOLD_=65536"] / med["without"] - 1}
    params = {"repeats": a.repeats, "every": a.every, "threads": 1}
    print(f"wrote {write_record('malloc_trim', runs, derived, params)}")


if __name__ == "__main__":
    main()
