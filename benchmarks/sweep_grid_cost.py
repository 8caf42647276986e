"""Cost of a finer rig grid: four-bar configurations at a hole pitch of 60 mm (the rig) and 30 mm,
and the wall time of their sweep projected on N Dask workers from a short measured draft sweep.

    python benchmarks/sweep_grid_cost.py [--every 400] [--workers 1 2 16 64]

Counting uses the rules of ``rigfem.studies.enumerate_configs`` with the rail's pitch overridden
(each length a whole number of pitches from one pitch up, its coupling's two screws on the
rail's holes, the ground from 660 mm on the 2500 mm ground rail); the 60 mm count is checked
against ``enumerate_configs`` itself.  The configurations that get an FE check are those whose
crank turns fully without a dead point: d + b2 < b3 + b4 and |d − b2| > |b3 − b4| (the loop
closes at every crank angle; equality is a dead point, a "toggle" row).  The rig's 60 mm
default is not changed.

Measured here: the unit-solution build (once per sweep: a 30 mm rail layout has more holes, so
this is a lower bound for it) and the per-configuration time of a serial draft sweep over an
evenly spread subset of the checked configurations.  Projection: T(N) = T_bases +
n_FE · t_cfg / (N · efficiency(N)) (+ the configurations without FE, rules and dynamics only);
efficiency is an assumption (the measured 1 → 2 local-worker figure in
results/benchmarks/sweep.md, kept for all N: a cluster's workers do not share 2 cores); the
unit-solution time is the larger of this run's (the on-disk cache may make it warm) and the
cold build recorded in results/benchmarks/sweep.json.
Writes results/benchmarks/sweep_grid_cost.{md,json}.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from rigfem.rig import MIN_GROUND_MM
from rigfem.rig.layout import RailLayout
from rigfem.rig.parts import load_part, rail_hole_x
from rigfem.settings import PLATE, RAIL
from rigfem.studies import SweepParams, build_bases, enumerate_configs, run_sweep

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def grid_lengths(rail_mm: float, pitch: float) -> list[float]:
    """Joint distances on a ``pitch`` grid whose coupling screws land on a ``pitch`` rail's holes."""
    r = load_part(RAIL, {"length": rail_mm, "pitch": pitch})
    lay = RailLayout(rail_hole_x(r), pitch, load_part(PLATE)["screw_spacing"])
    out, b = [], pitch
    while _fits(lay, b):
        out.append(b)
        b += pitch
    return out


def _fits(lay: RailLayout, b: float) -> bool:
    from rigfem.errors import InputError

    try:
        lay.coupling(b, "rail")
    except InputError:
        return False
    return True


def count(pitch: float, p: SweepParams = SweepParams()) -> dict:
    """Four-bar configurations on a ``pitch`` grid: all mountable ones and those checked by FE."""
    b2s, b3s, b4s = (np.array(grid_lengths(r, pitch)) for r in p.rails)
    ds = np.array([d for d in grid_lengths(p.ground_mm, pitch) if d >= MIN_GROUND_MM])
    b2, b3, b4, d = np.meshgrid(b2s, b3s, b4s, ds, indexing="ij")
    full_turn = (d + b2 < b3 + b4) & (np.abs(d - b2) > np.abs(b3 - b4))
    return {"pitch_mm": pitch, "lengths": [len(b2s), len(b3s), len(b4s), len(ds)], "mountable": int(b2.size),
            "fe_checked": int(full_turn.sum())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=400, help="time every n-th FE-checked 60 mm configuration")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2, 16, 64])
    ap.add_argument("--efficiency", type=float, default=None,
                    help="parallel efficiency assumed for N > 1 (default: results/benchmarks/sweep.json's 1 -> 2)")
    ap.add_argument("--bases-seconds", type=float, default=None,
                    help="cold unit-solution build time to assume (s; default: the larger of this run's and "
                         "results/benchmarks/sweep.json's, which a warm disk cache makes short)")
    a = ap.parse_args()
    p = SweepParams()
    counts = {pitch: count(pitch, p) for pitch in (60.0, 30.0)}
    assert counts[60.0]["mountable"] == len(enumerate_configs(p)), "grid count differs from enumerate_configs"
    eff = a.efficiency
    if eff is None:
        bench = json.loads((OUT / "sweep.json").read_text())
        eff = float(bench["scaling_efficiency_2"])
    cold = float(json.loads((OUT / "sweep.json").read_text())["unit_solutions_s"])
    cfgs = [c for c in enumerate_configs(p)
            if c["d"] + c["b2"] < c["b3"] + c["b4"] and abs(c["d"] - c["b2"]) > abs(c["b3"] - c["b4"])][::a.every]
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    bases = build_bases(p)
    t_bases = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        table = run_sweep(p, tmp, configs=cfgs, chunk_size=8, bases=bases, distributed=False, progress=False)
        t_run = time.perf_counter() - t0
    t_cfg = t_run / len(cfgs)
    # the unit-solution cache may be warm here: assume a cold build
    t_bases_used = a.bases_seconds if a.bases_seconds is not None else max(t_bases, cold)
    assert (table["status"] == "ok").all()
    t_ref = float(json.loads((OUT / "sweep.json").read_text())["per_configuration_s"]["1"])
    proj = {}
    for label, t in (("measured", t_cfg), ("sweep.json", t_ref)):
        for pitch, c in counts.items():
            proj[f"{pitch:g} mm, {label}"] = {n: t_bases_used + c["fe_checked"] * t / (n * (1.0 if n == 1 else eff))
                                           for n in a.workers}
    res = {"counts": {str(k): v for k, v in counts.items()}, "bases_s": t_bases, "bases_cold_s": t_bases_used,
           "per_config_s": t_cfg, "timed_configs": len(cfgs), "per_config_sweep_json_s": t_ref, "efficiency": eff,
           "load_before": load, "load_after": os.getloadavg()[0],
           "projected_s": {k: {str(n): v for n, v in d.items()} for k, d in proj.items()}}
    md = ["# Sweep cost of a finer rig grid (four-bar, draft)", "",
          "Command: `python benchmarks/sweep_grid_cost.py" + (f" --every {a.every}" if a.every != 400 else "")
          + (f" --bases-seconds {a.bases_seconds:g}" if a.bases_seconds is not None else "") + "`",
          f"(load average {load:.2f} before, {res['load_after']:.2f} after; shared 2-core machine).", "",
          "| hole pitch | lengths b2 × b3 × b4 × d | mountable configurations | with FE check (full turn) |",
          "|---|---|---|---|"]
    for c in counts.values():
        md.append(f"| {c['pitch_mm']:g} mm | {' × '.join(map(str, c['lengths']))} | {c['mountable']:,} | "
                  f"{c['fe_checked']:,} |")
    md += ["", f"Measured: unit solutions {t_bases:.1f} s here (the on-disk cache may be warm; the projection "
           f"uses {t_bases_used:.0f} s for a cold build), "
           f"{t_cfg * 1e3:.0f} ms per FE-checked "
           f"configuration (serial draft sweep of {len(cfgs)} configurations spread over the grid; "
           f"results/benchmarks/sweep.json recorded {t_ref * 1e3:.0f} ms per configuration on its subset with one "
           f"Dask worker, start-up included).  Assumed parallel efficiency {eff:.0%} for every N > 1 (the "
           f"steady-state 1 → 2 worker figure of results/benchmarks/sweep.md).", "",
           "| hole pitch, per-configuration time | " + " | ".join(f"N = {n}" for n in a.workers) + " |",
           "|---|" + "---|" * len(a.workers)]
    for key, d in proj.items():
        t = t_cfg if key.endswith("measured") else t_ref
        md.append(f"| {key.split(',')[0]}, {t * 1e3:.0f} ms ({key.split(', ')[1]}) | "
                  + " | ".join(_hms(v) for v in d.values()) + " |")
    md += ["", "Projection T(N) = unit solutions + n_FE × t_cfg / (N × efficiency); the configurations "
           "without FE (rules and dynamics only) are left out; the unit solutions of a 30 mm rail layout "
           "(more holes, more unit loads) are taken as the 60 mm ones, a lower bound.", ""]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "sweep_grid_cost.json").write_text(json.dumps(res, indent=1))
    (OUT / "sweep_grid_cost.md").write_text("\n".join(md))
    print("\n".join(md))


def _hms(s: float) -> str:
    return f"{s / 3600:.1f} h" if s >= 3600 else f"{s / 60:.1f} min" if s >= 60 else f"{s:.0f} s"


if __name__ == "__main__":
    main()
