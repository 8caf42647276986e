"""Loop-closure closed forms of the four-bar and the slider-crank: angles, rates and
accelerations of the links from the crank's, vectorised (and broadcast over lengths).

The lowest layer of the linkage code: the kinematics (``rigfem.linkage.kinematics``), the
closed-form dynamics (``rigfem.linkage.closed``), the 2013 program and the builders all
take their closure formulas from here.

Derivation (four-bar): the loop b2 e2 + b3 e3 = d ex + b4 e4 (e_i = (cos th_i, sin th_i))
is closed through the triangle A-B-O4; differentiating once and twice and taking dot
products with e4 and e3 eliminates one unknown rate at a time.  Slider-crank: the y
component of O2A + AB = y_offset gives sin th3, its derivatives omega3 and alpha3, the x
component the slider.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BRANCHES", "MU_TOGGLE_DEG", "transmission_angle_deg", "fourbar_closes", "fourbar_angles",
           "slider_crank_angles", "singular_ranges", "is_full_turn"]

#: branch name -> sign of the coupler's turn from the line A->O4 (as rigfem.linkage.original)
BRANCHES = {"open": 1, "crossed": -1}

#: a four-bar is at a toggle when its transmission angle mu is within this angle of 0 or
#: 180 deg, a slider-crank when its rod is within this angle of perpendicular to the slide:
#: reactions there are unbounded, so no peak is reported (``rigfem.dynamics.history.peaks``)
MU_TOGGLE_DEG = 5.0


def transmission_angle_deg(theta3: np.ndarray, theta4: np.ndarray) -> np.ndarray:
    """Four-bar transmission angle mu (deg, 0..180): the interior coupler–rocker angle at B."""
    return np.degrees(np.arccos(np.clip(np.cos(np.asarray(theta3) - np.asarray(theta4)), -1.0, 1.0)))


def fourbar_closes(b2: float, b3: float, b4: float, d: float, deg: np.ndarray) -> np.ndarray:
    """True where the four-bar loop closes at crank angle ``deg`` (O2 at 0, O4 at (d, 0))."""
    th = np.radians(deg)
    f = np.sqrt(b2**2 + d**2 - 2 * b2 * d * np.cos(th))
    return (f <= b3 + b4 + 1e-12 * f) & (f >= abs(b3 - b4) - 1e-12 * f)


def fourbar_angles(b2: float, b3: float, b4: float, d: float, th2: np.ndarray, w2, a2=0.0,
                   branch: int = 1) -> dict[str, np.ndarray]:
    """Coupler and rocker angles, rates and accelerations (rad, rad/s, rad/s²) of a four-bar
    (any length unit); ``branch`` +1 open, -1 crossed.  NaN where the loop cannot close."""
    th2 = np.asarray(th2, float)
    ax, ay = b2 * np.cos(th2), b2 * np.sin(th2)
    dx, dy = d - ax, -ay
    f2 = dx * dx + dy * dy
    f = np.sqrt(f2)
    with np.errstate(invalid="ignore", divide="ignore"):
        cpsi = (b3 * b3 + f2 - b4 * b4) / (2 * b3 * f)
        psi = np.arccos(np.where(np.abs(cpsi) <= 1.0 + 1e-12, np.clip(cpsi, -1.0, 1.0), np.nan))
        th3 = np.arctan2(dy, dx) + branch * psi
        th4 = np.arctan2(ay + b3 * np.sin(th3), ax + b3 * np.cos(th3) - d)
        s34 = np.sin(th3 - th4)
        w3 = b2 * w2 * np.sin(th4 - th2) / (b3 * s34)
        w4 = b2 * w2 * np.sin(th3 - th2) / (b4 * s34)
        # d2/dt2 of the loop, dotted with e4 (eliminates alpha4) and with e3 (eliminates alpha3)
        a3 = (-b4 * w4**2 + b2 * w2**2 * np.cos(th2 - th4) + b3 * w3**2 * np.cos(th3 - th4)
              - b2 * a2 * np.sin(th4 - th2)) / (b3 * np.sin(th4 - th3))
        a4 = (b2 * a2 * np.sin(th3 - th2) - b2 * w2**2 * np.cos(th2 - th3) - b3 * w3**2
              + b4 * w4**2 * np.cos(th4 - th3)) / (b4 * s34)
    return dict(theta3=th3, theta4=th4, omega3=w3, omega4=w4, alpha3=a3, alpha4=a4, f2=f2)


def slider_crank_angles(b2: float, b3: float, offset: float, th2: np.ndarray, w2, a2=0.0) -> dict[str, np.ndarray]:
    """Rod angle, rate and acceleration (rad, rad/s, rad/s²) and the slider's position, velocity
    and acceleration along the slide (any length unit) of a slider-crank, slider on the +x side."""
    th2 = np.asarray(th2, float)
    c2, sn2 = np.cos(th2), np.sin(th2)
    s3 = (offset - b2 * sn2) / b3
    th3 = np.arcsin(s3)
    c3 = np.cos(th3)
    with np.errstate(divide="ignore", invalid="ignore"):
        w3 = -b2 * w2 * c2 / (b3 * c3)
        a3 = (b2 * w2**2 * sn2 - b2 * a2 * c2 + b3 * w3**2 * s3) / (b3 * c3)
    return dict(theta3=th3, omega3=w3, alpha3=a3, x=b2 * c2 + b3 * c3, v=-b2 * w2 * sn2 - b3 * w3 * s3,
                acc=-b2 * (a2 * sn2 + w2**2 * c2) - b3 * (a3 * s3 + w3**2 * c3))


def singular_ranges(crank_deg: np.ndarray, mask: np.ndarray | None) -> list[list[float]] | None:
    """Contiguous crank-angle ranges [start, end] (deg) where ``mask`` is True; None if none."""
    if mask is None or not np.any(mask):
        return None
    idx = np.flatnonzero(mask)
    breaks = np.flatnonzero(np.diff(idx) != 1)
    starts, ends = np.r_[idx[0], idx[breaks + 1]], np.r_[idx[breaks], idx[-1]]
    return [[float(crank_deg[a]), float(crank_deg[b])] for a, b in zip(starts, ends)]


def is_full_turn(deg: np.ndarray) -> bool:
    """True if ``deg`` is an evenly spaced full turn (360 deg excluded)."""
    if deg.size < 4:
        return False
    step = np.diff(deg)
    return bool(np.allclose(step, step[0], rtol=1e-6, atol=1e-9)
                and abs(abs(step[0]) * deg.size - 360.0) < 1e-6 * 360)
