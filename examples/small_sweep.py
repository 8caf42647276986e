"""A small sweep: rig rules and peak pin reactions of every four-bar with a 480 mm crank
and a 1020 mm ground, coupler and rocker on the 60 mm hole grid.

``evaluate(cfg, params, None)`` is one row of ``rigfem sweep`` without the stress check
(rules and dynamics only), so this runs in seconds; ``rigfem sweep`` adds the stresses of
every part by superposing unit solutions.

Run: python examples/small_sweep.py

Prints (tests/test_examples.py compares; ``...`` stands for what differs from run to run)::

    196 configurations: 6 run a full turn, 3 comply with every rig rule
    lowest crank-pin reactions among the compliant ones (N, deg):
       b3    b4   peak_A_N  mu_min_deg
    780.0 840.0 400.532091   38.719297
    840.0 840.0 415.984044   37.498682
    840.0 780.0 420.063048   38.719297
"""

import pandas as pd

from rigfem.sweep import SweepParams, enumerate_configs, evaluate

p = SweepParams(linkage_type="four-bar", samples=90)
configs = [c for c in enumerate_configs(p) if c["b2"] == 480.0 and c["d"] == 1020.0]
table = pd.DataFrame([evaluate(c, p, None) for c in configs])
ok = table[table["status"] == "ok"]
print(f"{len(table)} configurations: {len(ok)} run a full turn, "
      f"{int(ok['rules_ok'].sum())} comply with every rig rule")
best = ok[ok["rules_ok"]].nsmallest(3, "peak_A_N")[["b3", "b4", "peak_A_N", "mu_min_deg"]]
print("lowest crank-pin reactions among the compliant ones (N, deg):")
print(best.to_string(index=False))
