"""Closed-form kinematics of the four-bar and the slider-crank, vectorised over crank angles.

Conventions (geometry/MECHANISMS.md): O2 at the origin, the ground line along +x, the crank angle
theta2 counter-clockwise from +x (degrees in); four-bar O4 at (d, 0); slider-crank slider on
the line y = offset on the +x side.  Link rates in rad/s and rad/s², points in mm, mm/s,
mm/s².  The driver turns at ``omega`` (rad/s, negative = clockwise) with angular
acceleration ``alpha`` (rad/s², 0 = constant speed).

Derivation (four-bar): the loop b2 e2 + b3 e3 = d ex + b4 e4 (e_i = (cos th_i, sin th_i))
is closed through the triangle A-B-O4; differentiating once and twice and taking dot
products with e4 and e3 eliminates one unknown rate at a time.  Slider-crank: the y
component of O2A + AB = y_offset gives sin th3, its derivatives omega3 and alpha3, the x
component the slider.  ``motion_from_history`` gives the same :class:`Motion` from the general
planar solver, for the linkages without a closed form here (inverted slider-crank, quick-return).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigfem.linkage.loops import (
    BRANCHES,
    change_points_deg,
    fourbar_angles,
    fourbar_closes,
    slider_crank_angles,
    transmission_angle_deg,
)
from rigfem.errors import ClosureError
from rigfem.linkage.dims import Drive, Lengths, Options
from rigfem.linkage.general import move
from rigfem.linkage.model import GROUND, Prismatic


@dataclass
class Motion:
    """Motion of a linkage at ``crank_deg``.

    ``links``: name -> {angle_deg, omega_rad_s, alpha_rad_s2} (n,); ``points``: name ->
    {position_mm, velocity_mm_s, acceleration_mm_s2} (n, 2); ``bars``: link name -> the
    point names it joins (for drawing); ``slider``: {position_mm, velocity_mm_s,
    acceleration_mm_s2} along the slide (n,) or None; ``transmission_deg`` (0..180) and
    ``mechanical_advantage`` (see :func:`fourbar_motion`, :func:`slider_crank_motion`) or None.
    """

    crank_deg: np.ndarray
    omega_rad_s: float
    alpha_rad_s2: float
    links: dict[str, dict[str, np.ndarray]]
    points: dict[str, dict[str, np.ndarray]]
    bars: dict[str, list[str]]
    transmission_deg: np.ndarray | None = None
    mechanical_advantage: np.ndarray | None = None
    slider: dict[str, np.ndarray] | None = None
    meta: dict = field(default_factory=dict)


def _e(th: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(th), np.sin(th)], -1)


def _eperp(th: np.ndarray) -> np.ndarray:
    return np.stack([-np.sin(th), np.cos(th)], -1)


def _point(pos, vel, acc) -> dict[str, np.ndarray]:
    return {"position_mm": pos, "velocity_mm_s": vel, "acceleration_mm_s2": acc}


def _link(th, w, a) -> dict[str, np.ndarray]:
    n = np.shape(th)
    return {"angle_deg": np.degrees(th), "omega_rad_s": np.broadcast_to(w, n).astype(float),
            "alpha_rad_s2": np.broadcast_to(a, n).astype(float)}


def _ranges_text(ok: np.ndarray, deg: np.ndarray) -> str:
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return "none"
    cuts = np.flatnonzero(np.diff(idx) > 1)
    starts, ends = np.r_[idx[0], idx[cuts + 1]], np.r_[idx[cuts], idx[-1]]
    return ", ".join(f"{deg[a]:.1f} to {deg[b]:.1f} deg" for a, b in zip(starts, ends))


# ----------------------------------------------------------------------------- four-bar
def fourbar_motion(b2: float, b3: float, b4: float, d: float, crank_deg, omega: float = 2 * np.pi,
                   alpha: float = 0.0, branch: str = "open",
                   coupler_point: tuple[float, float] | None = None) -> Motion:
    """Four-bar O2-A-B-O4 (crank b2, coupler b3, rocker b4, ground d; mm) at ``crank_deg``.

    Mechanical advantage = omega2 / omega4: the output torque over the input torque of an
    ideal (massless, frictionless) linkage; it grows without bound at the rocker's limit
    positions.  ``coupler_point`` (distance mm from A, angle deg from the coupler line A->B)
    adds point ``P``.  ClosureError (an InputError) if the loop cannot close at some of the angles.
    """
    Lengths({"b2": b2, "b3": b3, "b4": b4, "d": d}, lo=0.0, hi=1e5)
    drive, _ = Drive(omega, alpha), Options(branch)
    w2, a2 = drive.omega, drive.alpha
    deg = np.atleast_1d(np.asarray(crank_deg, float))
    th2 = np.radians(deg)
    k = fourbar_angles(b2, b3, b4, d, th2, w2, a2, BRANCHES[branch])
    th3, th4, w3, w4, a3, a4 = (k[n] for n in ("theta3", "theta4", "omega3", "omega4", "alpha3", "alpha4"))
    bad = np.isnan(th3)
    if bad.any():
        grid = np.arange(0.0, 360.0, 0.1)
        raise ClosureError(f"four-bar b2={b2:g} b3={b3:g} b4={b4:g} d={d:g} mm cannot be assembled at crank "
                         f"{deg[bad][0]:g} deg; it closes for crank angles "
                         f"{_ranges_text(fourbar_closes(b2, b3, b4, d, grid), grid)}")
    zero = np.zeros((deg.size, 2))
    e2, n2, e4, n4 = _e(th2), _eperp(th2), _e(th4), _eperp(th4)
    A = b2 * e2
    vA = (b2 * w2) * n2
    aA = (b2 * a2) * n2 - (b2 * w2**2) * e2
    O4 = np.zeros((deg.size, 2))
    O4[:, 0] = d
    B = O4 + b4 * e4
    vB = (b4 * w4)[:, None] * n4
    aB = (b4 * a4)[:, None] * n4 - (b4 * w4**2)[:, None] * e4
    points = {"O2": _point(zero, zero, zero), "A": _point(A, vA, aA), "B": _point(B, vB, aB),
              "O4": _point(O4, zero, zero)}
    bars = {"crank": ["O2", "A"], "coupler": ["A", "B"], "rocker": ["O4", "B"], "ground": ["O2", "O4"]}
    if coupler_point is not None:
        p, gam = coupler_point
        th = th3 + np.radians(gam)
        points["P"] = _point(A + p * _e(th), vA + (p * w3)[:, None] * _eperp(th),
                             aA + p * (a3[:, None] * _eperp(th) - (w3**2)[:, None] * _e(th)))
        bars["coupler"] = ["A", "P", "B", "A"]
    with np.errstate(divide="ignore"):
        ma = np.abs(w2 / w4)
    return Motion(deg, w2, a2, {"crank": _link(th2, w2, a2), "coupler": _link(th3, w3, a3),
                                "rocker": _link(th4, w4, a4)},
                  points, bars, transmission_angle_deg(th3, th4), ma,
                  meta=dict(type="four-bar", lengths_mm=dict(b2=b2, b3=b3, b4=b4, d=d), branch=branch,
                            mechanical_advantage="omega2/omega4 (output torque / input torque, ideal)"))


def _wrap180(x: np.ndarray | float) -> np.ndarray | float:
    return (np.asarray(x) + 180.0) % 360.0 - 180.0


def grashof_class(b2: float, b3: float, b4: float, d: float) -> str:
    """Grashof class with the crank b2 as input: crank-rocker, double-crank, rocker-crank,
    double-rocker (Grashof, coupler shortest), change-point or triple-rocker (non-Grashof)."""
    lengths = {"crank": b2, "coupler": b3, "rocker": b4, "ground": d}
    s, l = min(lengths.values()), max(lengths.values())
    pq = sum(lengths.values()) - s - l
    tol = 1e-9 * l
    if abs(s + l - pq) <= tol:
        return "change-point"
    if s + l > pq:
        return "triple-rocker"
    shortest = min(lengths, key=lengths.get)
    return {"crank": "crank-rocker", "ground": "double-crank", "rocker": "rocker-crank",
            "coupler": "double-rocker"}[shortest]


def fourbar_turn(b2: float, b3: float, b4: float, d: float, branch: str = "open") -> dict:
    """What the four-bar does over a crank turn (angles in deg, exact, from closed forms).

    ``dead_points_deg``: crank angles where coupler and rocker are collinear (mu = 0 or 180;
    the crank cannot drive past them; they bound ``crank_range_deg``), except the
    ``change_points_deg`` of a change-point four-bar (Grashof's equality): there every link lies
    in line, the crank passes and the linkage may leave on either branch; rigfem follows the
    smooth one (:func:`rigfem.linkage.loops.fourbar_angles`), on which a linkage with one change
    point a turn comes back to its start after two turns (``turns_to_repeat``).  ``toggles``: crank
    and coupler collinear (``extended``/``folded``) — the rocker's limit positions (its
    angular velocity is zero; a rocker-driven linkage locks there).  ``rocker_swing_deg`` and
    ``time_ratio`` (the slower over the faster stroke at constant crank speed) follow when
    both toggles lie on the crank's path.
    """
    Lengths({"b2": b2, "b3": b3, "b4": b4, "d": d}, lo=0.0, hi=1e5)
    sgn = BRANCHES[Options(branch).branch]
    # the crank's diagonal is shortest at 0 and longest at 180 deg: the loop closes for every crank
    # angle (to fourbar_closes' rounding tolerance, as the motion's) where it closes at both
    change = change_points_deg(b2, b3, b4, d)
    closes = fourbar_closes(b2, b3, b4, d, np.array([0.0, 180.0]))
    full = bool(closes.all())
    dead = []
    for f, on, deg in ((b3 + b4, 180.0 in change and closes[1], 180.0),
                       (abs(b3 - b4), 0.0 in change and closes[0], 0.0)):
        if on:  # a change point where the loop closes: its dead point, not a rounding error off it
            dead.append(deg)
            continue
        c = (b2**2 + d**2 - f**2) / (2 * b2 * d)
        if abs(c) <= 1.0:
            a = float(np.degrees(np.arccos(c)))
            dead += sorted({a % 360.0, -a % 360.0})
    toggles = []
    for kind, r in (("extended", b2 + b3), ("folded", abs(b3 - b2))):
        c = (r**2 + d**2 - b4**2) / (2 * r * d) if r > 0 else 2.0
        if abs(c) > 1.0:
            continue
        for phi in (np.arccos(c), -np.arccos(c)):   # direction of O2B
            th2 = phi if kind == "extended" else phi + (np.pi if b3 > b2 else 0.0)
            deg = float(np.degrees(th2) % 360.0)
            if not fourbar_closes(b2, b3, b4, d, np.array([deg]))[0]:
                continue
            k = fourbar_angles(b2, b3, b4, d, np.array([th2]), 1.0, 0.0, sgn)
            rel = k["theta3"][0] - th2
            tg = dict(kind=kind, crank_deg=deg, rocker_deg=float(np.degrees(k["theta4"][0]) % 360.0))
            if abs(np.sin(rel)) < 1e-6 and (np.cos(rel) > 0) == (kind == "extended") and tg not in toggles:
                toggles.append(tg)
    out = dict(grashof=grashof_class(b2, b3, b4, d), branch=branch, crank_turns_fully=full,
               dead_points_deg=dead, crank_range_deg=None if full else _crank_range(b2, b3, b4, d, dead),
               toggles=toggles, rocker_limits_deg=None, rocker_swing_deg=None, time_ratio=None,
               change_points_deg=change, turns_to_repeat=2 if full and len(change) == 1 else 1)
    ext = [t for t in toggles if t["kind"] == "extended"]
    fol = [t for t in toggles if t["kind"] == "folded"]
    if full and len(ext) == 1 and len(fol) == 1:
        e, f = ext[0], fol[0]
        out["rocker_limits_deg"] = sorted([e["rocker_deg"], f["rocker_deg"]])
        out["rocker_swing_deg"] = float(abs(_wrap180(e["rocker_deg"] - f["rocker_deg"])))
        out.update(_strokes(e["crank_deg"], f["crank_deg"]))
    return out


def _crank_range(b2, b3, b4, d, dead: list[float]) -> list[float] | None:
    """The crank-angle interval [start, end] (deg, counter-clockwise) where the loop closes."""
    if len(dead) < 2:
        return None
    a, b = dead[0], dead[-1] if len(dead) == 2 else dead[1]
    mid = (a + b) / 2
    if fourbar_closes(b2, b3, b4, d, np.array([mid]))[0]:
        return [a, b]
    return [b, a + 360.0]


def _arcs(dead: list[float], closes) -> list[list[float]]:
    """The crank-angle arcs [start, end] (deg, counter-clockwise; end may pass 360) between
    consecutive dead points over which the loop closes (``closes(deg)`` at the arc's middle)."""
    d = sorted({x % 360.0 for x in dead})
    return [[a, b] for a, b in zip(d, d[1:] + d[:1]) for b in [b + 360.0 * (b <= a)] if closes((a + b) / 2)]


def _strokes(start_deg: float, end_deg: float) -> dict:
    """Crank angles of the two strokes between limit positions and their ratio (>= 1)."""
    fwd = (end_deg - start_deg) % 360.0
    ret = 360.0 - fwd
    return dict(stroke_crank_deg=[fwd, ret], time_ratio=max(fwd, ret) / min(fwd, ret))


# ----------------------------------------------------------------------------- slider-crank
def slider_crank_motion(b2: float, b3: float, offset: float = 0.0, crank_deg=0.0, omega: float = 2 * np.pi,
                        alpha: float = 0.0) -> Motion:
    """Slider-crank O2-A-B, slider B on y = ``offset`` (mm) on the +x side, at ``crank_deg``.

    Mechanical advantage = b2·omega2 / v_B: the slider force over the tangential force at
    the crank pin of an ideal linkage (dimensionless; unbounded at the dead centres).
    """
    Lengths({"b2": b2, "b3": b3}, lo=0.0, hi=1e5, signed={"offset": offset})
    drive = Drive(omega, alpha)
    w2, a2 = drive.omega, drive.alpha
    deg = np.atleast_1d(np.asarray(crank_deg, float))
    th2 = np.radians(deg)
    s3 = (offset - b2 * np.sin(th2)) / b3
    if np.any(np.abs(s3) > 1.0):
        grid = np.arange(0.0, 360.0, 0.1)
        ok = np.abs(offset - b2 * np.sin(np.radians(grid))) <= b3
        raise ClosureError(f"slider-crank b2={b2:g} b3={b3:g} offset={offset:g} mm cannot be assembled at "
                         f"crank {deg[np.abs(s3) > 1][0]:g} deg; it closes for crank angles {_ranges_text(ok, grid)}")
    k = slider_crank_angles(b2, b3, offset, th2, w2, a2)
    th3, w3, a3, x, v, acc = (k[n] for n in ("theta3", "omega3", "alpha3", "x", "v", "acc"))
    zero = np.zeros((deg.size, 2))
    A = b2 * _e(th2)
    vA = b2 * w2 * _eperp(th2)
    aA = b2 * (a2 * _eperp(th2) - w2**2 * _e(th2))

    def on_line(u):
        return np.stack([u, np.zeros_like(u)], -1)

    B = np.stack([x, np.full_like(x, offset)], -1)
    with np.errstate(divide="ignore", over="ignore"):  # a dead point (v = 0, or denormal): infinite
        ma = np.abs(b2 * w2 / v)
    return Motion(deg, w2, a2, {"crank": _link(th2, w2, a2), "rod": _link(th3, w3, a3)},
                  {"O2": _point(zero, zero, zero), "A": _point(A, vA, aA), "B": _point(B, on_line(v), on_line(acc))},
                  {"crank": ["O2", "A"], "rod": ["A", "B"]},
                  # rod against the slide's normal: 90 deg is ideal, 0/180 the rod across the slide
                  90.0 - np.degrees(th3), ma,
                  slider={"position_mm": x, "velocity_mm_s": v, "acceleration_mm_s2": acc},
                  meta=dict(type="slider-crank", lengths_mm=dict(b2=b2, b3=b3, offset=offset), branch="open",
                            mechanical_advantage="b2*omega2/v_slider (slider force / crank-pin force, ideal)",
                            transmission_angle="90 deg - rod angle (angle between rod and slide normal)"))


def slider_crank_turn(b2: float, b3: float, offset: float = 0.0) -> dict:
    """Limit positions (dead centres, crank and rod collinear), stroke and time ratio of a
    slider-crank (mm, deg; exact).  If b2 + |offset| >= b3 the crank cannot turn fully:
    ``dead_points_deg`` are then the crank angles with the rod across the slide."""
    Lengths({"b2": b2, "b3": b3}, lo=0.0, hi=1e5)
    full = b2 + abs(offset) < b3
    dead = []
    for yb in (offset - b3, offset + b3):
        s = yb / b2
        if abs(s) <= 1.0:
            a = float(np.degrees(np.arcsin(s)))
            dead += sorted({a % 360.0, (180.0 - a) % 360.0})
    arcs = [] if full else _arcs(dead, lambda deg: abs(offset - b2 * np.sin(np.radians(deg))) <= b3)
    out = dict(branch="open", crank_turns_fully=bool(full), dead_points_deg=dead, limits=[], stroke_mm=None,
               stroke_crank_deg=None, time_ratio=None, crank_range_deg=arcs[0] if arcs else None,
               crank_ranges_deg=arcs)
    if full:
        xo, xi = np.sqrt((b3 + b2) ** 2 - offset**2), np.sqrt((b3 - b2) ** 2 - offset**2)
        outer = float(np.degrees(np.arctan2(offset, xo)) % 360.0)
        inner = float((np.degrees(np.arctan2(offset, xi)) + 180.0) % 360.0)
        out["limits"] = [dict(kind="outer dead centre (extended)", crank_deg=outer, slider_mm=float(xo)),
                         dict(kind="inner dead centre (folded)", crank_deg=inner, slider_mm=float(xi))]
        out["stroke_mm"] = float(xo - xi)
        out.update(_strokes(outer, inner))
    return out


# ----------------------------------------------------------------------------- general solver
def _body_point(b, loc) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration (mm, mm/s, mm/s²) of the point ``loc`` (local mm) of
    a body's motion record, with its arm from the origin (global mm)."""
    c, s = np.cos(b.angle_rad), np.sin(b.angle_rad)
    r = np.stack([c * loc[0] - s * loc[1], s * loc[0] + c * loc[1]], -1)
    rp = np.stack([-r[:, 1], r[:, 0]], -1)
    w, a = b.omega_rad_s[:, None], b.alpha_rad_s2[:, None]
    return b.origin_mm + r, b.origin_vel_mm_s + w * rp, b.origin_acc_mm_s2 + a * rp - w**2 * r


def _from_bodies(crank_deg, bodies: dict, joints, meta: dict, w2: float) -> Motion:
    """:class:`Motion` from every body's motion record (``rigfem.linkage.model.BodyHistory``):
    every body's angle and rates, every joint's point with velocity and acceleration (from the
    pose of the joint's second body)."""
    links, points, bars = {}, {}, {}
    for name, b in bodies.items():
        links[name] = _link(b.angle_rad, b.omega_rad_s, b.alpha_rad_s2)
    for j in joints:
        b = bodies[j.body_b]
        points[j.name] = _point(*_body_point(b, b.joint_local_mm[j.name]))
        for body in (j.body_a, j.body_b):
            if body != GROUND:
                bars.setdefault(body, [])
                if j.name not in bars[body]:
                    bars[body].append(j.name)
    slider = None
    for body in ("ram", "slider"):      # a body sliding along the ground's x axis
        if body in bodies and bodies[body].origin_vel_mm_s is not None:
            b = bodies[body]
            slider = {"position_mm": b.origin_mm[:, 0], "velocity_mm_s": b.origin_vel_mm_s[:, 0],
                      "acceleration_mm_s2": b.origin_acc_mm_s2[:, 0]}
            links.pop(body)
    return Motion(np.asarray(crank_deg, float), w2, 0.0, links, points, bars, slider=slider,
                  meta={k: v for k, v in meta.items() if k in ("type", "lengths_mm", "branch")})


def motion_from_history(h) -> Motion:
    """:class:`Motion` from a :class:`rigfem.dynamics.history.ReactionHistory` of the general
    solver (its bodies' motion records and its joints)."""
    return _from_bodies(h.crank_deg, h.bodies, h.joints.values(), h.meta, 2 * np.pi * float(h.meta.get("speed_hz", 1.0)))


def _along_link(lk, bodies: dict) -> dict[str, np.ndarray] | None:
    """Position, velocity and acceleration (mm, mm/s, mm/s²) of the block along the moving link
    it slides on: the first prismatic joint between two moving bodies, measured on the link's
    slide line from the link's point of it (the inverted slider-crank: from the foot of the arm,
    O4A when arm = 0).  None where every slide is on the ground."""
    j = next((j for j in lk.joints if isinstance(j, Prismatic) and GROUND not in (j.body_a, j.body_b)), None)
    if j is None:
        return None
    a, b = bodies[j.body_a], bodies[j.body_b]
    pa, va, aa = _body_point(a, np.asarray(j.local_a_mm, float))
    pb, vb, ab = _body_point(b, np.asarray(j.local_b_mm, float))
    ax = np.asarray(j.axis_a, float) / np.hypot(*j.axis_a)
    c, s = np.cos(a.angle_rad), np.sin(a.angle_rad)
    u = np.stack([c * ax[0] - s * ax[1], s * ax[0] + c * ax[1]], -1)
    n = np.stack([-u[:, 1], u[:, 0]], -1)
    w, al = a.omega_rad_s[:, None], a.alpha_rad_s2[:, None]
    d, vd, ad = pb - pa, vb - va, ab - aa
    # s = d·u, u' = w n, n' = -w u
    return {"position_mm": np.sum(d * u, 1), "velocity_mm_s": np.sum(vd * u + d * w * n, 1),
            "acceleration_mm_s2": np.sum(ad * u + 2 * vd * w * n + d * (al * n - w**2 * u), 1)}


def linkage_motion(lk, crank_deg, omega: float, alpha: float = 0.0) -> Motion:
    """Motion of a builder-made Linkage (``lk.meta`` gives type and lengths): the closed form
    for a four-bar or slider-crank, otherwise the general solver (constant speed only); a
    block sliding on a moving link (inverted slider-crank) gets its position along the link
    as ``slider``."""
    m, L = lk.meta, lk.meta.get("lengths_mm", {})
    Drive(omega, alpha, m.get("type"))
    if m.get("type") == "four-bar":
        cp = m.get("coupler_point")
        return fourbar_motion(L["b2"], L["b3"], L["b4"], L["d"], crank_deg, omega, alpha, m.get("branch", "open"),
                              None if cp is None else (cp["distance_mm"], cp["angle_deg"]))
    if m.get("type") == "slider-crank":
        return slider_crank_motion(L["b2"], L["b3"], L.get("offset", 0.0), crank_deg, omega, alpha)
    deg = np.atleast_1d(np.asarray(crank_deg, float))
    order = np.argsort(deg)
    bodies = move(lk, deg[order], omega / (2 * np.pi))
    mo = _from_bodies(deg[order], bodies, lk.joints, m, omega)
    if mo.slider is None:
        mo.slider = _along_link(lk, bodies)
        if mo.slider is not None:
            mo.meta["slider"] = "block along the link it slides on, from the link's slide point (mm)"
    inv = np.argsort(order)
    mo.crank_deg = deg
    for group in (*mo.links.values(), *mo.points.values(), mo.slider or {}):
        for k in group:
            group[k] = group[k][inv]
    return mo


def linkage_turn(lk) -> dict | None:
    """:func:`fourbar_turn` or :func:`slider_crank_turn` of a Linkage; None for other types."""
    m, L = lk.meta, lk.meta.get("lengths_mm", {})
    if m.get("type") == "four-bar":
        return fourbar_turn(L["b2"], L["b3"], L["b4"], L["d"], m.get("branch", "open"))
    if m.get("type") == "slider-crank":
        return slider_crank_turn(L["b2"], L["b3"], L.get("offset", 0.0))
    if m.get("type") == "inverted-slider-crank":
        return inverted_slider_crank_turn(L["d"], L["b2"], L["arm"])
    return None


def inverted_slider_crank_turn(d: float, b2: float, arm: float) -> dict | None:
    """Dead points and range of motion of an inverted slider-crank whose crank cannot turn fully
    (the crank pin comes nearer O4 than ``arm``: |A − O4|² = b2² + d² − 2·b2·d·cos θ < arm²);
    None if it turns fully (the general solver traces it; no closed form here)."""
    c = (b2 * b2 + d * d - arm * arm) / (2 * b2 * d)
    if c < -1.0 or c >= 1.0:
        return None if c >= 1.0 else dict(branch="open", crank_turns_fully=False, dead_points_deg=[], limits=[],
                                          stroke_mm=None, stroke_crank_deg=None, time_ratio=None,
                                          crank_range_deg=None, crank_ranges_deg=[])
    a = float(np.degrees(np.arccos(c)))
    arcs = _arcs([a, 360.0 - a], lambda deg: b2 * b2 + d * d - 2 * b2 * d * np.cos(np.radians(deg)) >= arm * arm)
    return dict(branch="open", crank_turns_fully=False, dead_points_deg=[a, 360.0 - a], limits=[], stroke_mm=None,
                stroke_crank_deg=None, time_ratio=None, crank_range_deg=arcs[0] if arcs else None,
                crank_ranges_deg=arcs)
