"""Part load cases: from a linkage's reaction history to unit loads and superposition weights.

Linear elasticity is linear, so every part is solved once per *unit* load and the stress at
any crank angle is ``σ(θ) = Σ_k c_k(θ) σ_k``.  A :class:`PartCase` holds the unit loads of one
part and the coefficient matrix ``coef`` (one row per crank angle, or per study case).

Bearing loads (a pin or screw pushing on the half of a hole, cosine pressure) are not linear
in the force *direction*, so a force that turns over the cycle is written as a non-negative
combination of the two neighbouring of ``n_dir`` fixed directions (:func:`direction_weights`):
the pressure then always lies on the side the force pushes.

Conventions (mm, N, N·mm, rad/s, mm/s²):

* A rail's frame is its mesh frame: x along the rail from its end, y across, z up; the
  linkage plane is x–y.  A coupling (plate + shaft) is screwed through two neighbouring
  holes; its joint lies midway between them.  A bar's pivot coupling uses holes 0 and 1, the
  joint at distance b from the pivot uses holes m, m+1 with m = round(b / pitch).
* ``original`` mode (2013 study): peak reaction × load factor at the far joint, split equally
  over the last two holes of the rail, in the rail's longitudinal/transverse directions; the
  rail is held by the two screws of its pivot coupling.
* ``cycle`` mode: at every crank angle the actual joint forces through the actual coupling
  holes, the driver torque as a screw couple, minus the inertia of the point masses lumped at
  each joint, plus the rail's own inertia as a body force; the bar is solved free.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigfem.errors import InputError

#: inertia unit cases: body force -ρ·(a0 + α ẑ×r − ω² r) split into its linear parts
INERTIA = ("a0x", "a0y", "alpha", "omega2")


@dataclass(frozen=True)
class UnitLoad:
    """One unit load on a part, in the part's frame.

    ``kind="bearing"``: 1 N pushed by a pin/screw on hole ``group`` along ``direction``.
    ``kind="torque"``: 1 N·mm about ``direction`` carried by hole ``group``.
    ``kind="inertia"``: body force of unit ``component`` (one of :data:`INERTIA`),
    density scaled so that the part's mass is ``PartCase.mass_kg``.
    """

    kind: str
    group: str | None = None
    direction: tuple[float, float, float] | None = None
    component: str | None = None


@dataclass
class PartCase:
    """One part instance to check: what to mesh, how it is held, its unit loads and weights."""

    name: str  #: instance name, e.g. "crank_rail", "plate_A"
    part: str  #: part definition name (geometry/)
    params: dict  #: part parameters, e.g. {"length": 700}
    supports: list[tuple[str, tuple[str, ...]]]  #: [("bolt", ("hole_00", "hole_01"))] or [("free", ())]
    loads: list[UnitLoad]
    coef: np.ndarray  #: (n_rows, n_loads) weights of the unit solutions
    rows: np.ndarray  #: crank angle (deg) of each row
    refine: tuple[str, ...]  #: groups that carry load (mesh refinement)
    mass_kg: float | None = None  #: target mass for inertia loads
    notes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.coef = np.atleast_2d(np.asarray(self.coef, dtype=float))
        if self.coef.shape != (len(self.rows), len(self.loads)):
            raise ValueError(f"{self.name}: coef shape {self.coef.shape} != "
                             f"({len(self.rows)}, {len(self.loads)})")
        if not np.all(np.isfinite(self.coef)):
            raise InputError(f"{self.name}: load coefficients contain NaN or infinity")


def direction_weights(v: np.ndarray, n_dir: int = 12) -> np.ndarray:
    """Non-negative weights (n, n_dir) with ``Σ_k w_k e_k = v`` on the two directions around v.

    ``e_k = (cos 2πk/n_dir, sin 2πk/n_dir)``; ``v`` has shape (n, 2).
    """
    v = np.atleast_2d(np.asarray(v, dtype=float))
    step = 2 * np.pi / n_dir
    ang = np.mod(np.arctan2(v[:, 1], v[:, 0]), 2 * np.pi)
    k0 = np.minimum(np.floor(ang / step).astype(int), n_dir - 1)
    k1 = (k0 + 1) % n_dir
    e0 = np.stack([np.cos(k0 * step), np.sin(k0 * step)], axis=1)
    e1 = np.stack([np.cos(k1 * step), np.sin(k1 * step)], axis=1)
    det = np.sin(step)
    a = (v[:, 0] * e1[:, 1] - v[:, 1] * e1[:, 0]) / det
    b = (e0[:, 0] * v[:, 1] - e0[:, 1] * v[:, 0]) / det
    w = np.zeros((v.shape[0], n_dir))
    rows = np.arange(v.shape[0])
    np.add.at(w, (rows, k0), np.maximum(a, 0.0))
    np.add.at(w, (rows, k1), np.maximum(b, 0.0))
    return w


def directions(n_dir: int) -> list[tuple[float, float, float]]:
    """The fixed in-plane unit directions used by :func:`direction_weights`."""
    t = 2 * np.pi * np.arange(n_dir) / n_dir
    return [(float(np.cos(a)), float(np.sin(a)), 0.0) for a in t]


def hole_name(i: int) -> str:
    """Physical-group name of a rail's i-th mounting hole (in x order)."""
    return f"hole_{i:02d}"


def coupling_holes(distance_mm: float, n_holes: int, pitch_mm: float, bar: str) -> tuple[int, int]:
    """Indices of the two holes of the coupling whose joint is ``distance_mm`` from the pivot."""
    m = int(round(distance_mm / pitch_mm))
    if m < 0 or m + 1 >= n_holes:
        raise InputError(f"{bar}: joint at {distance_mm:g} mm from the pivot needs holes {m} and "
                         f"{m + 1}, but the rail has holes 0..{n_holes - 1}; allowed "
                         f"0..{(n_holes - 2) * pitch_mm:g} mm")
    return m, m + 1


def rotate_into(vectors: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Components of global in-plane vectors (n, 2) in frames turned by ``angle`` (n,) rad."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * vectors[:, 0] + s * vectors[:, 1],
                     -s * vectors[:, 0] + c * vectors[:, 1]], axis=1)


def screw_forces(force: np.ndarray, torque_nmm: np.ndarray | None, pitch_mm: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Forces (n, 2) on the two screws of a coupling (first at -pitch/2, second at +pitch/2 in x).

    The force is shared equally; a torque about z is carried as a couple ±T/pitch along y.
    """
    half = 0.5 * np.asarray(force, dtype=float)
    if torque_nmm is None:
        return half, half.copy()
    couple = np.zeros_like(half)
    couple[:, 1] = np.asarray(torque_nmm, dtype=float) / pitch_mm
    return half - couple, half + couple


def bearing_cases(hole_forces: dict[str, np.ndarray], n_dir: int
                  ) -> tuple[list[UnitLoad], np.ndarray]:
    """Unit bearing loads on each hole in ``n_dir`` directions and their weights (n, holes·n_dir)."""
    loads, cols = [], []
    dirs = directions(n_dir)
    for group, f in hole_forces.items():
        loads += [UnitLoad("bearing", group, d) for d in dirs]
        cols.append(direction_weights(f, n_dir))
    return loads, np.hstack(cols)
