"""The verdict stage: every part case's outcome against the criterion, and what the whole check says.

One stage for every path that gives a verdict (``rigfem check``, the sweep, the rig design): the
measured error band of each peak, the lost-load guard (a free body out of balance is undecided),
a part nothing loads is *not loaded* (never a pass), a broken rig rule fails the configuration,
and a check of a subset of the parts or modes says what it left out.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from rigfem.errors import ComputeError
from rigfem.rig.rules import standing
from rigfem.settings import MODES, PARTS
from rigfem.verdict.criterion import Verdict, allowable_stress, half_ultimate, overall
from rigfem.verdict.fatigue import goodman

__all__ = ["Outcome", "PartVerdict", "Verdicts", "Target", "judge"]


@dataclasses.dataclass(frozen=True)
class Outcome:
    """What the FE says of one part case: all a verdict is made of (MPa, deg).

    A check's FE stage gives it (:attr:`rigfem.fe.partcase.CaseResult.outcome`); the sweep's
    superposed unit bases give the same fields without a solution (:mod:`rigfem.sweep.superpose`),
    so both are judged by one verdict stage (:func:`judge`)."""

    name: str
    part: str
    mode: str
    peak_mpa: float
    error_pct: float  #: the error band's half-width, % of the peak (the calibrated ZZ estimate)
    crank_deg: float
    imbalance: tuple[float, float] = (0.0, 0.0)  #: relative (force, moment) imbalance of a free body
    loaded: bool = True  #: False when every load of the case is zero
    cycle_stress: np.ndarray | None = None  #: (rows, points, 6) stress history where the peak may be, MPa


@dataclasses.dataclass(frozen=True)
class PartVerdict:
    """One part case's verdict: its outcome, the σu/2 verdict with its band, and the Goodman check."""

    outcome: Outcome
    verdict: Verdict
    fatigue: dict | None = None  #: Goodman at the critical point of a cycle case (its ``point`` among the candidates)

    @property
    def band_mpa(self) -> float:
        """The band's half-width, MPa."""
        return self.verdict.peak_mpa * self.verdict.error_pct / 100.0


@dataclasses.dataclass(frozen=True)
class Verdicts:
    """Every part case's verdict, the stress verdict over them, the configuration's verdict (a broken
    rig rule fails it), its standing in the one vocabulary (:func:`rigfem.rig.rules.standing`) and
    the parts and modes left out of a check of a subset ("" when none)."""

    parts: tuple[PartVerdict, ...]
    stress: str
    overall: str
    limit_mpa: float  #: the allowable stress the peaks were judged against
    rule_violations: tuple[str, ...] = ()
    left_out: str = ""
    #: what a check of a subset checked, short ("1 of 6 parts, original mode only"; "" when everything)
    checked: str = ""
    not_checked: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())  #: (parts, modes) not checked
    #: "assembles; meets the rig rules (or they do not apply); passes the stress criterion (or not)"
    standing: str = ""

    @property
    def governing(self) -> PartVerdict | None:
        """The case with the highest utilisation (None when nothing was computed)."""
        return max(self.parts, key=lambda p: p.verdict.utilisation_pct, default=None)


@dataclasses.dataclass(frozen=True)
class Target:
    """The refinement policy's judge (:class:`rigfem.fe.ladder.Judge`): a case is settled when a
    finer mesh cannot change what the report says of it — its band does not straddle the limit
    and its half-width ``peak·error_pct/100`` is within the preset's reporting target,
    ``settings.target_pct`` % of the allowable, and, where the preset has one (``fine``),
    ``error_pct`` within ``settings.target_peak_pct`` % of the peak (a part nothing loads is
    settled; a free body out of balance is not a matter of mesh and is judged by the band alone)."""

    settings: object  #: rigfem.settings.CheckSettings

    def settled(self, outcome: Outcome, shrink: float = 1.0) -> bool:
        """True when ``outcome`` is settled with its band narrowed ``shrink`` times (a finer level's best case)."""
        s, err = self.settings, outcome.error_pct * shrink
        v = half_ultimate(outcome.peak_mpa, s.material.sigma_u, err, s.limit_factor, loaded=outcome.loaded)
        if v.verdict == "not loaded":
            return True
        of_peak = getattr(s, "target_peak_pct", None)
        return (v.verdict != "undecided" and outcome.peak_mpa * err <= s.target_pct * v.limit_mpa
                and (of_peak is None or err <= of_peak))


def _scope(settings) -> dict:
    """What a check of a subset left out (the long text, the short one, the parts and modes not
    checked); empty texts when every part and mode was checked."""
    every = PARTS.get(settings.linkage_type, {})
    parts = tuple(p for p in every if p not in settings.parts)
    modes = tuple(m for m in MODES if m not in settings.modes)
    long, short = [], []
    if parts:
        count = f"{len(every) - len(parts)} of {len(every)} parts"
        long.append(f"{count} (not {', '.join(parts)})")
        short.append(count)
    if modes:
        long.append(f"{' and '.join(settings.modes)} mode only")
        short.append(long[-1])
    return {"left_out": ", ".join(long), "checked": ", ".join(short), "not_checked": (parts, modes)}


def judge(outcomes: Sequence[Outcome], settings, rule_violations: Sequence[str] | None = (),
          singular: list | None = None) -> Verdicts:
    """The verdicts of ``outcomes`` under ``settings`` (a :class:`rigfem.settings.CheckSettings`:
    material, limit factor, fatigue).  The configuration fails when it breaks a rig rule
    (``rule_violations``: the rules it breaks, none by default; None: the rig rules do not apply,
    a textbook linkage), whatever its stresses, and when its linkage passes a toggle
    (``singular``: the crank-angle ranges where its reactions grow without bound).  A
    configuration a check computes assembles."""
    parts = []
    for o in outcomes:
        if o.loaded and not o.peak_mpa > 0:  # an invariant no cache entry can hide: load without stress is a bug
            raise ComputeError(f"part {o.name} ({o.mode}): loaded, but its peak von Mises is {o.peak_mpa!r} MPa")
        v = half_ultimate(o.peak_mpa, settings.material.sigma_u, o.error_pct, settings.limit_factor, o.imbalance,
                          o.loaded)
        fatigue = None
        if o.cycle_stress is not None and np.size(o.cycle_stress):
            fatigue = goodman(o.cycle_stress, settings.material.sigma_u, **settings.fatigue)
        parts.append(PartVerdict(o, v, fatigue))
    stress = ("fail" if singular else overall([{"verdict": p.verdict.verdict} for p in parts]) if parts
              else "undecided")
    broken = tuple(rule_violations or ())
    return Verdicts(tuple(parts), stress, "fail" if broken else stress,
                    allowable_stress(settings.material.sigma_u, settings.limit_factor), broken, **_scope(settings),
                    standing=standing(True, None if rule_violations is None else not broken, stress))
