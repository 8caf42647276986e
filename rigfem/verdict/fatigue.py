"""Goodman fatigue check with a Marin-corrected endurance limit (Shigley, 10th ed., §6-9 and §6-12)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigfem.errors import ComputeError, InputError, check_range
from rigfem.tensors import von_mises
from rigfem.material import LOADING, RELIABILITY, SURFACE


@dataclass(frozen=True)
class Marin:
    """The Marin factors' inputs (Shigley §6-9), checked as they are made: the surface finish, the
    critical section's equivalent diameter d_e (mm, 2.79-254: for a non-rotating rectangle h×b,
    d_e = 0.808·√(h·b), the size-25 rail ≈ 19 mm), the loading, the reliability and kd."""

    surface: str = "machined"
    size_mm: float = 19.0
    loading: str = "combined"
    reliability: float = 0.9
    temperature_factor: float = 1.0

    def __post_init__(self) -> None:
        for name, value, allowed in (("surface", self.surface, SURFACE), ("loading", self.loading, LOADING),
                                     ("reliability", self.reliability, RELIABILITY)):
            if value not in allowed:
                raise InputError(f"fatigue {name} {value!r} is not one of {', '.join(str(v) for v in allowed)}")
        check_range("fatigue size_mm", self.size_mm, 2.79, 254.0, unit="mm")
        check_range("fatigue temperature_factor", self.temperature_factor, 0.0, 1.0, lo_open=True)


def marin_endurance(sigma_u_mpa: float, **factors) -> dict:
    """Marin-corrected endurance limit Se = ka·kb·kc·kd·ke·Se' with Se' = 0.5·Sut (Sut ≤ 1400 MPa);
    ``factors``: the fields of :class:`Marin` (σu comes validated: :class:`rigfem.material.Material`)."""
    m, su = Marin(**factors), sigma_u_mpa
    d = m.size_mm
    a, b = SURFACE[m.surface]
    ka = a * su ** b
    kb = 1.0 if m.loading == "axial" else ((d / 7.62) ** -0.107 if d <= 51 else 1.51 * d ** -0.157)
    kc, kd, ke = LOADING[m.loading], m.temperature_factor, RELIABILITY[m.reliability]
    se_prime = 0.5 * su if su <= 1400 else 700.0
    return {"se_prime_mpa": se_prime, "ka": ka, "kb": kb, "kc": kc, "kd": kd, "ke": ke,
            "se_mpa": ka * kb * kc * kd * ke * se_prime}


def goodman(history: np.ndarray, sigma_u_mpa: float, **marin) -> dict:
    """Goodman fatigue check of the stress cycle at candidate points.

    ``history``: stress tensors over one turn, shape (n_angles, n_points, 6) in MPa.
    Per point the mean and alternating tensors are the component-wise mid-range and
    half-range over the turn; their von Mises values σm', σa' give the Goodman factor
    n = 1 / (σa'/Se + σm'/Sut).  Returns the critical point (smallest n).
    """
    h = np.asarray(history, dtype=float)
    if h.ndim != 3 or h.shape[-1] != 6 or h.shape[0] < 2 or h.shape[1] < 1 or not np.all(np.isfinite(h)):
        raise ComputeError(f"a stress history must be finite, of shape (angles >= 2, points >= 1, 6): {h.shape}")
    end = marin_endurance(sigma_u_mpa, **marin)
    hi, lo = h.max(axis=0), h.min(axis=0)
    sa, sm = von_mises((hi - lo) / 2), von_mises((hi + lo) / 2)
    demand = sa / end["se_mpa"] + sm / sigma_u_mpa
    k = int(np.argmax(demand))
    n = float(np.inf) if demand[k] == 0 else 1.0 / float(demand[k])
    return {"point": k, "alternating_mpa": float(sa[k]), "mean_mpa": float(sm[k]),
            "safety_factor": min(n, 1e9), "verdict": "pass" if n >= 1.0 else "fail", **end}
