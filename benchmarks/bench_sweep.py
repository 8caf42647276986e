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
    ap.add_argument("--workers", type=int, nargs="+", default=[2, 1],
                    help="worker counts, in order: each gets a cold run then a warm run")
    ap.add_argument("--repeats", type=int, default=1)
    a = ap.parse_args(argv)
    samples: dict[str, list] = {}
    for _ in range(a.repeats):
        for w in a.workers:
            with tempfile.TemporaryDirectory() as tmp:
                env = cold_env(tmp, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
                for state in ("cold", "warm"):
                    r = _sweep(w, env)
                    samples.setdefault(f"{state}, {w} workers", []).append(r)
                    print(f"{state}, {w} workers: {r['wall_s']:.0f} s", flush=True)
                    _write(samples, a)  # after every run: an interrupted benchmark keeps what it measured


def _write(samples: dict[str, list], a: argparse.Namespace) -> None:
    """The record with the figures the runs so far give (efficiency needs 1 and 2 workers)."""
    med = {k: v["wall_s"]["median"] for k, v in summarise(samples).items()}
    derived = {}
    for c in ("cold", "warm"):
        if f"{c}, 1 workers" in med and f"{c}, 2 workers" in med:
            derived[f"{c} efficiency 1 -> 2 workers"] = med[f"{c}, 1 workers"] / (2 * med[f"{c}, 2 workers"])
    for w in (1, 2):  # what a cold cache adds once: meshes, unit solutions, compiled kernels
        if f"cold, {w} workers" in med and f"warm, {w} workers" in med:
            derived[f"cold - warm, {w} workers (s)"] = med[f"cold, {w} workers"] - med[f"warm, {w} workers"]
    write_record("sweep", samples, derived, {"workers": a.workers, "repeats": a.repeats, "threads per process": 1})


if __name__ == "__main__":
    main()
