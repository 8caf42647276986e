"""Closed-form four-bar kinematics over a full turn at 5000 crank angles (target < 5 ms).

Run: ``python benchmarks/bench_kinematics.py``; writes results/benchmarks/kinematics.json
(``python benchmarks/publish.py`` writes kinematics.md).
In-process timing (time.perf_counter), median of 15 runs after one warm-up.
"""

import time

from record import summarise, write_record

from rigfem.linkage import crank_angles, fourbar_motion, fourbar_turn

RUNS, N, TARGET_MS = 15, 5000, 5.0
CASE = (540.0, 840.0, 780.0, 1020.0)       # the rig's reference four-bar (geometry/RIG.md §3)


def main() -> None:
    deg = crank_angles(N)
    fourbar_motion(*CASE, deg, coupler_point=(300.0, 30.0))
    samples = {}
    for label, fn in (("motion (angles, rates, 4 points + coupler point, mu, MA)",
                       lambda: fourbar_motion(*CASE, deg, coupler_point=(300.0, 30.0))),
                      ("turn analysis (Grashof, toggles, swing, time ratio)", lambda: fourbar_turn(*CASE))):
        t = []
        for _ in range(RUNS):
            t0 = time.perf_counter()
            fn()
            t.append({"ms": (time.perf_counter() - t0) * 1000})
        samples[label] = t
    total = sum(v["ms"]["median"] for v in summarise(samples).values())
    params = {"four-bar mm": CASE, "angles": N, "runs": RUNS, "target_ms": TARGET_MS}
    print(f"total {total:.3f} ms; wrote {write_record('kinematics', samples, {'total ms': total}, params)}")


if __name__ == "__main__":
    main()
