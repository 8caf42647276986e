"""Verdict on one part: peak von Mises against the σu/2 criterion, and a Goodman fatigue check.

The 2013 study's criterion is ``σvm,peak < σu/2`` (half the ultimate strength, the classic
estimate of the endurance limit).  A peak whose discretisation-error band straddles the
limit is *undecided*, never silently passed; the band is an estimate (calibrated ZZ recovery,
:func:`rigfem.fe.stress.error_band_pct`), not a bound.  Beside it, :func:`goodman` checks the stress
cycle at the critical point (mean and alternating von Mises stress over one crank turn)
against a Goodman line with a Marin-corrected endurance limit (Shigley, *Mechanical
Engineering Design*, 10th ed., §6-9 and §6-12).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from rigfem.errors import check_range


@dataclass(frozen=True)
class Verdict:
    """σu/2 verdict of one part."""

    peak_mpa: float
    limit_mpa: float
    utilisation_pct: float
    error_pct: float  #: discretisation-error estimate of the peak (the band's half-width), in % of the peak
    verdict: str  #: "pass", "fail" or "undecided" (the error band contains the limit)

    def as_dict(self) -> dict:
        return asdict(self)


#: the study's criterion: peak von Mises below half the ultimate strength (geometry/RIG.md §5)
LIMIT_FACTOR = 0.5


def allowable_stress(sigma_u_mpa: float, factor: float = LIMIT_FACTOR) -> float:
    """The allowable stress ``factor·σu`` (MPa): the one place the criterion's limit is computed."""
    su = check_range("sigma_u", sigma_u_mpa, 0.0, unit="MPa", lo_open=True)
    return check_range("limit_factor", factor, 0.0, 1.0, lo_open=True) * su


def half_ultimate(peak_mpa: float, sigma_u_mpa: float, error_pct: float = 0.0,
                  factor: float = LIMIT_FACTOR) -> Verdict:
    """Check ``peak < factor·σu`` with the error-estimate band ``peak·(1 ± error_pct/100)``.

    >>> half_ultimate(300.0, 750.0, error_pct=2.0).verdict
    'pass'
    >>> half_ultimate(370.0, 750.0, error_pct=2.0).verdict   # 370 ± 7.4 straddles 375
    'undecided'
    """
    peak = check_range("peak von Mises", peak_mpa, 0.0, unit="MPa")
    err = check_range("error estimate", error_pct, 0.0, unit="%")
    limit = allowable_stress(sigma_u_mpa, factor)
    lo, hi = peak * (1 - err / 100), peak * (1 + err / 100)
    verdict = "pass" if hi < limit else "fail" if lo >= limit else "undecided"
    return Verdict(peak, limit, 100.0 * peak / limit, err, verdict)


def overall(parts: list[dict]) -> str:
    """Overall verdict: fail if any part fails, undecided if any cannot be decided, else pass."""
    verdicts = {p["verdict"] for p in parts}
    return "fail" if "fail" in verdicts else "undecided" if "undecided" in verdicts else "pass"
