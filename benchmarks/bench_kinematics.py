"""Closed-form four-bar kinematics over a full turn at 5000 crank angles (target < 5 ms).

Run: ``python benchmarks/bench_kinematics.py``; writes results/benchmarks/kinematics.md.
In-process timing (time.perf_counter), median of 15 runs after one warm-up.
"""

import platform
import statistics
import time
from pathlib import Path

import numpy as np

from rigfem.linkage import crank_angles, fourbar_motion, fourbar_turn

RUNS, N, TARGET_MS = 15, 5000, 5.0
CASE = (540.0, 840.0, 780.0, 1020.0)       # the rig's reference four-bar (geometry/RIG.md §3)


def main() -> None:
    deg = crank_angles(N)
    fourbar_motion(*CASE, deg, coupler_point=(300.0, 30.0))
    times = {}
    for label, fn in (("motion (angles, rates, 4 points + coupler point, mu, MA)",
                       lambda: fourbar_motion(*CASE, deg, coupler_point=(300.0, 30.0))),
                      ("turn analysis (Grashof, toggles, swing, time ratio)", lambda: fourbar_turn(*CASE))):
        t = []
        for _ in range(RUNS):
            t0 = time.perf_counter()
            fn()
            t.append((time.perf_counter() - t0) * 1000)
        times[label] = statistics.median(t)
    total = sum(times.values())
    lines = ["# Closed-form kinematics benchmark", "",
             f"Four-bar {'/'.join(f'{v:g}' for v in CASE)} mm, {N} crank angles over a full turn; "
             f"median of {RUNS} runs (time.perf_counter, in process) on {platform.processor() or platform.machine()}, "
             f"Python {platform.python_version()}, numpy {np.__version__}.", "",
             "| step | median (ms) |", "|---|---|"]
    lines += [f"| {k} | {v:.3f} |" for k, v in times.items()]
    lines += [f"| **total** | **{total:.3f}** (target < {TARGET_MS:g}) |", "",
              "Command: `python benchmarks/bench_kinematics.py`"]
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(__file__).resolve().parents[1] / "results" / "benchmarks" / "kinematics.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)


if __name__ == "__main__":
    main()
