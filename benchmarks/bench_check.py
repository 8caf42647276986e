"""Wall time and peak memory of ``rigfem check`` on the reference scene: cold and warm cache.

Run: ``python benchmarks/bench_check.py [--repeats 3] [--fidelity standard draft]``
-> results/benchmarks/check.json (then ``python benchmarks/publish.py`` writes check.md).
Each run is a separate ``rigfem check`` process, so its wall time includes start-up; its peak
memory is the peak RSS of its own process tree (benchmarks/record.py).  *Cold*: an empty rigfem
cache AND an empty numba cache (meshing, compiling, assembly, factorisation and solves).
*Warm*: the meshes, unit solutions and compiled kernels come from the caches a first run
filled (what a user sees from the second check of a scene on).  Outputs (VTU, PVD frames,
pictures) are written as the README's main command writes them.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from record import cold_env, summarise, timed_process, write_record


def _run(scene: str, fidelity: str, env: dict) -> dict:
    """One ``rigfem check`` process (benchmarks/record.timed_process); exits 0 or 1 only."""
    with tempfile.TemporaryDirectory() as tmp:
        r = timed_process([sys.executable, "-m", "rigfem", "check", scene, "--fidelity", fidelity,
                           "--out", str(Path(tmp) / "o")], env=env)
    if r["exit"] not in (0, 1):
        raise SystemExit(f"rigfem check failed ({r['exit']}): {r['stderr_tail']}")
    return r


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--fidelity", nargs="+", default=["standard", "draft"])
    ap.add_argument("--scene", default="final-cm")
    args = ap.parse_args(argv)
    samples, derived = {}, {}
    for fid in args.fidelity:
        cold = []
        for _ in range(args.repeats):
            with tempfile.TemporaryDirectory() as tmp:
                cold.append(_run(args.scene, fid, cold_env(tmp)))
        with tempfile.TemporaryDirectory() as tmp:
            env = cold_env(tmp)
            _run(args.scene, fid, env)  # fills both caches
            warm = [_run(args.scene, fid, env) for _ in range(args.repeats)]
        samples[f"{fid} cold"], samples[f"{fid} warm"] = cold, warm
        med = {k: v["wall_s"]["median"] for k, v in zip(("cold", "warm"), summarise({0: cold, 1: warm}).values())}
        derived[f"{fid} warm / cold"] = med["warm"] / med["cold"]
        print(f"{fid}: cold median {med['cold']:.1f} s, warm median {med['warm']:.1f} s")
    path = write_record("check", samples, derived, {"scene": args.scene, "fidelity": args.fidelity,
                                                    "repeats": args.repeats})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
