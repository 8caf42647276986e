"""Cost of a finer rig grid: four-bar configurations at a hole pitch of 60 mm (the rig) and 30 mm,
and the wall time of their sweep projected on N Dask workers from a short measured draft sweep.

    python benchmarks/sweep_grid_cost.py [--every 40] [--workers 1 2 16 64]

Counting uses the rules of ``rigfem.sweep.enumerate_configs`` with the rail's pitch overridden
(each length a whole number of pitches from one pitch up, its coupling's two screws on the
rail's holes, the ground from 660 mm on the 2500 mm ground rail); the 60 mm count is checked
against ``enumerate_configs`` itself.  The configurations that get an FE check are those whose
crank turns fully without a dead point: d + b2 < b3 + b4 and |d − b2| > |b3 − b4| (the loop
closes at every crank angle; equality is a dead point, a "toggle" row).  The rig's 60 mm
default is not changed.

Measured here: the per-configuration time of a serial draft sweep over an evenly spread subset
of the checked configurations.  Read from results/benchmarks/sweep.json (the end-to-end sweep
record): the once-per-sweep cold cost (cold minus warm wall time of the whole 60 mm sweep with
two workers: meshes, unit solutions, compiled kernels; a 30 mm rail layout has more holes, so
this is a lower bound for it) and the parallel efficiency (warm sweep, 1 -> 2 workers, start-up
included, kept for all N: a cluster's workers do not share 2 cores).  Projection: T(N) =
T_cold + n_FE · t_cfg / (N · efficiency(N)); the configurations without FE (rules and dynamics
only) are left out.  Writes results/benchmarks/sweep_grid_cost.json (``benchmarks/publish.py``
writes the .md).
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np
from record import read_record, write_record

from rigfem.rig import MIN_GROUND_MM
from rigfem.rig.layout import RailLayout
from rigfem.rig.parts import load_part, rail_hole_x
from rigfem.settings import PLATE, RAIL
from rigfem.sweep import SweepParams, build_bases, enumerate_configs, run_sweep


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
    """Four-bar configurations on a ``pitch`` grid: all of them and those checked by FE."""
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
    a = ap.parse_args()
    p = SweepParams()
    counts = {pitch: count(pitch, p) for pitch in (60.0, 30.0)}
    assert counts[60.0]["mountable"] == len(enumerate_configs(p)), "grid count differs from enumerate_configs"
    sweep = read_record("sweep")
    cfgs = [c for c in enumerate_configs(p)
            if c["d"] + c["b2"] < c["b3"] + c["b4"] and abs(c["d"] - c["b2"]) > abs(c["b3"] - c["b4"])][::a.every]
    t0 = time.perf_counter()
    bases = build_bases(p)
    t_bases = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        table = run_sweep(p, tmp, configs=cfgs, chunk_size=8, bases=bases, distributed=False, progress=False)
        t_run = time.perf_counter() - t0
    assert (table["status"] == "ok").all()
    samples = {"unit solutions (this run, cache as found)": [{"wall_s": t_bases}],
               "serial draft sweep of the subset": [{"wall_s": t_run, "configurations": len(cfgs)}]}
    t_cfg = t_run / len(cfgs)
    eff = sweep["derived"].get("warm efficiency 1 -> 2 workers")  # None: no 1-worker run, N = 1 only
    workers = [n for n in a.workers if n == 1 or eff is not None]
    t_cold = sweep["derived"]["cold - warm, 2 workers (s)"]  # meshes, unit solutions, kernels: once per sweep
    proj = {f"{pitch:g}": {str(n): t_cold + c["fe_checked"] * t_cfg / (n * (1.0 if n == 1 else eff))
                           for n in workers} for pitch, c in counts.items()}
    derived = {"counts": {f"{k:g}": v for k, v in counts.items()}, "per_config_s": t_cfg,
               "efficiency (sweep record, warm 1 -> 2 workers)": eff,
               "cold build (sweep record, cold - warm, 2 workers) s": t_cold,
               "sweep record": {"date": sweep["date"], "commit": sweep["commit"]["sha"]}, "projected_s": proj}
    print(f"wrote {write_record('sweep_grid_cost', samples, derived, {'every': a.every, 'workers': a.workers})}")
