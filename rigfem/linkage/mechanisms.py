"""The catalogue of mechanisms: the rig's linkages built as data, with the rig's masses from one
catalogue.

Builders (lengths in mm, angles in degrees) return a :class:`rigfem.linkage.model.Linkage`:
``four_bar``, ``slider_crank``, ``inverted_slider_crank``, ``quick_return``; ``build`` makes
the one a scene names.  Their ``start_deg`` is the crank angle at which the initial assembly
(hence the branch) is computed; lengths below 10 mm are rejected as probable metres.

Mass data (geometry/RIG.md §3), ``masses="rig"``: every rail is a uniform bar of the catalogue's
linear mass over its full guide length L_i, reaching ``rail_behind_mm`` behind the bar's
first joint as the meshed rail does (centre of mass L_i/2 − rail_behind_mm from that joint,
I_G = m L_i²/12), carriages, plates and couplings as particles at their joints.  The forces
they cause are computed by :mod:`rigfem.dynamics`.
"""

from __future__ import annotations

import inspect

from dataclasses import asdict
from typing import Any

import numpy as np

from rigfem.linkage.loops import (
    BRANCHES,
    MU_TOGGLE_DEG,
    fourbar_angles,
    fourbar_closes,
    singular_ranges,
    transmission_angle_deg,
)
from rigfem.linkage.dims import Lengths, Options, Rails
from rigfem.linkage.model import GROUND, Body, BodyHistory, ClosureError, CrankDriver, Linkage, Load, Prismatic, Revolute
from rigfem.rig.catalogue import RIG_MASSES, RIG_RAILS_MM, RigMasses

__all__ = ["four_bar", "transmission_angle", "coupler_point_path", "slider_crank", "inverted_slider_crank",
           "quick_return", "BUILDERS", "build", "crank_angles"]


def _rail(name: str, length_mm: float, cat: RigMasses, points: list) -> Body:
    """A guide rail as a uniform bar along +x, ``rail_behind_mm`` of it behind its first joint
    (the frame origin)."""
    m = cat.rail_kg_m * length_mm / 1000
    return Body(name, m, (length_mm / 2 - cat.rail_behind_mm, 0.0), m * length_mm**2 / 12, points)


def _massless(name: str, overrides: dict | None) -> Body:
    kw = dict((overrides or {}).get(name, {}))
    pts = [(lab, float(pm), tuple(pos)) for lab, pm, pos in kw.pop("point_masses", [])]
    return Body(name, point_masses=pts, **kw)


def _ranges_text(deg: np.ndarray, bad: np.ndarray) -> str:
    rng = singular_ranges(deg, bad) or []
    return ", ".join(f"{a:.1f}-{b:.1f} deg" for a, b in rng)


# ----------------------------------------------------------------------------- four-bar
def four_bar(b2: float, b3: float, b4: float, d: float, *, masses: str | None = "rig",
             rails_mm: tuple[float, float, float] = RIG_RAILS_MM, branch: str = "open",
             coupler_point: tuple[float, float] | None = None, body_masses: dict | None = None,
             start_deg: float = 0.0, catalogue: RigMasses = RIG_MASSES,
             gravity_mm_s2: tuple[float, float] = (0.0, 0.0), whole_turn: bool = True) -> Linkage:
    """Four-bar O2-A-B-O4: crank b2, coupler b3, rocker b4, ground d (mm), O4 at (d, 0).

    Bodies ``crank`` (O2->A), ``coupler`` (A->B), ``rocker`` (O4->B); joints O2, A, B, O4.
    ``masses="rig"``: rails of ``rails_mm`` with plate+carriage at A on the crank, coupling
    at A and plate+carriage at B on the coupler, coupling at B on the rocker (geometry/RIG.md §3).
    ``masses=None``: massless unless ``body_masses`` (name -> Body keyword dict) says so.
    ``coupler_point`` (distance mm from A, angle deg from the coupler line) is recorded
    in meta and reported by :func:`coupler_point_path`.  Raises AssemblyError naming the
    crank-angle range where the loop cannot close, unless ``whole_turn`` is False (a kinematics
    run over the crank's range of motion): then it is built at an angle where it closes.
    """
    Lengths({"b2": b2, "b3": b3, "b4": b4, "d": d})
    Options(branch, masses)
    if masses == "rig":
        Rails(tuple(rails_mm), {"b2": b2, "b3": b3, "b4": b4}, catalogue.rail_behind_mm)
    grid = np.linspace(0.0, 360.0, 3601)
    ok = fourbar_closes(b2, b3, b4, d, grid)
    if not ok.all() and (whole_turn or not ok.any()):
        raise ClosureError(f"four-bar b2={b2:g} b3={b3:g} b4={b4:g} d={d:g} mm cannot be assembled "
                            f"for crank angles {_ranges_text(grid, ~ok)}")
    if not fourbar_closes(b2, b3, b4, d, np.array([start_deg]))[0]:
        start_deg = float(grid[np.flatnonzero(ok)[0]])
    th = np.radians(start_deg)
    k = fourbar_angles(b2, b3, b4, d, np.array([th]), 1.0, 0.0, BRANCHES[branch])
    A, th3, th4 = b2 * np.array([np.cos(th), np.sin(th)]), k["theta3"][0], k["theta4"][0]
    if masses == "rig":
        c = catalogue
        L2, L3, L4 = rails_mm
        bodies = [_rail("crank", L2, c, [("A", c.plate + c.carriage, (b2, 0.0))]),
                  _rail("coupler", L3, c, [("A", c.coupling, (0.0, 0.0)),
                                           ("B", c.plate + c.carriage, (b3, 0.0))]),
                  _rail("rocker", L4, c, [("B", c.coupling, (b4, 0.0))])]
    else:  # None (Options)
        bodies = [_massless(n, body_masses) for n in ("crank", "coupler", "rocker")]
    joints = [Revolute("O2", GROUND, "crank", (0.0, 0.0), (0.0, 0.0)),
              Revolute("A", "crank", "coupler", (b2, 0.0), (0.0, 0.0)),
              Revolute("B", "coupler", "rocker", (b3, 0.0), (b4, 0.0)),
              Revolute("O4", GROUND, "rocker", (d, 0.0), (0.0, 0.0))]
    guess = {"crank": (0.0, 0.0, np.radians(start_deg)), "coupler": (A[0], A[1], th3),
             "rocker": (d, 0.0, th4)}

    def toggle(deg, bodies_h):
        mu = transmission_angle(bodies_h)
        return np.sin(np.radians(mu)) < np.sin(np.radians(MU_TOGGLE_DEG))

    meta = dict(type="four-bar", lengths_mm=dict(b2=b2, b3=b3, b4=b4, d=d), branch=branch,
                rails_mm=list(rails_mm), masses=masses or "custom", singular_fn=toggle,
                catalogue=asdict(catalogue))
    if coupler_point is not None:
        meta["coupler_point"] = dict(distance_mm=coupler_point[0], angle_deg=coupler_point[1])
    return Linkage(bodies, joints, CrankDriver("crank"), guess, gravity_mm_s2=gravity_mm_s2, meta=meta)


def transmission_angle(bodies: dict[str, BodyHistory]) -> np.ndarray:
    """Four-bar transmission angle mu (deg, 0..180): the interior coupler–rocker angle at B."""
    return transmission_angle_deg(bodies["coupler"].angle_rad, bodies["rocker"].angle_rad)


def coupler_point_path(h) -> np.ndarray:
    """Global position (mm) of the four-bar coupler point recorded in ``h.meta`` (n, 2), from a
    history's coupler motion (``h.bodies["coupler"]``)."""
    cp = h.meta["coupler_point"]
    c = h.bodies["coupler"]
    ang = c.angle_rad + np.radians(cp["angle_deg"])
    return c.origin_mm + cp["distance_mm"] * np.stack([np.cos(ang), np.sin(ang)], -1)


# ----------------------------------------------------------------------------- slider-crank
def slider_crank(b2: float, b3: float, offset: float = 0.0, *, masses: str | None = "rig",
                 rails_mm: tuple[float, float] = RIG_RAILS_MM[:2], body_masses: dict | None = None,
                 slider_force: Any = None, start_deg: float = 0.0, catalogue: RigMasses = RIG_MASSES,
                 gravity_mm_s2: tuple[float, float] = (0.0, 0.0), whole_turn: bool = True) -> Linkage:
    """Slider-crank: crank b2 (O2->A), rod b3 (A->B), slider B on the line y = ``offset`` (mm), +x side.

    Bodies ``crank``, ``rod``, ``slider``; joints O2, A, B (revolute) and ``slide``
    (prismatic, ground -> slider).  Rig masses (an assumption, the study never analysed
    this case): crank rail with plate+carriage at A; rod rail with coupling at A and a
    plate at B; the slider is a carriage on the ground rail plus a coupling.
    ``slider_force(state) -> (n, 2)`` N is an external force on the slider (e.g. gas).  Raises
    ClosureError naming the crank-angle range where the rod cannot reach the slide line, unless
    ``whole_turn`` is False (a kinematics run over the crank's range of motion): then it is built
    at an angle where it closes.
    """
    Lengths({"b2": b2, "b3": b3}, signed={"offset": offset})
    Options(masses=masses)
    if masses == "rig":
        Rails(tuple(rails_mm), {"b2": b2, "b3": b3}, catalogue.rail_behind_mm)
    grid = np.linspace(0.0, 360.0, 3601)
    ok = np.abs(offset - b2 * np.sin(np.radians(grid))) <= b3
    if not ok.all() and (whole_turn or not ok.any()):
        raise ClosureError(f"slider-crank b2={b2:g} b3={b3:g} offset={offset:g} mm cannot be assembled "
                            f"for crank angles {_ranges_text(grid, ~ok)}")
    if not abs(offset - b2 * np.sin(np.radians(start_deg))) <= b3:
        start_deg = float(grid[np.flatnonzero(ok)[0]])
    th = np.radians(start_deg)
    ax, ay = b2 * np.cos(th), b2 * np.sin(th)
    bx = ax + np.sqrt(b3**2 - (offset - ay) ** 2)
    if masses == "rig":
        c = catalogue
        bodies = [_rail("crank", rails_mm[0], c, [("A", c.plate + c.carriage, (b2, 0.0))]),
                  _rail("rod", rails_mm[1], c, [("A", c.coupling, (0.0, 0.0)), ("B", c.plate, (b3, 0.0))]),
                  Body("slider", 0.0, (0.0, 0.0), 0.0, [("B", c.carriage + c.coupling, (0.0, 0.0))])]
    else:  # None (Options)
        bodies = [_massless(n, body_masses) for n in ("crank", "rod", "slider")]
    joints = [Revolute("O2", GROUND, "crank", (0.0, 0.0), (0.0, 0.0)),
              Revolute("A", "crank", "rod", (b2, 0.0), (0.0, 0.0)),
              Revolute("B", "rod", "slider", (b3, 0.0), (0.0, 0.0)),
              Prismatic("slide", GROUND, "slider", (0.0, offset), (1.0, 0.0), (0.0, 0.0))]
    guess = {"crank": (0.0, 0.0, th), "rod": (ax, ay, np.arctan2(offset - ay, bx - ax)),
             "slider": (bx, offset, 0.0)}
    loads = [Load("slider", (0.0, 0.0), slider_force)] if slider_force is not None else []

    def toggle(deg, bodies_h):
        # rod within MU_TOGGLE_DEG of perpendicular to the slide: the crank cannot drive the slider
        return np.abs(np.cos(bodies_h["rod"].angle_rad)) < np.sin(np.radians(MU_TOGGLE_DEG))

    meta = dict(type="slider-crank", lengths_mm=dict(b2=b2, b3=b3, offset=offset),
                rails_mm=list(rails_mm), masses=masses or "custom", singular_fn=toggle)
    return Linkage(bodies, joints, CrankDriver("crank"), guess, loads, gravity_mm_s2, meta)


# ----------------------------------------------------------------------------- inverted slider-crank
def inverted_slider_crank(d: float, b2: float, arm: float, *, masses: str | None = "rig",
                          rails_mm: tuple[float, float] = (RIG_RAILS_MM[0], RIG_RAILS_MM[2]),
                          body_masses: dict | None = None, start_deg: float = 0.0,
                          catalogue: RigMasses = RIG_MASSES, whole_turn: bool = True) -> Linkage:
    """Inverted slider-crank: crank b2 at O2 = (0, 0); link 4 pivoted at O4 = (d, 0) carries a
    slide line at distance ``arm`` from O4, perpendicular to the arm; block 3 pinned at the
    crank pin A slides on it.  Bodies ``crank``, ``block``, ``rocker`` (frame x along the arm,
    the slide line through (arm, 0) along local +y); joints O2, A, slide, O4.

    Rig masses (assumption): crank rail with a plate at A; the block is a carriage with a
    coupling; link 4 is a rail of length rails_mm[1] along the slide line, centred at the foot
    of the arm, plus a plate at O4.  ``whole_turn`` False: built at an angle where it closes
    even if the crank cannot turn fully (as :func:`four_bar`).
    """
    Lengths({"d": d, "b2": b2}, arm={"arm": arm})
    Options(masses=masses)
    grid = np.linspace(0.0, 360.0, 3601)
    f = np.sqrt(b2**2 + d**2 - 2 * b2 * d * np.cos(np.radians(grid)))
    ok = f >= arm
    if not ok.all() and (whole_turn or not ok.any()):
        raise ClosureError(f"inverted slider-crank d={d:g} b2={b2:g} arm={arm:g} mm cannot be assembled "
                            f"for crank angles {_ranges_text(grid, ~ok)}")
    if not np.hypot(b2 * np.cos(np.radians(start_deg)) - d, b2 * np.sin(np.radians(start_deg))) >= arm:
        start_deg = float(grid[np.flatnonzero(ok)[0]])
    th = np.radians(start_deg)
    A = np.array([b2 * np.cos(th), b2 * np.sin(th)])
    D = A - np.array([d, 0.0])
    phi4 = np.arctan2(D[1], D[0]) - np.arccos(arm / np.hypot(*D))
    if masses == "rig":
        c = catalogue
        m4 = c.rail_kg_m * rails_mm[1] / 1000
        bodies = [_rail("crank", rails_mm[0], c, [("A", c.plate, (b2, 0.0))]),
                  Body("block", 0.0, (0.0, 0.0), 0.0, [("A", c.carriage + c.coupling, (0.0, 0.0))]),
                  Body("rocker", m4, (arm, 0.0), m4 * rails_mm[1] ** 2 / 12, [("O4", c.plate, (0.0, 0.0))])]
    else:  # None (Options)
        bodies = [_massless(n, body_masses) for n in ("crank", "block", "rocker")]
    joints = [Revolute("O2", GROUND, "crank", (0.0, 0.0), (0.0, 0.0)),
              Revolute("A", "crank", "block", (b2, 0.0), (0.0, 0.0)),
              Prismatic("slide", "rocker", "block", (arm, 0.0), (0.0, 1.0), (0.0, 0.0), 0.0),
              Revolute("O4", GROUND, "rocker", (d, 0.0), (0.0, 0.0))]
    guess = {"crank": (0.0, 0.0, th), "block": (A[0], A[1], phi4), "rocker": (d, 0.0, phi4)}
    meta = dict(type="inverted-slider-crank", lengths_mm=dict(d=d, b2=b2, arm=arm), masses=masses or "custom")
    return Linkage(bodies, joints, CrankDriver("crank"), guess, meta=meta)


# ----------------------------------------------------------------------------- quick-return
def quick_return(b2: float, pivot_below: float, ram_height: float, *, masses: str | None = "rig",
                 rails_mm: tuple[float, float] = (RIG_RAILS_MM[0], RIG_RAILS_MM[2]),
                 body_masses: dict | None = None, start_deg: float = 0.0,
                 catalogue: RigMasses = RIG_MASSES) -> Linkage:
    """Whitworth/shaper quick-return: crank b2 at O2 = (0, 0); slotted rocker pivoted at
    O4 = (0, -pivot_below); block 3 on the crank pin slides in the rocker; the ram slides on
    the horizontal line ``ram_height`` above O4 and its pin C slides in the rocker slot (block 5).

    Bodies ``crank``, ``block``, ``rocker`` (frame x along the slot), ``ram_block``, ``ram``
    (frame origin at C); joints O2, A, slot, O4, slot_C, C, ram_slide.  Needs pivot_below > b2.
    Rig masses (assumption): crank rail + plate at A; carriage + coupling as each block;
    rocker rail of length rails_mm[1] from O4; the ram a carriage + plate.
    """
    Lengths({"b2": b2, "pivot_below": pivot_below, "ram_height": ram_height})
    Options(masses=masses)
    if pivot_below <= b2:
        raise ClosureError(f"quick-return: pivot_below = {pivot_below:g} mm must exceed the crank "
                            f"b2 = {b2:g} mm or the crank pin reaches the rocker pivot (0-360 deg)")
    if ram_height <= pivot_below + b2:
        raise ClosureError(f"ram_height = {ram_height:g} mm must exceed pivot_below + b2 = "
                           f"{pivot_below + b2:g} mm or the rocker cannot reach the ram")
    th = np.radians(start_deg)
    A = np.array([b2 * np.cos(th), b2 * np.sin(th)])
    O4 = np.array([0.0, -pivot_below])
    phi = np.arctan2(*(A - O4)[::-1])
    yc = ram_height - pivot_below
    xc = ram_height / np.tan(phi)
    if masses == "rig":
        c = catalogue
        bodies = [_rail("crank", rails_mm[0], c, [("A", c.plate, (b2, 0.0))]),
                  Body("block", point_masses=[("A", c.carriage + c.coupling, (0.0, 0.0))]),
                  _rail("rocker", rails_mm[1], c, [("O4", c.plate, (0.0, 0.0))]),
                  Body("ram_block", point_masses=[("C", c.carriage + c.coupling, (0.0, 0.0))]),
                  Body("ram", point_masses=[("C", c.carriage + c.plate, (0.0, 0.0))])]
    else:  # None (Options)
        bodies = [_massless(n, body_masses) for n in ("crank", "block", "rocker", "ram_block", "ram")]
    joints = [Revolute("O2", GROUND, "crank", (0.0, 0.0), (0.0, 0.0)),
              Revolute("A", "crank", "block", (b2, 0.0), (0.0, 0.0)),
              Prismatic("slot", "rocker", "block", (0.0, 0.0), (1.0, 0.0), (0.0, 0.0), 0.0),
              Revolute("O4", GROUND, "rocker", (0.0, -pivot_below), (0.0, 0.0)),
              Prismatic("slot_C", "rocker", "ram_block", (0.0, 0.0), (1.0, 0.0), (0.0, 0.0), 0.0),
              Revolute("C", "ram_block", "ram", (0.0, 0.0), (0.0, 0.0)),
              Prismatic("ram_slide", GROUND, "ram", (0.0, yc), (1.0, 0.0), (0.0, 0.0), 0.0)]
    guess = {"crank": (0.0, 0.0, th), "block": (A[0], A[1], phi), "rocker": (O4[0], O4[1], phi),
             "ram_block": (xc, yc, phi), "ram": (xc, yc, 0.0)}
    meta = dict(type="quick-return", lengths_mm=dict(b2=b2, pivot_below=pivot_below, ram_height=ram_height),
                masses=masses or "custom")
    return Linkage(bodies, joints, CrankDriver("crank"), guess, meta=meta)


# ----------------------------------------------------------------------------- simulate
BUILDERS = {"four-bar": four_bar, "slider-crank": slider_crank,
            "inverted-slider-crank": inverted_slider_crank, "quick-return": quick_return}


def build(scene, slider_force: Any = None, whole_turn: bool = True) -> Linkage:
    """The linkage a scene (:class:`rigfem.scene.Scene`: type, builder arguments) describes:
    geometry, driver and masses; ``slider_force`` an external force on a slider-crank's slider;
    ``whole_turn`` False: a linkage whose crank cannot turn fully is built where it closes."""
    kwargs = dict(scene.params)
    if slider_force is not None:
        kwargs["slider_force"] = slider_force
    if not whole_turn and "whole_turn" in inspect.signature(BUILDERS[scene.linkage_type]).parameters:
        kwargs["whole_turn"] = False
    lk = BUILDERS[scene.linkage_type](**kwargs)
    lk.meta["scene"] = scene.name
    lk.meta["textbook"] = scene.textbook
    return lk


def crank_angles(samples: int, start_deg: float = 0.0) -> np.ndarray:
    """``samples`` evenly spaced crank angles over one turn (deg), 360 excluded."""
    return start_deg + 360.0 * np.arange(samples) / samples
