"""A linkage's whole motion at given driver phases, in one piece: what the dynamics balances
forces on, handed over as plain arrays so the forces need no call back into the linkage.

Every body's angle, rates, frame origin and its acceleration, its mass totals and its centre
of mass's path and acceleration; the joints' positions; each external load's point; and the
:class:`~rigfem.linkage.model.BodyHistory` records (joint points included) a reaction history
carries.  SI (m, rad, s, kg) like the dynamics; the histories in mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from rigfem.linkage.model import BodyHistory, Linkage, perp, rotate

__all__ = ["BodyState", "GeneralState", "LinkageState", "linkage_state"]


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


def linkage_state(lk: Linkage, theta: np.ndarray, motion: dict[str, tuple], joints: dict[str, np.ndarray],
                  kind: str = "general", general: GeneralState | None = None,
                  q: np.ndarray | None = None, qd: np.ndarray | None = None) -> LinkageState:
    """Assemble a :class:`LinkageState` from every body's (phi, omega, alpha, origin, origin velocity,
    origin acceleration) in ``motion`` and the joints' positions (SI); ``q``, ``qd`` the general
    solver's coordinates where it gave them."""
    bodies, hist = {}, {}
    for b in lk.bodies:
        phi, w, al, r, v, a = motion[b.name]
        m, c, inertia = b.totals()
        rc = rotate(phi, c)
        bodies[b.name] = BodyState(phi, w, al, r, v, m, inertia, rc,
                                   a + perp(rc) * al[:, None] - rc * (w**2)[:, None])
        hist[b.name] = b.history(phi, w, al, r, v, a)
    lk.record_joint_points(hist)
    arms = [rotate(bodies[ld.body].phi, np.asarray(ld.local_mm, float) / 1000) for ld in lk.loads]
    if lk.loads and q is None:  # the loads see the general solver's coordinates
        q = np.concatenate([np.column_stack([bodies[b.name].origin, bodies[b.name].phi]) for b in lk.bodies], 1)
        qd = np.concatenate([np.column_stack([bodies[b.name].origin_vel, bodies[b.name].omega])
                             for b in lk.bodies], 1)
    return LinkageState(theta, bodies, joints, hist, arms, q if lk.loads else None, qd if lk.loads else None,
                        kind, general)
