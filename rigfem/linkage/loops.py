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
           "change_points_deg", "change_points_passed", "slider_crank_angles", "singular_ranges", "is_full_turn"]

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


def _change_masks(b2, b3, b4, d) -> tuple:
    """Whether the four-bar (lengths may be arrays) has a change point at crank 0 deg, at 180 deg."""
    tol = 1e-9 * np.maximum(np.maximum(b2, b3), np.maximum(b4, d))
    return np.abs(np.abs(d - b2) - np.abs(b3 - b4)) <= tol, np.abs(d + b2 - b3 - b4) <= tol


def change_points_deg(b2: float, b3: float, b4: float, d: float) -> list[float]:
    """Crank angles (0 and/or 180 deg) where a change-point four-bar (two lengths summing to the
    other two, Grashof's equality) lies flat, every link in line: its two assembly branches meet
    there and the linkage may leave on either.  [] for any other four-bar.

    >>> change_points_deg(500, 500, 500, 500), change_points_deg(300, 700, 700, 300)
    ([0.0, 180.0], [0.0])
    """
    at0, at180 = _change_masks(b2, b3, b4, d)
    return [0.0] * bool(at0) + [180.0] * bool(at180)


def change_points_passed(b2: float, b3: float, b4: float, d: float, start_deg: float, span_deg: float) -> list[float]:
    """The change points (:func:`change_points_deg`) the crank meets turning ``span_deg`` from
    ``start_deg`` (negative: clockwise), both ends included: where the linkage may leave on
    either branch.

    >>> change_points_passed(500, 500, 500, 500, 90.0, 180.0), change_points_passed(500, 500, 500, 500, 90.0, -80.0)
    ([180.0], [])
    """
    out = []
    for c in change_points_deg(b2, b3, b4, d):
        off = (c - start_deg) % 360.0 if span_deg >= 0 else (start_deg - c) % 360.0
        if off <= abs(span_deg) + 1e-9:
            out.append(c)
    return out


def _branch_signs(at180, th2, branch):
    """The closed form's branch sign at each crank angle of a four-bar followed by continuity: the
    named ``branch`` from crank 0 deg on, the sign flipping where the crank passes a change point
    (there the two branches meet, and keeping the formula's sign would jump to the other one).
    Over one turn [0, 360) the flip at 180 deg is the only one that shows (``at180``: the
    four-bar has a change point there)."""
    return np.where(at180 & (np.mod(th2, 2 * np.pi) > np.pi), -float(branch), float(branch))


#: crank step (rad) of the rates near a change point: within it, where the formulas read 0/0 or
#: lose their digits (at 1e-3 rad from it, accelerations keep five), the rates are interpolated
#: from the smooth branch's at 1, 2 and 3 steps on either side (a quintic: its truncation and the
#: formulas' round-off there are both near 1e-9 relative)
_CHANGE_STEP = 1e-2
_CHANGE_NODES = np.array([-3.0, -2.0, -1.0, 1.0, 2.0, 3.0])  #: in steps from the change point


def fourbar_angles(b2: float, b3: float, b4: float, d: float, th2: np.ndarray, w2, a2=0.0,
                   branch: int = 1) -> dict[str, np.ndarray]:
    """Coupler and rocker angles, rates and accelerations (rad, rad/s, rad/s²) of a four-bar
    (any length unit; lengths may be arrays, broadcast with the angles); ``branch`` +1 open,
    -1 crossed.  NaN where the loop cannot close.

    A change-point four-bar (:func:`change_points_deg`) is followed through its change points by
    continuity (the smooth motion: angles and rates continuous), its rates near a change point
    (where the formulas read 0/0) being those of the smooth curve through it."""
    th2 = np.asarray(th2, float)
    at0, at180 = _change_masks(b2, b3, b4, d)
    if np.any(at0) or np.any(at180):  # one turn [0, 360): 360 deg is crank 0 again, not the end of a turn
        th2 = np.where(at0 | at180, np.mod(th2, 2 * np.pi), th2)
    out = _fourbar_angles(b2, b3, b4, d, th2, w2, a2, _branch_signs(at180, th2, branch))
    if np.any(at0) or np.any(at180):
        _rates_at_change_points(out, at0, at180, (b2, b3, b4, d, th2, w2, a2), branch)
    return out


def _rates_at_change_points(out: dict, at0, at180, args: tuple, branch: int) -> None:
    """Replace the rates within :data:`_CHANGE_STEP` of a change point by those of the smooth curve
    the motion is on there (its Lagrange interpolant through :data:`_CHANGE_NODES`): the branch it
    follows on that side, continued through the change point by the other sign (on the change
    point itself, the branch it leaves on).  A crank that swings through its change point within
    a few steps (its dead points close by) takes steps 8 or 64 times shorter; where even those
    would run into a dead point, the closed form stays."""
    shape = np.broadcast(*args).shape
    turn = np.mod(args[4], 2 * np.pi)
    past0, past180 = np.mod(turn + np.pi, 2 * np.pi) - np.pi, turn - np.pi  # signed, from each change point
    near0 = at0 & (np.abs(past0) < _CHANGE_STEP)
    on = np.broadcast_to(near0 | (at180 & (np.abs(past180) < _CHANGE_STEP)), shape)
    if not on.any():
        return
    b2, b3, b4, d, t, w2, a2 = (np.broadcast_to(x, shape)[on] for x in args)
    at180_on = np.broadcast_to(at180, shape)[on]
    delta = np.where(np.broadcast_to(near0, shape)[on], np.broadcast_to(past0, shape)[on],
                     np.broadcast_to(past180, shape)[on])
    t0 = t - delta
    # the sign on the side past the change point, of the curve the motion is on at t
    ahead = np.where(delta < 0, -_branch_signs(at180_on, t, branch),
                     _branch_signs(at180_on, t0 + _CHANGE_STEP, branch))
    rates = {k: np.broadcast_to(out[k], shape)[on].astype(float) for k in ("omega3", "omega4", "alpha3", "alpha4")}
    todo = np.ones(len(t), bool)
    for h in (_CHANGE_STEP, _CHANGE_STEP / 8, _CHANGE_STEP / 64):
        x = _CHANGE_NODES * h
        sel = todo & (np.abs(delta) < h)

        def at(k: float) -> dict:
            return _fourbar_angles(b2[sel], b3[sel], b4[sel], d[sel], t0[sel] + k, w2[sel], a2[sel],
                                   np.sign(k) * ahead[sel])

        # the curve must close a step beyond the nodes, else they may run into a dead point
        room = np.isfinite(at(x.min() - h)["theta4"]) & np.isfinite(at(x.max() + h)["theta4"])
        u = delta[sel]
        weights = [np.prod([(u - x[m]) / (x[j] - x[m]) for m in range(len(x)) if m != j], axis=0)
                   for j in range(len(x))]
        nodes = [at(k) for k in x]
        idx = np.flatnonzero(sel)[room]
        for k in rates:
            rates[k][idx] = sum(w * n[k] for w, n in zip(weights, nodes))[room]
        todo[idx] = False
    for k, r in rates.items():
        v = np.array(np.broadcast_to(out[k], shape), float)
        v[on] = r
        out[k] = v


def _fourbar_angles(b2, b3, b4, d, th2: np.ndarray, w2, a2, branch) -> dict[str, np.ndarray]:
    """:func:`fourbar_angles` with the branch sign given per angle (``branch``: ±1 or an array)."""
    ax, ay = b2 * np.cos(th2), b2 * np.sin(th2)
    dx, dy = d - ax, -ay
    f2 = dx * dx + dy * dy
    f = np.sqrt(f2)
    with np.errstate(invalid="ignore", divide="ignore"):
        cpsi = (b3 * b3 + f2 - b4 * b4) / (2 * b3 * f)
        psi = np.arccos(np.where(np.abs(cpsi) <= 1.0 + 1e-12, np.clip(cpsi, -1.0, 1.0), np.nan))
        line = np.arctan2(dy, dx)
        over = (f2 == 0.0) & (b3 == b4)  # A on O4 (b2 = d, crank 0): the line A->O4 and psi as the crank nears it
        if np.any(over):
            line = np.where(over, np.mod(th2, 2 * np.pi) / 2 - np.pi / 2, line)
            psi = np.where(over, np.pi / 2, psi)
        th3 = line + branch * psi
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
