"""Closed-form stresses the FE is checked against (the one home of their formulas).

* :func:`kt_plate_hole` — Peterson's stress concentration factor of a finite-width plate with a
  central circular hole in uniaxial tension: Pilkey & Pilkey, *Peterson's Stress Concentration
  Factors*, 3rd ed., eq. (4.1) / Chart 4.1, a fit to Howland (1930) for plane stress,
  Kt_n = 2 + 0.284 q − 0.600 q² + 1.32 q³ with q = 1 − d/W, referred to the net-section stress
  σ·W/(W − d); within about 1 % of Howland's own table (2.51 at d/W = 0.2).
"""

from __future__ import annotations

from rigfem.errors import check_range


def kt_plate_hole(d_over_w: float) -> float:
    """Peterson's net-section Kt_n of a plate (width W) with a central hole (diameter d) in tension."""
    q = 1.0 - check_range("d/W", d_over_w, 0.0, 0.65)
    return 2.0 + 0.284 * q - 0.600 * q**2 + 1.32 * q**3


def plate_hole_peak_mpa(sigma_mpa: float, width_mm: float, diameter_mm: float) -> float:
    """Peak (hoop) stress at the hole's edge, MPa: Kt_n · σ · W/(W − d) for a remote tension σ."""
    return kt_plate_hole(diameter_mm / width_mm) * sigma_mpa * width_mm / (width_mm - diameter_mm)
