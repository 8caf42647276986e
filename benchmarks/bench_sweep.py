"""The whole four-bar sweep, end to end: ``rigfem sweep --four-bar`` with cold and warm caches, 1 and 2 workers.

    python benchmarks/bench_sweep.py [--workers 1 2] [--repeats 1]

Each run is a separate ``rigfem sweep --four-bar --workers W --quiet`` process writing to a
fresh output folder, so its wall time includes start-up, enumeration, the unit solutions, the
local Dask cluster and the report; its peak memory is the peak RSS of its process tree (the
workers included: benchmarks/record.py).  *Cold*: empty rigfem and numba caches (meshes, unit
solutions and compiled kernels built).  *Warm*: the same caches, filled by the cold run.
Writes results/benchmarks/sweep.json (``python benchmarks/publish.py`` writes sweep.md).
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
from pathlib import Path

from record import cold_env, summarise, timed_process, write_record


def _sweep(workers: int, env: dict) -> dict:
    """One full sweep process; its sample with the counts it printed."""
    with tempfile.TemporaryDirectory() as out:
        r = timed_process([sys.executable, "-m", "rigfem", "sweep", "--four-bar", "--workers", str(workers),
                           "--quiet", "--out", str(Path(out) / "sweep")], env=env)
    if r["exit"] != 0:
        raise SystemExit(f"rigfem sweep failed ({r['exit']}): {r['stderr_tail']}")
    m = re.search(r"(\d+) configurations, (\d+) computed, (\d+) fail", r["stdout_tail"])
    return r | {"workers": workers, "configurations": int(m[1]), "computed": int(m[2]), "fail": int(m[3])}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=1)
    a = ap.parse_args(argv)
    samples: dict[str, list] = {}
    for w in a.workers:
        for _ in range(a.repeats):
            with tempfile.TemporaryDirectory() as tmp:
                env = cold_env(tmp, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
                samples.setdefault(f"cold, {w} workers", []).append(_sweep(w, env))
                samples.setdefault(f"warm, {w} workers", []).append(_sweep(w, env))
                print(f"{w} workers: cold {samples[f'cold, {w} workers'][-1]['wall_s']:.0f} s, "
                      f"warm {samples[f'warm, {w} workers'][-1]['wall_s']:.0f} s", flush=True)
    s = summarise(samples)
    med = {k: v["wall_s"]["median"] for k, v in s.items()}
    derived = {}
    if {1, 2} <= set(a.workers):
        for c in ("cold", "warm"):
            derived[f"{c} efficiency 1 -> 2 workers"] = med[f"{c}, 1 workers"] / (2 * med[f"{c}, 2 workers"])
        # what a cold cache adds once: meshes, unit solutions, compiled kernels (one worker, same sweep)
        derived["cold - warm, 1 worker (s)"] = med["cold, 1 workers"] - med["warm, 1 workers"]
    path = write_record("sweep", samples, derived, {"workers": a.workers, "repeats": a.repeats,
                                                    "threads per process": 1})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
