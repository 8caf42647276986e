"""Verdict on one part: peak von Mises against the σu/2 criterion, and a Goodman fatigue check.

The 2013 study's criterion is ``σvm,peak < σu/2`` (half the ultimate strength, the classic
estimate of the endurance limit).  A peak whose discretisation-error band straddles the
limit is *undecided*, never silently passed; the band is an estimate (calibrated ZZ recovery,
:func:`rigfem.fe.stress.error_band_pct`), not a bound.  So is a part whose free body does not balance
(its loads lost information) undecided, and a part nothing loads is *not loaded*, never a pass.
Beside it, :func:`goodman` checks the stress
cycle at the critical point (mean and alternating von Mises stress over one crank turn)
against a Goodman line with a Marin-corrected endurance limit (Shigley, *Mechanical
Engineering Design*, 10th ed., §6-9 and §6-12).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from rigfem.errors import ComputeError


@dataclass(frozen=True)
class Verdict:
    """σu/2 verdict of one part."""

    peak_mpa: float
    limit_mpa: float
    utilisation_pct: float
    error_pct: float  #: discretisation-error estimate of the peak (the band's half-width), in % of the peak
    verdict: str  #: "pass", "fail", "undecided" (error band contains the limit, or loads out of balance), "not loaded"
    reason: str = ""  #: why a part is undecided or not loaded

    def as_dict(self) -> dict:
        return asdict(self)


#: the study's criterion: peak von Mises below half the ultimate strength (geometry/RIG.md §5)
LIMIT_FACTOR = 0.5


def allowable_stress(sigma_u_mpa: float, factor: float = LIMIT_FACTOR) -> float:
    """The allowable stress ``factor·σu`` (MPa): the one place the criterion's limit is computed.
    σu and the factor come validated (:class:`rigfem.material.Material`, the scene's schema)."""
    if not (sigma_u_mpa > 0 and 0 < factor <= 1):
        raise ComputeError(f"allowable stress of sigma_u = {sigma_u_mpa!r} MPa and factor {factor!r}: not a limit")
    return factor * sigma_u_mpa


#: largest relative imbalance of a free body's loads (force over the applied load Σ|F|, moment
#: about the centroid over Σ|F| × the part's lever) a verdict accepts.  The FE part's mass
#: distribution is not the dynamics model's (holes, the rail behind its pivot), which leaves
#: below 1 % on the rig's rails; a history that lost a load (the crank's driver torque read as
#: zero) leaves tens of % (tests/test_trust.py measures both).  Above it the part is undecided:
#: inertia relief would cancel the missing load and the stress would be too low.
IMBALANCE_TOL = 0.05


def half_ultimate(peak_mpa: float, sigma_u_mpa: float, error_pct: float = 0.0,
                  factor: float = LIMIT_FACTOR, imbalance: tuple[float, float] = (0.0, 0.0),
                  loaded: bool = True) -> Verdict:
    """Check ``peak < factor·σu`` with the error-estimate band ``peak·(1 ± error_pct/100)``.

    ``imbalance``: the relative (force, moment) imbalance of the part's free body; above
    :data:`IMBALANCE_TOL` the part is undecided.  ``loaded``: False when every load of the part
    is zero (verdict "not loaded", never "pass").

    >>> half_ultimate(300.0, 750.0, error_pct=2.0).verdict
    'pass'
    >>> half_ultimate(370.0, 750.0, error_pct=2.0).verdict   # 370 ± 7.4 straddles 375
    'undecided'
    >>> half_ultimate(30.0, 750.0, imbalance=(0.001, 0.4)).reason
    'free body out of balance: force 0.1 %, moment 40.0 % (tolerance 5 %)'
    """
    peak, err = float(peak_mpa), float(error_pct)
    if not (math.isfinite(peak) and math.isfinite(err) and peak >= 0 and err >= 0):  # the FE's invariant
        raise ComputeError(f"peak von Mises {peak_mpa!r} MPa with error estimate {error_pct!r} %: not a stress")
    limit = allowable_stress(sigma_u_mpa, factor)
    lo, hi = peak * (1 - err / 100), peak * (1 + err / 100)
    verdict = "pass" if hi < limit else "fail" if lo >= limit else "undecided"
    reason = ""
    if not loaded:
        verdict, reason = "not loaded", "every load of this part is zero: nothing was checked"
    elif max(imbalance) > IMBALANCE_TOL and verdict != "fail":
        verdict = "undecided"
        reason = (f"free body out of balance: force {100 * imbalance[0]:.1f} %, moment {100 * imbalance[1]:.1f} % "
                  f"(tolerance {100 * IMBALANCE_TOL:g} %)")
    return Verdict(peak, limit, 100.0 * peak / limit, err, verdict, reason)


def overall(parts: list[dict]) -> str:
    """Overall verdict: fail if any part fails, undecided if any cannot be decided or is not
    loaded (an unloaded part was not checked), else pass."""
    verdicts = {p["verdict"] for p in parts}
    return ("fail" if "fail" in verdicts else
            "undecided" if verdicts & {"undecided", "not loaded"} else "pass")
