"""What a sweep or a rig synthesis search will cost, estimated from the counts before any array
is allocated, any mesh built or the search started, and refused past the machine's memory or
:data:`rigfem.settings.MAX_JOB_HOURS` unless the user lifts the limits (``rigfem --allow-large``).

- A configuration whose crank turns fully costs about :data:`SECONDS_PER_ANGLE` per crank angle
  (dynamics, load cases, unit-field peaks) and holds about :data:`BYTES_PER_ANGLE` per crank
  angle while it is evaluated, in each worker; the others cost almost nothing.
- The unit solutions (one mesh and solve per part) are estimated from each part's dimensions
  (:func:`rigfem.mesh.mesher.estimate_part`): meshing time and the memory of gmsh and of a
  direct P2 solve; a lower bound (refinement comes on top).
"""

from __future__ import annotations

from dataclasses import dataclass

from rigfem.errors import InfeasibleError
from rigfem.settings import MAX_JOB_HOURS, allow_large
from rigfem.sweep.configs import SweepParams

__all__ = ["SECONDS_PER_ANGLE", "BYTES_PER_ANGLE", "JobCost", "turning", "bases_cost", "sweep_cost",
           "synthesis_cost", "check_cost"]

#: s per crank angle of a configuration that turns, draft unit solutions built: 11.9 s for 16
#: configurations × 360 angles (results/benchmarks/stages.md, `benchmarks/profile_stages.py`)
SECONDS_PER_ANGLE = 11.9 / 16 / 360
#: bytes held per crank angle while a configuration is evaluated (18 MB at 3600 angles, tracemalloc)
BYTES_PER_ANGLE = 5.2e3


@dataclass(frozen=True)
class JobCost:
    """A job's estimated peak memory (GiB) and wall time (s), and what it counts."""

    what: str
    gib: float
    seconds: float


def turning(p: SweepParams, configs: list[dict]) -> int:
    """How many of ``configs`` have a crank that turns fully (the ones that get a stress check):
    four-bar d + b2 < b3 + b4 and |d − b2| > |b3 − b4|; slider-crank b2 + |offset| < b3."""
    if p.linkage_type == "four-bar":
        return sum(c["d"] + c["b2"] < c["b3"] + c["b4"] and abs(c["d"] - c["b2"]) > abs(c["b3"] - c["b4"])
                   for c in configs)
    return sum(c["b2"] + abs(c.get("offset", 0.0)) < c["b3"] for c in configs)


def bases_cost(p: SweepParams, workers: int = 1) -> JobCost:
    """The unit solutions of ``p``'s parts at its fidelity: memory of the largest parts solved at
    once (meshing or their direct P2 solves; :func:`rigfem.sweep.bases.parallel_bases`
    of them with ``workers``), meshing time of all of them; from their dimensions, nothing built."""
    from rigfem.mesh.mesher import estimate_part
    from rigfem.rig.parts import load_part
    from rigfem.sweep.bases import parallel_bases

    s = p.settings()
    gibs, seconds = [], 0.0
    for spec in s.parts.values():
        est = estimate_part(load_part(spec["part"], {"length": spec["length"]} if "length" in spec else None), s)
        if est is not None:
            gibs, seconds = gibs + [est.gib], seconds + est.seconds
    gib = sum(sorted(gibs, reverse=True)[:parallel_bases(workers, len(gibs))])
    return JobCost(f"unit solutions of {len(s.parts)} parts at {p.fidelity}", gib, seconds)


def sweep_cost(p: SweepParams, configs: list[dict], workers: int, bases: bool = True) -> JobCost:
    """Cost of sweeping ``configs`` on ``workers`` processes (``bases``: unit solutions included)."""
    n = turning(p, configs)
    base = bases_cost(p, workers) if bases else JobCost("", 0.0, 0.0)
    per = p.samples * BYTES_PER_ANGLE / 2**30
    return JobCost(f"{len(configs)} {p.linkage_type} configurations ({n} turn fully) × {p.samples} crank angles "
                   f"on {workers} worker{'s' * (workers != 1)}",
                   max(base.gib, workers * per), base.seconds + n * p.samples * SECONDS_PER_ANGLE / workers)


def synthesis_cost(p: SweepParams, candidates: int, stress: bool) -> JobCost:
    """Cost of the stress verdicts of ``candidates`` rig four-bars (``stress``; the ranking itself
    works on fixed-size blocks of the rig's four-bars and costs seconds)."""
    if not stress:
        return JobCost("rig search without stress verdicts", 0.0, 0.0)
    base = bases_cost(p)
    return JobCost(f"stress verdicts of {candidates} rig four-bars ({base.what})", base.gib,
                   base.seconds + candidates * p.samples * SECONDS_PER_ANGLE)


def check_cost(cost: JobCost, machine_gib: float) -> None:
    """Refuse (InfeasibleError, one line) a job past the machine's memory or :data:`MAX_JOB_HOURS`,
    unless the user lifted the limits (``rigfem --allow-large``)."""
    over = []
    if cost.gib > machine_gib:
        over.append(f"{cost.gib:.3g} GiB of memory, more than the machine's {machine_gib:.3g} GiB")
    if cost.seconds > MAX_JOB_HOURS * 3600:
        over.append(f"{cost.seconds / 3600:.3g} h, more than the limit of {MAX_JOB_HOURS:g} h")
    if over and not allow_large():
        raise InfeasibleError(f"{cost.what}: estimated {' and '.join(over)}; reduce the job, or pass "
                              f"rigfem --allow-large")
