"""A planar one-degree-of-freedom linkage as data: bodies, revolute and prismatic joints, one
driver, the motion record of a body over a crank turn, and the whole linkage's motion at
given driver phases (:class:`LinkageState`: what the dynamics balances forces on, handed
over as plain arrays so the forces need no call back into the linkage).

Lengths in mm, angles in rad, masses in kg (a body's mass data is plain data here; the
forces it causes are :mod:`rigfem.dynamics`' business).  The general planar solver that
moves such a linkage is :mod:`rigfem.linkage.general`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from rigfem.errors import ClosureError, ComputeError  # noqa: F401  (ClosureError: rigfem.linkage names it here)
from rigfem.linkage.loops import is_full_turn, transmission_angle_deg

GROUND = "ground"


def rotate(phi: np.ndarray, s) -> np.ndarray:
    """R(phi) s for phi (n,), s (2,) -> (n, 2)."""
    c, sn = np.cos(phi), np.sin(phi)
    out = np.empty(np.shape(phi) + (2,))
    out[..., 0] = c * s[0] - sn * s[1]
    out[..., 1] = sn * s[0] + c * s[1]
    return out


def perp(v: np.ndarray) -> np.ndarray:
    """v turned by +90 degrees, (..., 2)."""
    out = np.empty(v.shape)
    out[..., 0] = -v[..., 1]
    out[..., 1] = v[..., 0]
    return out


class AssemblyError(ComputeError):
    """The solver cannot close the loop at some driver positions (message names the angle)."""


@dataclass
class BodyHistory:
    """Motion and mass data of one moving body (frame origin at its first joint, a bar's x
    axis towards its second joint).  ``mass_kg``/``com_local_mm``/``inertia_com_kg_mm2`` are the
    body's own (e.g. the guide rail); ``point_masses`` the particles it carries."""

    name: str
    angle_rad: np.ndarray
    omega_rad_s: np.ndarray
    alpha_rad_s2: np.ndarray
    origin_mm: np.ndarray
    origin_acc_mm_s2: np.ndarray
    mass_kg: float
    com_local_mm: np.ndarray
    inertia_com_kg_mm2: float
    point_masses: list[tuple[str, float, np.ndarray]] = field(default_factory=list)
    joint_local_mm: dict[str, np.ndarray] = field(default_factory=dict)
    #: velocity of the frame origin (mm/s); None where the source does not give it
    origin_vel_mm_s: np.ndarray | None = None


@dataclass
class Body:
    """A rigid body: own mass (kg), centre of mass and inertia about it (local frame, mm, kg·mm²).

    ``point_masses`` are particles (label, kg, local position mm) carried by the body,
    e.g. a carriage or plate lumped at a joint.
    """

    name: str
    mass_kg: float = 0.0
    com_local_mm: tuple[float, float] = (0.0, 0.0)
    inertia_com_kg_mm2: float = 0.0
    point_masses: list[tuple[str, float, tuple[float, float]]] = field(default_factory=list)

    def totals(self) -> tuple[float, np.ndarray, float]:
        """Mass (kg), centre of mass (local, m) and inertia about it (kg·m²) including particles."""
        m = self.mass_kg + sum(p[1] for p in self.point_masses)
        if m == 0.0:
            return 0.0, np.zeros(2), 0.0
        c0 = np.asarray(self.com_local_mm, float) / 1000
        pts = [(pm, np.asarray(pos, float) / 1000) for _, pm, pos in self.point_masses]
        c = (self.mass_kg * c0 + sum(pm * pos for pm, pos in pts)) / m
        inertia = self.inertia_com_kg_mm2 * 1e-6 + self.mass_kg * np.sum((c0 - c) ** 2)
        inertia += sum(pm * np.sum((pos - c) ** 2) for pm, pos in pts)
        return m, c, float(inertia)

    def history(self, phi, omega, alpha, origin_m, vel_m, acc_m) -> BodyHistory:
        """The body's :class:`BodyHistory` from its motion (SI in, mm out); joint points empty."""
        return BodyHistory(self.name, phi, omega, alpha, origin_m * 1000, acc_m * 1000, self.mass_kg,
                           np.asarray(self.com_local_mm, float), self.inertia_com_kg_mm2,
                           [(lab, pm, np.asarray(pos, float)) for lab, pm, pos in self.point_masses], {},
                           vel_m * 1000)


@dataclass
class Revolute:
    """Pin joint: point ``local_a_mm`` of body_a coincides with ``local_b_mm`` of body_b."""

    name: str
    body_a: str
    body_b: str
    local_a_mm: tuple[float, float]
    local_b_mm: tuple[float, float]


@dataclass
class Prismatic:
    """Slider: point ``local_b_mm`` of body_b moves on the line of body_a through
    ``local_a_mm`` with direction ``axis_a``; the relative angle phi_b - phi_a stays ``rel_angle_rad``."""

    name: str
    body_a: str
    body_b: str
    local_a_mm: tuple[float, float]
    axis_a: tuple[float, float]
    local_b_mm: tuple[float, float]
    rel_angle_rad: float = 0.0


@dataclass
class CrankDriver:
    """Constant-speed rotation of ``body`` relative to the ground: phi = theta + ``offset_rad``."""

    body: str
    offset_rad: float = 0.0


@dataclass
class SliderDriver:
    """Driven slider on prismatic ``joint``: s = mean + amplitude·sin(theta) (mm), theta = cycle phase."""

    joint: str
    mean_mm: float
    amplitude_mm: float


@dataclass
class Load:
    """External force on ``body`` at ``local_mm``: ``force(state) -> (n, 2)`` N, state in mm/rad."""

    body: str
    local_mm: tuple[float, float]
    force: Callable[[dict], np.ndarray]

@dataclass
class Linkage:
    """A one-DOF planar linkage.  ``guess`` gives each body's approximate pose (x mm, y mm,
    phi rad) at one driver phase (the crank body's guessed angle; phase 0 for a driven
    slider); it selects the assembly branch, which the solver then follows continuously."""

    bodies: list[Body]
    joints: list[Revolute | Prismatic]
    driver: CrankDriver | SliderDriver
    guess: dict[str, tuple[float, float, float]]
    loads: list[Load] = field(default_factory=list)
    gravity_mm_s2: tuple[float, float] = (0.0, 0.0)
    meta: dict = field(default_factory=dict)

    def record_joint_points(self, bodies: dict[str, BodyHistory]) -> None:
        """Each moving body's joint points (local mm), for the kinematics of its history."""
        for j in self.joints:
            for bn, loc in ((j.body_a, j.local_a_mm), (j.body_b, j.local_b_mm)):
                if bn != GROUND:
                    bodies[bn].joint_local_mm[j.name] = np.asarray(loc, float)


@dataclass
class BodyState:
    """One body's motion (n samples, SI) and mass totals (particles included)."""

    phi: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    origin: np.ndarray  #: frame origin (n, 2) m
    origin_vel: np.ndarray  #: (n, 2) m/s
    mass_kg: float
    inertia_kg_m2: float  #: about the centre of mass
    com: np.ndarray  #: centre of mass from the frame origin, world axes (n, 2) m
    com_acc: np.ndarray  #: acceleration of the centre of mass (n, 2) m/s²


@dataclass
class GeneralState:
    """What the general solver's inverse dynamics needs besides the bodies' motion: the
    coordinates' layout, the inverse constraint Jacobian and each joint's geometry."""

    n_coords: int
    index: dict[str, int]  #: body -> its block (x, y, phi) in the coordinates
    rows: list[int]  #: first constraint row of each joint (in ``lk.joints``' order)
    drow: int  #: the driver's constraint row
    Jinv: np.ndarray  #: (n, m, m)
    rcond: np.ndarray  #: reciprocal condition number of the scaled Jacobian (n,)
    #: joint -> (point on body_b (n, 2) m, its offset from body_b's origin, slide axis u, normal) (u, normal None
    #: for a revolute)
    frames: dict[str, tuple]
    warnings: list[str] = field(default_factory=list)


@dataclass
class LinkageState:
    """The motion of a linkage at driver phases ``theta`` (rad)."""

    theta: np.ndarray
    bodies: dict[str, BodyState]
    joints: dict[str, np.ndarray]  #: joint position (n, 2) m
    histories: dict[str, BodyHistory]  #: mm, joint points recorded
    load_arms: list[np.ndarray]  #: each of ``lk.loads``' points from its body's origin (n, 2) m
    q: np.ndarray | None  #: the general solver's coordinates (x, y, phi per body; None without loads)
    qd: np.ndarray | None
    kind: str = "general"  #: "four-bar" | "slider-crank" (closed forms) | "general"
    general: GeneralState | None = None
    #: the same branch's motion where the solver's continuation points are denser than ``theta`` (a toggle
    #: narrower than the sampling shows there), else None
    probe: LinkageState | None = None
    #: the motion at other phases (deg) on the same branch
    at: Callable[[np.ndarray], LinkageState | None] | None = None
    #: ``theta`` is an evenly spaced full turn (:func:`rigfem.linkage.loops.is_full_turn`)
    full_turn: bool = False
    #: a four-bar's transmission angle (deg) at ``theta`` (:func:`rigfem.linkage.loops.transmission_angle_deg`);
    #: None for another linkage
    mu_deg: np.ndarray | None = None


def state_of(lk: Linkage, theta: np.ndarray, motion: dict[str, tuple], joints: dict[str, np.ndarray] | None,
                  kind: str = "general", general: GeneralState | None = None,
                  q: np.ndarray | None = None, qd: np.ndarray | None = None) -> LinkageState:
    """Assemble a :class:`LinkageState` from every body's (phi, omega, alpha, origin, origin velocity,
    origin acceleration) in ``motion`` and the joints' positions (SI; None: each at its point on
    its ``body_b``); ``q``, ``qd`` the general solver's coordinates where it gave them."""
    bodies, hist = {}, {}
    for b in lk.bodies:
        phi, w, al, r, v, a = motion[b.name]
        m, c, inertia = b.totals()
        rc = rotate(phi, c)
        bodies[b.name] = BodyState(phi, w, al, r, v, m, inertia, rc,
                                   a + perp(rc) * al[:, None] - rc * (w**2)[:, None])
        hist[b.name] = b.history(phi, w, al, r, v, a)
    lk.record_joint_points(hist)
    if joints is None:
        joints = {j.name: bodies[j.body_b].origin + rotate(bodies[j.body_b].phi, np.asarray(j.local_b_mm, float) / 1000)
                  for j in lk.joints}
    arms = [rotate(bodies[ld.body].phi, np.asarray(ld.local_mm, float) / 1000) for ld in lk.loads]
    if lk.loads and q is None:  # the loads see the general solver's coordinates
        q = np.concatenate([np.column_stack([bodies[b.name].origin, bodies[b.name].phi]) for b in lk.bodies], 1)
        qd = np.concatenate([np.column_stack([bodies[b.name].origin_vel, bodies[b.name].omega])
                             for b in lk.bodies], 1)
    return LinkageState(theta, bodies, joints, hist, arms, q if lk.loads else None, qd if lk.loads else None,
                        kind, general, full_turn=is_full_turn(np.degrees(theta)),
                        mu_deg=(transmission_angle_deg(bodies["coupler"].phi, bodies["rocker"].phi)
                                if lk.meta.get("type") == "four-bar" else None))
